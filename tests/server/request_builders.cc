// Shared request builders of the server tests (request_builders.h).
#include "request_builders.h"

#include <chrono>
#include <memory>

#include <gtest/gtest.h>

#include "tactforce/api/convert.h"
#include "tactforce/api/inertia.h"
#include "tactforce/estimator/friction.h"
#include "tactforce/planner/examples.h"
#include "tactforce/sim/simulate.h"
#include "test_support.h"

namespace tactforce::testing {

v1::TrajectoryRequest LiftRequest(int steps) {
  const planner::TrajectoryProblem t = planner::WrenchLiftAndRotate(steps);
  v1::TrajectoryRequest r;
  *r.mutable_plan() =
      api::ToRequest(t.base, planner::PlanOptions{}, planner::SolverKind::kGeometric);
  v1::Inertia* in = r.mutable_plan()->mutable_object()->mutable_inertia();
  in->set_ixx(t.inertia->ixx);
  in->set_iyy(t.inertia->iyy);
  in->set_izz(t.inertia->izz);
  in->set_ixy(t.inertia->ixy);
  in->set_ixz(t.inertia->ixz);
  in->set_iyz(t.inertia->iyz);
  for (const auto& s : t.steps) {
    v1::TrajectoryStep* out = r.add_steps();
    *out->mutable_gravity() = api::ToProto(s.gravity);
    *out->mutable_linear_acceleration() = api::ToProto(s.linear_acceleration);
    *out->mutable_angular_velocity() = api::ToProto(s.angular_velocity);
    *out->mutable_angular_acceleration() = api::ToProto(s.angular_acceleration);
  }
  return r;
}

// Readings of `model` against a simulated press-release reference, as an
// AuditRequest.
v1::AuditRequest SimulatedAuditRequest(const sim::SensorModel& model, double seconds,
                                       uint64_t seed) {
  sim::SimOptions options;
  options.seconds = seconds;
  options.seed = seed;
  absl::StatusOr<sim::SimRun> run = sim::SimulateSensor(model, options);
  EXPECT_TRUE(run.ok()) << run.status();
  v1::AuditRequest request;
  if (!run.ok()) return request;
  for (size_t k = 0; k < run->t.size(); ++k) {
    v1::AuditSample* s = request.add_samples();
    s->set_t(run->t[k]);
    s->set_reference(run->reference[k]);
    s->set_reading(run->reading[k]);
  }
  return request;
}

v1::EstimateRequest WrenchEstimateRequest() {
  v1::EstimateRequest request;
  const v1::PlanRequest wrench = WrenchRequest();
  *request.mutable_object() = wrench.object();
  *request.mutable_contacts() = wrench.contacts();
  for (double r : {2.0, 1.5, 3.5}) request.add_readings(r);
  return request;
}

v1::FrictionRequest SimulatedFrictionRequest(double mu, int trials) {
  estimator::FrictionSimOptions sim;
  sim.mu = mu;
  sim.trials = trials;
  const estimator::SimulatedFriction data = estimator::SimulateFriction(sim);
  v1::FrictionRequest request;
  for (const auto& trial : data.trials) {
    v1::FrictionTrial* t = request.add_trials();
    *t->mutable_normal() = api::ToProto(*trial.normal);
    for (const auto& s : trial.samples) {
      v1::FrictionSample* out = t->add_samples();
      out->set_t(s.t);
      *out->mutable_force() = api::ToProto(s.force);
      *out->mutable_contact_point() = api::ToProto(s.contact_point);
    }
  }
  return request;
}

v1::FrictionProbeRequest ProbeRequest() {
  v1::FrictionProbeRequest probe;
  *probe.mutable_plan() = api::ToRequest(planner::BuiltInGrasps()[2].problem,
                                         planner::PlanOptions{}, planner::SolverKind::kGeometric);
  probe.mutable_position()->set_z(0.06);
  probe.mutable_normal()->set_z(-1);
  probe.mutable_tangent()->set_x(1);
  probe.set_tangential_force(1.0);
  probe.set_initial_normal_force(3.0);
  probe.set_final_normal_force(1.0);
  probe.set_ramp_rate(1.0);
  probe.set_sample_rate(10.0);
  return probe;
}

grpc::Status StreamInertia(v1::Estimator::Stub& stub, const inertia::InertiaSamples& samples,
                           const v1::InertiaFitOptions& options, int batch,
                           v1::FitInertiaResponse* response, int corrupt_index,
                           bool options_twice) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  std::unique_ptr<grpc::ClientWriter<v1::FitInertiaRequest>> writer =
      stub.FitInertia(&context, response);
  v1::FitInertiaRequest message;
  *message.mutable_options() = options;
  for (size_t i = 0; i < samples.samples.size(); ++i) {
    v1::InertiaSample* s = message.add_samples();
    *s = api::InertiaSampleToProto(samples.samples[i], samples.source);
    if (static_cast<int>(i) == corrupt_index) s->mutable_orientation()->Clear();  // zero quaternion
    if (message.samples_size() == batch || i + 1 == samples.samples.size()) {
      if (!writer->Write(message)) break;
      message.Clear();
      if (options_twice) *message.mutable_options() = options;
    }
  }
  writer->WritesDone();
  return writer->Finish();
}

}  // namespace tactforce::testing
