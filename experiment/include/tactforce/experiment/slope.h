// Friction ground truth by the slope method (Sundaralingam & Hermans IV-A)
// against the probing estimate (estimator::EstimateFriction), both in
// MuJoCo on the same surface, and MuJoCo's creep under static friction.
//
// Slope: a fingertip (a sphere on three slide joints: it slides, it cannot
// roll) rests on a plate that tilts slowly about a horizontal axis through
// the contact; mu_slope = tan(tilt when the fingertip has moved
// `slip_distance` down the plate since the tilt started).
// Probe: the fingertip is pushed onto a level plate with a constant
// tangential force while the normal force ramps down until it slips; the
// contact force and contact point at `sample_rate` go to EstimateFriction.
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/estimator/friction.h"
#include "tactforce/experiment/physics.h"

namespace tactforce::experiment {

struct SlopeConfig {
  std::vector<double> mus = {0.3, 0.5, 0.7, 0.9};
  double fingertip_mass = 0.05;     // kg
  double fingertip_radius = 0.012;  // m
  double tilt_rate_deg = 0.5;       // deg/s
  double start_margin_deg = 3;      // tilting starts at atan(mu) - margin
  double settle = 0.3;              // s at the start tilt before tilting
  double slip_distance = 0.001;     // m down the plate since the tilt started
  // Probing.
  double probe_tangential = 1.0;        // N
  double probe_ramp = 0.5;              // N/s, normal-force decrease
  double probe_start_ratio = 1.5;       // initial normal force = ratio * F_t / mu
  double sample_rate = 200;             // Hz
  estimator::FrictionOptions friction;  // EstimateFriction settings
  PhysicsSettings physics;
};
absl::Status ValidateSlopeConfig(const SlopeConfig& c);

struct SlopeRow {
  double mu = 0;  // MJCF friction
  double slip_tilt_deg = 0;
  double mu_slope = 0;  // tan(slip tilt)
  double mu_probe = 0;  // EstimateFriction
  bool probe_valid = false;
  std::string probe_message;
};

absl::StatusOr<SlopeRow> RunSlopeAndProbe(const SlopeConfig& c, double mu);
absl::StatusOr<std::vector<SlopeRow>> RunSlopeTable(const SlopeConfig& c);

// Creep: the fingertip on a plate tilted to tan(tilt) = load_ratio * mu
// (static friction must hold it); mean down-slope velocity (m/s) over
// `seconds` after `settle` s.
absl::StatusOr<double> MeasureCreep(const PhysicsSettings& physics, double mu, double load_ratio,
                                    double seconds = 2.0, double settle = 0.5,
                                    double fingertip_mass = 0.05);

}  // namespace tactforce::experiment
