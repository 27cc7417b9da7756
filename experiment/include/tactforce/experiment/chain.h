// The chain probe -> fit -> plan -> lift (issue 28) in MuJoCo: for each
// object and seed, friction probed in a grasp (probe.h), mass, CoM and
// inertia fitted from an in-hand run (inhand.h), then the lift planned three
// ways and run through the closed loop with estimated-force feedback
// (grasp.h): with the true parameters, with the point estimates, and with the
// estimates and their uncertainty (planner: Contact::friction_sigma,
// ObjectModel::uncertainty).
//
// The probe and the in-hand run act on simulated equivalents of the grasp
// object, not on the grasp object itself: the probe's box with the grasp's
// fingertip friction (friction is the surface pair's), and an in-hand box with
// the object's mass, CoM and (clamped) principal moments, its frame the grasp
// object's. SI units, object frame.
//
//   ChainConfig c;  c.objects = {GraspObject::kWrench};  c.trials = 5;
//   auto report = RunChain(c);   // rows per object and planning
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/experiment/grasp.h"
#include "tactforce/experiment/inhand.h"
#include "tactforce/experiment/probe.h"

namespace tactforce::experiment {

enum class Planning { kTruth, kPoint, kUncertain };
const char* ToString(Planning p);  // "truth", "point", "uncertain"

struct ChainConfig {
  std::vector<GraspObject> objects = {GraspObject::kSphere, GraspObject::kWrench,
                                      GraspObject::kCylinder};
  uint64_t seed = 1;  // seeds seed .. seed + seeds - 1
  int seeds = 2;
  int trials = 5;              // closed-loop trials per object, seed and planning
  int probe_trials = 3;        // in-grasp friction probes per object and seed
  double inhand_duration = 4;  // s of in-hand excitation logged per object and seed
  inertia::InertiaMethod fit_method = inertia::InertiaMethod::kConstrained;
  double confidence = 1.0;  // kappa of the friction and parameter uncertainty (std. devs)
  GraspConfig grasp;        // the closed loop (object, seed, planning_model are set per run)
  ProbeConfig probe;        // the probe (object = its box; seed set per run)
  InHandConfig inhand;      // the in-hand run (custom object, seed, duration set per run)
};
// InvalidArgument naming the field ("trials: must be >= 1, got 0").
absl::Status ValidateChainConfig(const ChainConfig& c);

// What one seed's probe and fit gave, beside the truth.
struct ChainEstimates {
  GraspObject object = GraspObject::kSphere;
  uint64_t seed = 0;
  double mu_true = 0, mu = 0, mu_sigma = 0;  // mean and std. dev. over valid probes
  int probes_valid = 0;
  double mass_true = 0, mass = 0, mass_se = 0;     // kg
  planner::Vec3 com_true = planner::Vec3::Zero();  // m
  planner::Vec3 com = planner::Vec3::Zero(), com_se = planner::Vec3::Zero();
  // Some estimate (mu, mass or a CoM component) is off by more than its standard error.
  bool off_by_more_than_se = false;
  PlanningModel point, uncertain;
};

struct ChainRow {
  GraspObject object = GraspObject::kSphere;
  Planning planning = Planning::kTruth;
  int successes = 0, trials = 0;
  int plan_failures = 0;        // seeds whose plan could not be made (trials count as failed)
  std::string plan_failure;     // the first such seed's planner message
  int trials_run = 0;           // trials actually simulated (the two figures below are over these)
  double median_squeeze_n = 0;  // N, median over trials of the mean sum of normal forces
  double min_slip_margin = 1;   // smallest over trials (TrialResult::min_slip_margin)
  double median_trial_slip_margin = 1;  // median over trials of each trial's smallest
  bool estimates_off = false;  // any seed's estimates off by more than their standard error
};

struct ChainReport {
  std::vector<ChainRow> rows;  // per object: truth, point, uncertain
  std::vector<ChainEstimates> estimates;
  double wall_seconds = 0;
};

// The in-hand box standing in for `object`: its mass and CoM, edges from its
// principal moments about the CoM, clamped to [0.04, 0.3] m.
InHandObject InHandEquivalent(const std::string& name, double mass, const planner::Vec3& com,
                              const planner::Inertia& inertia);

// `progress(done, total)` after each step (may be empty).
absl::StatusOr<ChainReport> RunChain(const ChainConfig& config,
                                     const std::function<void(int, int)>& progress = {});

}  // namespace tactforce::experiment
