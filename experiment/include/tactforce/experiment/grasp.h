// Closed-loop grasp-and-lift experiments in MuJoCo (GeoDEx Table III):
// floating spherical fingertips on three slide joints each, PD-controlled in
// fingertip space (the Jacobian is the identity), close on an object resting
// on a table, regulate their normal forces with an admittance loop on either
// the raw tactile readings or tactforce's estimate, lift, hold and place.
// Readings come from one sensor-model channel per fingertip or from a
// 42-taxel array per fingertip (SensorArray::kTaxel), whose sensed contacts
// replace the grasp's for planning at the end of the close; failed trials are
// labelled with a FailureCause and batches split the force error between
// successful and failed trials (Table III).
//
//   GraspConfig c;  c.object = GraspObject::kWrench;  c.feedback = Feedback::kRaw;
//   auto setup = GraspSetup::Create(c);            // plans once per object
//   auto trial = RunGraspTrial(**setup, 3);        // trial 3 of seed c.seed
//   auto batch = RunGraspBatch(c, 20);             // 20 trials, summary
//
// All quantities SI. Errors are InvalidArgument naming the config field.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/estimator/force_estimation.h"
#include "tactforce/experiment/physics.h"
#include "tactforce/experiment/sensor_channel.h"
#include "tactforce/io/svg.h"
#include "tactforce/planner/trajectory.h"
#include "tactforce/sim/sensor_model.h"
#include "tactforce/sim/taxel_array.h"

