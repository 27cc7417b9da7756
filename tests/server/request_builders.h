// Requests the server tests share: a trajectory, an audit, a FitInertia
// stream. Each builds the message from the libraries' own examples and
// simulations (seeded), so the same call gives the same request.
#pragma once

#include <cstdint>

#include <grpcpp/grpcpp.h>

#include "tactforce/inertia/samples.h"
#include "tactforce/sim/sensor_model.h"
#include "tactforce/v1/audit.pb.h"
#include "tactforce/v1/estimator.grpc.pb.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::testing {

// planner::WrenchLiftAndRotate(steps) as a geometric TrajectoryRequest.
v1::TrajectoryRequest LiftRequest(int steps);

// EstimateForces on the "wrench-3f" grasp with readings 2, 1.5, 3.5 N.
v1::EstimateRequest WrenchEstimateRequest();

// Readings of `model` against a simulated press-release reference of
// `seconds`, as an AuditRequest.
v1::AuditRequest SimulatedAuditRequest(const sim::SensorModel& model, double seconds,
                                       uint64_t seed);

// EstimateFriction: `trials` simulated slip trials at friction `mu`, each
// with its normal.
v1::FrictionRequest SimulatedFrictionRequest(double mu, int trials);

// PlanFrictionProbe: a probe on built-in grasp 2 ramping 3 N -> 1 N at
// 1 N/s, sampled at 10 Hz (21 steps).
v1::FrictionProbeRequest ProbeRequest();

// FitInertia: streams `samples` in batches of `batch`, `options` in the
// first message (and every message with `options_twice`); sample
// `corrupt_index` gets a zero quaternion. 60 s deadline.
grpc::Status StreamInertia(v1::Estimator::Stub& stub, const inertia::InertiaSamples& samples,
                           const v1::InertiaFitOptions& options, int batch,
                           v1::FitInertiaResponse* response, int corrupt_index = -1,
                           bool options_twice = false);

}  // namespace tactforce::testing
