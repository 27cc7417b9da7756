// Internal (not installed): what one in-grasp probe trial is set up with —
// the contact layout on the box, the PlanFrictionProbe holding plan and the
// MJCF scene (probe_setup.cc) — and the simulation that runs it
// (probe_trial.cc).
#pragma once

#include <random>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/estimator/friction.h"
#include "tactforce/experiment/probe.h"
#include "tactforce/planner/trajectory.h"

namespace tactforce::experiment {

inline constexpr int kHoldingFingers = 3;  // thumb, middle, ring (layout: probe_setup.cc)
inline constexpr double kCloseTime =
    0.3;  // s: the holding fingertips close (object held kinematically)
inline constexpr double kSettleTime = 0.3;  // s: object released, probe force ramps in

struct ProbeSetup {
  std::vector<planner::Contact> holding;  // object frame, the three fingertips
  planner::FrictionProbe probe;           // object frame
  planner::ProbePlan plan;                // probe schedule + holding forces per sample
  Eigen::Vector3d rest_position;          // box centre (world) at rest; axes aligned with the world
  std::string mjcf;
};

// Contacts, plan and scene for one trial; `rng` draws the probe's position
// jitter on the top face.
absl::StatusOr<ProbeSetup> MakeProbeSetup(const ProbeConfig& c, const SurfacePair& surface,
                                          std::mt19937_64& rng);

// What the simulation hands to the estimator and the validity rule.
struct ProbeRecording {
  estimator::FrictionTrial trial;  // sensed force and contact point, object frame
  std::vector<double> motion,
      rotation;  // per sample: object travel (m) and rotation (deg) since the probe began
  bool dropped = false;
};

// Runs the scene: close, settle, then the probe schedule until the probe has
// travelled `probe_travel_stop` on the object (plus 50 ms) or the schedule ends.
absl::StatusOr<ProbeRecording> SimulateProbe(const ProbeConfig& c, const ProbeSetup& setup,
                                             std::mt19937_64& rng);

}  // namespace tactforce::experiment