namespace tactforce::experiment {

enum class GraspObject {
  kSphere,    // 0.082 kg, r 35 mm, 2-finger pinch, mu 0.8
  kWrench,    // 0.3 kg wrench (handle + head), 3 fingers, mu 0.9
  kCylinder,  // 0.36 kg, d 0.11 m, 4 fingers, mu 0.6
  kCube,  // 8 cm, 0.15 kg, 2 fingers (mu 0.8) pivot it about a bottom edge on the table (mu 0.6)
};
const char* ToString(GraspObject o);  // "sphere", "wrench", "cylinder", "cube"
absl::StatusOr<GraspObject> ParseGraspObject(std::string_view name);
std::vector<GraspObject> AllGraspObjects();

enum class Feedback { kRaw, kEstimated };
const char* ToString(Feedback f);  // "raw", "estimated"
absl::StatusOr<Feedback> ParseFeedback(std::string_view name);

// How the force error drives the fingertip targets.
enum class Admittance {
  // target += gain K^-1 (f_desired - f_observed), the whole 3D force (the
  // paper's and the loop). Raw readings observe r_i n_i: no tangential part.
  kFull,
  // Only along the sensed normal: delta_n += gain K^-1 (fn_desired - fn_observed);
  // the planned tangential force is fed forward as a position offset K^-1 f_t.
  kNormal,
};
const char* ToString(Admittance a);  // "full", "normal"
absl::StatusOr<Admittance> ParseAdmittance(std::string_view name);

enum class SensorMode {
  kGeoDexRandom,  // a model drawn per fingertip and trial from `error_ranges`
  kModel,         // `sensor_model` on every fingertip (noise still seeded per trial)
  kIdeal,         // readings = true normal force
};

// What each fingertip's reading comes from.
enum class SensorArray {
  kChannel,  // one SensorChannel per fingertip on MuJoCo's normal force (`sensors` picks its model)
  kTaxel,    // a sim::TaxelArray per fingertip on MuJoCo's contact point and 3D force; contact
             // locations and normals for planning and estimation sensed at the end of the close
};
const char* ToString(SensorArray s);  // "channel", "taxel"
absl::StatusOr<SensorArray> ParseSensorArray(std::string_view name);

// Where the plans and the estimator take each taxel fingertip's contact
// from at the end of the close.
enum class ContactSensing {
  // GeoDEx IV-A: the force-weighted mean taxel position and the normalised
  // force-weighted mean taxel normal (the mean position lies inside the surface).
  kTaxelMean,
  // That position projected onto the fingertip's known surface
  // (sim::ProjectOntoFingertip), the normal the surface's normal there.
  kSurface,
  // Diagnostics (what-if runs): MuJoCo's true contact normal with the
  // kTaxelMean location, the true location with the kTaxelMean normal, or both true.
  kTrueNormal,
  kTrueLocation,
  kTruth,
};
const char* ToString(
    ContactSensing s);  // "mean", "surface", "true-normal", "true-location", "truth"
absl::StatusOr<ContactSensing> ParseContactSensing(std::string_view name);

struct PhaseDurations {  // s
  double close = 0.3;    // fingertips move from open to contact (position control)
  double settle = 0.5;   // force loop on, object on the table
  double hold = 0.5;
  double lift = 1.0;  // minimum-jerk lift (cube: pivot up)
  double hold_lifted = 1.0;
  double place = 0.8;   // back down
  double placed = 0;    // held on the table after the place (0 = none)
  double switched = 0;  // then the other feedback (raw <-> estimated) for this long (0 = none)
};

// The trial's timeline: today's short trial, or GeoDEx Sec. IV-C's wrench
// protocol (Fig. 12): converge and hold until 27 s, lift, place back at 33 s,
// hold, switch the feedback at 40 s, 10 s more.
enum class Protocol { kShort, kPaper };
const char* ToString(Protocol p);  // "short", "paper"
absl::StatusOr<Protocol> ParseProtocol(std::string_view name);
PhaseDurations ProtocolPhases(Protocol p);

// Why a failed trial failed (GeoDEx Sec. IV-C's failure modes), judged from
// the settle until the first failure criterion is met:
//   non_activation: a fingertip's reading < 50 % of its true force for > 0.1 s
//     while the true force rises (and exceeds 0.1 N);
//   phantom_force: a reading > true + 0.5 N while the true force < 0.1 N, or a
//     touching fingertip detaching (true force < 0.1 N for >= 0.05 s);
//   over_reading_tilt: the object tilted (rotation >= max_rotation_deg, not
//     dropped; it may slip too) with a fingertip reading on average more than
//     0.25 N above its true force;
//   slip_drop: any other failure.
// The first that applies, in this order.
enum class FailureCause { kNone, kNonActivation, kPhantomForce, kOverReadingTilt, kSlipDrop };
const char* ToString(
    FailureCause c);  // "none", "non_activation", "phantom_force", "over_reading_tilt", "slip_drop"
std::vector<FailureCause> AllFailureCauses();  // the four causes, without kNone

// A constructed sensor fault on one fingertip's summed reading (tests and
// what-if runs): from `start` (s) on, kDead reads 0, kOffset adds `magnitude` N.
struct SensorFault {
  enum class Kind { kNone, kDead, kOffset };
  Kind kind = Kind::kNone;
  int finger = 0;
  double magnitude = 0;  // N
  double start = 0;      // s
};

// Parameters the plans and the estimator's problems use in place of the
// simulated object's (issue 28's chain: point estimates, or estimates with
// their uncertainty); MuJoCo always simulates the true object. Object frame,
// SI; `inertia` about the CoM; `friction` and `friction_sigma` replace every
// fingertip contact's (extrinsic contacts keep theirs).
struct PlanningModel {
  double mass = 0;                            // kg
  planner::Vec3 com = planner::Vec3::Zero();  // m
  planner::Inertia inertia;                   // kg m^2, about the CoM
  double friction = 0;                        // mu of the fingertips
  double friction_sigma = 0;                  // std. dev. of mu (0 = known)
  planner::ParameterUncertainty uncertainty;  // of pi about the origin (zero = known)
};

// GraspConfig::contact_cap_deg's default (deg): the dome's outermost taxel
// ring (sim::DefaultFingertip: the apex and rings at 30 and 60 deg).
inline constexpr double kDefaultContactCapDeg = 60;

struct GraspConfig {
  GraspObject object = GraspObject::kWrench;
  Feedback feedback = Feedback::kEstimated;
  estimator::EstimateMethod estimator =
      estimator::EstimateMethod::kNormalLsq;       // or kProjection (GeoDEx)
  SensorMode sensors = SensorMode::kGeoDexRandom;  // kChannel's model
  ErrorRanges error_ranges;
  SensorArray sensor_array = SensorArray::kChannel;
  sim::TaxelRanges taxel_ranges;  // kTaxel: drawn per taxel, fingertip and trial
  // kTaxel: where on the fingertip its contact lands. Each fingertip's axis is
  // drawn per trial (the same for raw and estimated feedback) so that the
  // contact's polar angle from the apex is uniform by area over the cap of
  // this half-angle (deg, [0, 90]; azimuth uniform). 0: every fingertip points
  // along its contact normal, so every contact is centred on the apex taxel.
  // Default: the polar angle of the dome's outermost taxel ring
  // (sim::DefaultFingertip), so a contact lands anywhere on the taxelised tip.
  double contact_cap_deg = kDefaultContactCapDeg;
  ContactSensing contact_sensing = ContactSensing::kTaxelMean;  // kTaxel
  SensorFault fault;
  sim::SensorModel sensor_model;  // kModel
  uint64_t seed = 1;              // trial k draws from (seed, k), independent of feedback
  PhaseDurations phases;
  double lift_height = 0.05;    // m
  double pivot_angle_deg = 15;  // cube
  double control_rate = 200;    // Hz: sensor sampling, estimation, admittance update
  // Admittance: each control tick moves a fingertip target by
  // gain * K^-1 (f_desired - f_observed), K = kp (see Admittance).
  Admittance admittance = Admittance::kFull;
  double admittance_gain = 0.2;
  // kFull with estimated feedback: how far (deg) the contact normals the
  // estimate stands on may be off. A normal off by delta turns the estimated
  // force f by delta, a tangential error up to |f| sin(delta) (the estimate's
  // tangential part comes from equilibrium on those normals, not from a
  // measurement), so the tangential part of (f_desired - f_estimated) is
  // acted on only beyond |f_estimated| sin(delta). Raw feedback has no
  // estimate and is not changed. Negative: the taxel layout's resolution
  // (sim::DomeResolutionDeg) with taxel sensors, 0 with channel sensors
  // (their normals are the specification's).
  double normal_uncertainty_deg = -1;
  double kp = 10000;  // N/m, fingertip PD stiffness (also its tangential stiffness)
  double damping_ratio = 1.0;
  double fingertip_mass = 0.05;     // kg (gravity compensated)
  double fingertip_radius = 0.012;  // m
  double confidence = 1.0;          // planner kappa
  double max_rotation_deg =
      1.0;                      // success thresholds from the settle to the end of the lifted hold
  double max_slip = 0.005;      // m
  double drop_distance = 0.02;  // m, object this far from where the hand holds it = dropped
  PhysicsSettings physics;
  int trace_trials = 0;                         // record TraceSamples for trials 0..trace_trials-1
  std::optional<PlanningModel> planning_model;  // empty: plan with the true parameters
};
absl::Status ValidateGraspConfig(const GraspConfig& c);

enum class Phase { kClose, kSettle, kHold, kLift, kHoldLifted, kPlace, kPlaced, kSwitched };
const char* ToString(Phase p);

struct TraceSample {
  double t = 0;
  Phase phase = Phase::kClose;
  // Per intrinsic fingertip (N, normal components).
  std::vector<double> desired, raw, estimated, truth;
  double slip = 0, rotation_deg = 0;  // vs where the hand holds it (lift and after)
};

struct TrialResult {
  int trial = 0;
  uint64_t seed = 0;
  bool success = false;
  bool dropped = false;
  std::string
      failure;  // "", "dropped", "slip 7.1 mm", "rotation 2.3 deg", "moved before the lift (...)"
  FailureCause cause = FailureCause::kNone;  // kNone when successful
  // The object's pose from the settle's start to the end of the lifted hold,
  // against where the hand's motion since then puts it (m, deg), and the
  // same over the settle and hold alone (the hand at rest: the object should
  // not move); failure_time: when a criterion was first met (s, -1 = never).
  double max_slip = 0;
  double max_rotation_deg = 0;
  double max_slip_before_lift = 0, max_rotation_before_lift_deg = 0;
  double failure_time = -1;
  double force_error = 0;     // N, mean |fn_true - fn_desired| over fingertips, hold..hold_lifted
  double feedback_error = 0;  // N, mean |fn_observed - fn_true| (what the loop was told vs truth)
  // The loop's own error, mean |fn_desired - fn_observed| (GeoDEx's "error between the desired
  // force and the estimated values"), hold..hold_lifted, over fingertips; and both errors per
  // fingertip (N).
  double loop_error = 0;
  std::vector<double> finger_force_error, finger_loop_error;
  // Hold, lift and lifted hold, from MuJoCo's true contact forces: the
  // squeeze (sum of the fingertips' normal forces, N, mean over control
  // ticks) and the smallest slip margin 1 - |f_t| / (mu f_n) over ticks and
  // fingertips pressing with f_n >= 0.05 N (1 = no shear, 0 = on the cone).
  double squeeze = 0;
  double min_slip_margin = 1;
  double converge_time = -1;  // s after settle start until the loop's own error stays
                              // below max(0.1 N, 10 %) for 0.1 s; -1 = never
  int estimate_failures = 0;  // ticks where the estimator gave no answer (raw used)
  double sim_seconds = 0, wall_seconds = 0;
  std::vector<sim::SensorModel> sensor_models;  // per fingertip (the draw; channel sensors)
  // Taxel sensors: how far the sensed contact locations (end of the close)
  // were from the grasp specification's (m, mean over fingertips), how many
  // fingertips sensed one (the rest keep the specification's), and whether
  // the re-plan on them failed (the specification's plan is kept).
  double contact_location_error = 0;
  double contact_normal_error_deg = 0;
  int contacts_sensed = 0;
  bool replan_failed = false;
  // Taxel sensors: where each fingertip's contact landed at rest, its polar
  // angle from the apex (deg; GraspConfig::contact_cap_deg).
  std::vector<double> contact_polar_deg;
  // Switched phase (PhaseDurations::switched > 0): mean |fn_true - fn_desired|
  // per fingertip under the other feedback, and the object's largest motion
  // from its pose when the switch happened.
  std::vector<double> switched_force_error;
  double switched_motion = 0;      // m
  std::vector<TraceSample> trace;  // when record_trace
};

// Object, MJCF and force plans of one config, shared by its trials.
class GraspSetup {
 public:
  static absl::StatusOr<std::unique_ptr<GraspSetup>> Create(const GraspConfig& config);
  ~GraspSetup();
  const GraspConfig& config() const { return config_; }
  const std::string& mjcf() const { return mjcf_; }
  const std::vector<std::string>& finger_names() const;

  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  GraspSetup() = default;
  GraspConfig config_;
  std::string mjcf_;
  std::unique_ptr<Impl> impl_;
};

absl::StatusOr<TrialResult> RunGraspTrial(const GraspSetup& setup, int trial);

struct BatchSummary {
  GraspObject object = GraspObject::kWrench;
  Feedback feedback = Feedback::kEstimated;
  int trials = 0, successes = 0, drops = 0;
  double force_error_mean = 0, force_error_std = 0;  // over trials (N)
  // Table III's split: over successful and over failed trials (N; 0 if none).
  double force_error_success_mean = 0, force_error_success_std = 0;
  double force_error_failure_mean = 0, force_error_failure_std = 0;
  std::map<std::string, int> failure_causes;                  // every cause's name -> failed trials
  double loop_error_mean = 0, loop_error_std = 0;             // N, over trials
  std::vector<double> finger_force_error, finger_loop_error;  // N, per fingertip, mean over trials
  std::vector<std::string> finger_names;
  int replan_failures = 0;                   // taxel sensors
  double contact_location_error_mean = 0;    // m, taxel sensors
  std::vector<double> switched_force_error;  // per fingertip, mean over trials (paper protocol)
  double feedback_error_mean = 0;            // N
  double converge_time_mean = -1;            // s over converged trials; -1 none
  int converged = 0;
  double wall_seconds = 0, sim_seconds = 0;
  std::vector<TrialResult> results;
};

// Runs trials 0..n-1; `progress(done)` after each.
absl::StatusOr<BatchSummary> RunGraspBatch(const GraspConfig& config, int trials,
                                           const std::function<void(int)>& progress = {});

// Desired / estimated / raw / true normal-force traces, one panel per fingertip.
io::SvgPlot TracePlot(const TrialResult& trial, const std::vector<std::string>& finger_names,
                      const std::string& title);

}  // namespace tactforce::experiment
