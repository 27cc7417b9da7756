// The inertia ablation of Sundaralingam & Hermans (T-RO 2021, Sec. IV-B,
// Figs. 7-8, Tables I-IV), reproduced: every method on the same data from
// every source, median errors per (method, source), beside the paper's.
//
// A source is a named function seed -> data (samples, truth, fit options:
// gravity, noise the fits are told, hull, mesh). Built in:
//   sim-0 .. sim-1     the paper's simulation object (Table I, "seed-table1"),
//                      four points of force application with planner forces,
//                      force-noise variance 0 / 0.1 / 0.25 / 0.5 / 1 N^2
//                      (inertia::SimulateInertia, kPaperForceVariances);
//   wrist-moderate     the same object on a simulated wrist force-torque
//                      sensor at Nadeau et al.'s moderate noise;
//   inhand-vision,     the MuJoCo in-hand source (inhand.h: box_0..box_4 in
//   inhand-kinematic   turn by seed, tactile force model, the tracker).
// Methods: baseline-ls, baseline-ls+sg51 (Savitzky-Golay, cubic, 51: the
// paper's "Baseline"), the four factor-graph variants (inertia/fit.h:
// baseline-fg, fg-no-c, fg-c, fg-c-g with the truth as prior, as the paper
// did), constrained (hull from the object's geometry) and density (the
// object's mesh).
// Errors per run (inertia/metrics.h): eq. 38 |4 - Tr(P_gt^-1 P_est)| and the
// Riemannian distance (eq. 38 is not a distance; +inf for an inconsistent
// estimate), mass %, CoM mm, consistency; medians over the runs.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/types.h"
#include "tactforce/io/mesh.h"

namespace tactforce::experiment {

enum class AblationMethod {
  kBaselineLs,
  kBaselineLsSg,
  kBaselineFg,
  kFgNoC,
  kFgC,
  kFgCG,
  kConstrained,
  kDensity,
};
// "baseline-ls", "baseline-ls+sg51", "baseline-fg", "fg-no-c", "fg-c",
// "fg-c-g", "constrained", "density".
const char* ToString(AblationMethod method);
std::vector<AblationMethod> AllAblationMethods();
// The paper's name of the method ("Baseline", "Baseline-FG", "No C, No G",
// "C, No G", "C + G"), empty for ours.
std::string PaperMethodName(AblationMethod method);

// One data set: the samples, their truth, and the fit options every method
// starts from (gravity, noise the fits are told, hull, mesh).
struct AblationData {
  std::string object;  // e.g. "seed-table1", "box_3"
  inertia::InertiaSamples samples;
  inertia::InertialParameters truth;
  inertia::InertiaOptions base;  // base.mesh: the object's closed mesh (object frame)
};

struct AblationSource {
  std::string name;         // "sim-0.25", "wrist-moderate", "inhand-vision", ...
  std::string description;  // one line for the table
  std::function<absl::StatusOr<AblationData>(uint64_t seed)> make;
};

struct AblationConfig {
  int seeds = 3;  // runs per (method, source), seeds first_seed..
  uint64_t first_seed = 1;
  double duration = 10.0;                         // s, every source's trajectory
  double rate = 100.0;                            // Hz
  std::vector<std::string> sources;               // names; empty: all built in
  std::vector<AblationMethod> methods;            // empty: all
  std::function<void(double fraction)> progress;  // may be empty
};

// InvalidArgument naming the field ("seeds: must be >= 1, got 0").
absl::Status ValidateAblationConfig(const AblationConfig& config);

// The simulation and wrist sources.
std::vector<AblationSource> SimulationAblationSources(const AblationConfig& config);
// The in-hand sources (vision and kinematic tracker): the one place where
// the MuJoCo in-hand data source (inhand.h) plugs into the ablation.
std::vector<AblationSource> InHandAblationSources(const AblationConfig& config);
// Both, in table order.
std::vector<AblationSource> BuiltInAblationSources(const AblationConfig& config);

// The options `method` fits `data` with.
inertia::InertiaOptions AblationOptions(AblationMethod method, const AblationData& data);

struct AblationRow {
  std::string method, source;
  double median_eq38 = 0;        // |4 - Tr(P_gt^-1 P_est)|
  double median_riemannian = 0;  // +inf when most runs are inconsistent
  double median_mass_error_percent = 0;
  double median_com_error_mm = 0;
  int consistent = 0;                // runs with a physically consistent estimate
  int runs = 0;                      // fits that returned an estimate
  int failed = 0;                    // fits that returned an error (not in the medians)
  std::vector<std::string> objects;  // per run
  std::vector<double> eq38;          // per run
};

struct AblationTable {
  std::vector<AblationRow> rows;  // source-major, methods in AllAblationMethods() order
  std::vector<AblationSource> sources;
  AblationConfig config;
};

// Runs every method on every source for seeds first_seed..first_seed+seeds-1.
// A failing fit is counted (`failed`), a failing source is an error.
absl::StatusOr<AblationTable> RunAblation(const AblationConfig& config);
// The same on the given sources.
absl::StatusOr<AblationTable> RunAblation(const AblationConfig& config,
                                          const std::vector<AblationSource>& sources);

// The paper's values, computed here from its Tables I-IV with the metrics
// above. Convention (the one that reproduces the 4.46 / 4.14 / 5.04 /
// 4.23 / 5.40 for in-hand vision "C, No G" to the printed digits): the
// tables' inertia is about the CoM, as tensor entries (not negated
// products), in units of 1e-2 (Table I) and 1e-5 (Tables II-IV) kg m^2.
// Per object; `source` uses our names (Table II = "wrist-moderate": note the
// paper's wrist data are real, ours simulated).
struct PaperAblationValue {
  std::string method;  // ours ("fg-c"), from PaperMethodName
  std::string source;
  std::vector<std::string> objects;
  std::vector<double> eq38, riemannian, mass_error_percent, com_error_mm;
  int consistent = 0;
};
std::vector<PaperAblationValue> PaperAblationValues();
std::optional<PaperAblationValue> FindPaperValue(const std::string& method,
                                                 const std::string& source);

// Markdown table with the paper's values beside ours, the convention, and
// the in-hand targets (fg-c median eq. 38 <= 0.2 x fg-no-c and x baseline-fg).
std::string AblationMarkdown(const AblationTable& table);
// {"rows": [{"method", "source", "median_eq38", "median_riemannian",
//   "median_mass_error_percent", "median_com_error_mm", "consistent",
//   "runs"}...]} (non-finite numbers are null).
std::string AblationJson(const AblationTable& table);

}  // namespace tactforce::experiment
