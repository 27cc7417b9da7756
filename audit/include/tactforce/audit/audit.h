// The sensor-model audit: given measured data (reference force vs the
// sensor's reading), show what the nominal model gets wrong, name the
// cause(s), extend the model, and measure the gain.
//
// Steps (see README, "Model audit"):
//  1. Nominal model reading = a * reference + b fitted (least squares) on the
//     training block (the earlier 1 - heldout_fraction of the samples, time
//     ordered, never shuffled); diagnostics on the residuals.
//  2. Candidate causes (force-domain operators, the same code the simulation
//     runs, sim::ApplyChannel): deadzone, saturation, nonlinearity,
//     hysteresis, delay, lag, drift, crosstalk. Their parameters are fitted
//     with NLopt (grid start + LN_SBPLX, derivative-free, for the non-smooth
//     ones; LN_BOBYQA for the smooth ones); gain/offset in closed form.
//     Two effects have two forms, each fitted and scored as a candidate of
//     its own (the lower held-out BIC represents the effect): hysteresis =
//     play operator | Prandtl-Ishlinskii (non-negative weights on a fixed
//     radius grid, NNLS), nonlinearity = quadratic | power law.
//     Two streams with an estimated clock offset: 'delay' is replaced by a
//     nuisance delay fitted with every model (reported in clock_offset_s).
//  3. Forward selection: each round fits every remaining candidate on the
//     training block and scores it on the held-out block with
//     BIC_h = n_h ln(RSS_h / n_h) + k ln(n_h). The best is accepted when it
//     lowers BIC_h AND improves the held-out RMS by at least min_gain
//     (default 1 %) AND by at least min_rms_drop x the reference force range
//     (force equivalent; default 1e-6, an absolute floor); otherwise
//     selection stops. At most max_causes.
//     Each round also tries a phantom (a reading that persists after
//     unloading), named when it beats the channel candidates.
//  3b. Blocked hold-out (options.blocks contiguous blocks): each block
//     audited on its own and confirmed with its split reversed, so an effect
//     that appears only late is named; causes list the blocks that show them.
//  3c. Per-taxel data: taxels that never activate (partial_activation),
//     listed first.
//  4. The extended model = nominal + named effects, jointly re-fitted, with
//     1-sigma uncertainties (conditional Delta-RSS = sigma^2 intervals).
//  5. Gain: the measured run re-simulated with both models
//     (sim::PredictReading), held-out RMS before/after and percent gain.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/audit/measured_data.h"
#include "tactforce/sim/sensor_model.h"

namespace tactforce::audit {

enum class Effect {
  kDeadzone,
  kSaturation,
  kNonlinearity,
  kHysteresis,
  kDelay,
  kLag,
  kDrift,
  kCrosstalk
};
inline constexpr int kNumEffects = 8;
const char* EffectName(Effect e);  // "deadzone", ... (report.json vocabulary)
absl::StatusOr<Effect> ParseEffect(const std::string& name);
const std::vector<Effect>& AllEffects();
// Two more effects the audit names that are not operators of the sensor
// model's channel (sim/ has no fields for them; they are reported in
// report.json, not written into extended_model.json):
//  - partial_activation (per-taxel data only): a fraction of the taxels never
//    activates (reading never leaves its baseline noise); parameters fraction,
//    silent_taxels (count), taxels (count); array silent_taxel_indices.
//  - phantom: a reading that persists after unloading, P * exp(-(t - t_r)/tau)
//    on top of the channel for every sample at which the reference is
//    unloaded (<= F_min + 5 % of the range) after a release at t_r;
//    parameters phantom_force P (N, > 0) and phantom_decay tau (s).
inline constexpr char kPartialActivation[] = "partial_activation";
inline constexpr char kPhantom[] = "phantom";
// The whole vocabulary: the eight channel effects, then the two above.
std::vector<std::string> AllEffectNames();
// Sensor-model fields an effect owns, all forms (e.g. deadzone: threshold,
// threshold_shift; hysteresis: hysteresis_width, pi_thresholds, pi_weights).
std::vector<std::string> EffectFields(Effect e);

struct AuditOptions {
  double heldout_fraction = 0.35;  // later block used for scoring, (0.1, 0.6)
  // Blocked hold-out (k-fold in time): after the selection on the final
  // block, further causes are chosen and scored by cross-validation over
  // `blocks` contiguous time blocks (each held out in turn, fitted on the
  // others), so an effect that appears only late is found. 0 or 1 = off;
  // at most 10.
  int blocks = 4;
  // Per-taxel data: a taxel is silent (never activates) when the largest
  // deviation of its 5-sample moving mean from its median stays below
  // silent_sigmas x its noise (robust, from first differences) / sqrt(5).
  double silent_sigmas = 8;
  bool phantom = true;     // try the phantom candidate (each round)
  double min_gain = 0.01;  // relative held-out RMS gain to accept a cause
  // Absolute floor beside min_gain: the held-out RMS (force equivalent,
  // reading units / |gain|) must also fall by at least this fraction of the
  // reference force range (1e-6: 10 uN on a 10 N range, 10x above the
  // round-off of a 9-digit CSV, far below any tactile sensor's resolution),
  // so a large relative gain on a negligible residual is no cause.
  double min_rms_drop = 1e-6;
  int max_causes = 3;
  double max_delay = 0.3;    // s, |delay| bound
  double max_lag = 0.5;      // s
  int max_evaluations = 60;  // NLopt evaluations per local refinement
  int min_samples = kMinAuditSamples;
  bool uncertainties = true;
  std::vector<Effect> candidates;  // empty = all (crosstalk needs a shear column)
  // A given model: its effects are the base the nominal fit starts from
  // (gain/offset are re-fitted; its as-given held-out RMS is reported).
  std::optional<sim::SensorModel> model;
  std::string reading_units = "reading units";
  // Downstream: force-estimation error of the grasp estimator with readings
  // corrected by the extended vs the nominal model (simulated grasps, see
  // src/downstream.cc; measured only when a cause is named).
  bool downstream_gain = true;
  int downstream_grasps = 20;
  uint64_t seed = 1;
  // Polled between the audit's stages and selection rounds; once true the
  // audit stops with absl::Cancelled("interrupted ..."). May be empty.
  std::function<bool()> interrupt;
};

struct ForceBin {
  double lo = 0, hi = 0;  // N (reference)
  int count = 0;
  double mean_residual = 0;  // N (residual / gain)
  double std_error = 0;      // N
};

struct Diagnostics {
  double train_rms = 0;          // reading units
  double heldout_rms = 0;        // reading units
  double heldout_rms_force = 0;  // N equivalent (/ |gain|)
  std::vector<ForceBin> bias_bins;
  double loading_mean = 0, unloading_mean = 0;  // N, mean residual
  int loading_count = 0, unloading_count = 0;
  int ljung_box_lags = 0;
  double ljung_box_q = 0, ljung_box_p = 1;  // held-out residuals
  int xcorr_lag_samples = 0;                // > 0: reading lags reference
  double xcorr_lag_seconds = 0;
  double residual_time_slope = 0;          // N/s
  std::vector<double> residual_time_bins;  // N, mean residual per tenth of the run
};

struct Cause {
  std::string effect;  // vocabulary above
  // Functional form where an effect has more than one: hysteresis "play" or
  // "prandtl_ishlinskii"; nonlinearity "quadratic" or "power_law"; else "".
  std::string form;
  std::map<std::string, double> parameters;  // sensor-model field -> value
  // Array parameters (PI hysteresis: pi_thresholds, pi_weights).
  std::map<std::string, std::vector<double>> array_parameters;
  std::map<std::string, double> uncertainties;  // 1 sigma (joint final fit)
  double heldout_rms_before = 0;                // reading units
  double heldout_rms_after = 0;
  double gain = 0;       // percent
  double delta_bic = 0;  // BIC_h(after) - BIC_h(before) (< 0)
  // How the cause was found: "final_block" (the split at heldout_fraction),
  // "blocked" (the blocked hold-out), "taxels" (per-taxel data).
  std::string found_by = "final_block";
  // The time blocks (1-based, of AuditReport::block_times) that show the
  // cause: for found_by "blocked" those whose held-out RMS it lowered by at
  // least min_gain (fitted on the other blocks); otherwise those in which it
  // lowers the residual RMS of the final model by at least min_gain. And the
  // per-block drop of the final model's residual RMS (percent). Empty for
  // partial_activation and phantom.
  std::vector<int> blocks;
  std::vector<double> block_gains;
};

struct CandidateScore {
  int round = 0;
  std::string effect;
  std::string form;  // see Cause::form
  std::map<std::string, double> parameters;
  std::map<std::string, std::vector<double>> array_parameters;
  double heldout_rms = 0;
  double bic = 0;
  bool accepted = false;
};

struct DownstreamGain {
  int grasps = 0;
  // RMS over contacts of |estimate from corrected readings - estimate from
  // exact normal forces| (N): the estimation error due to the readings.
  double error_nominal = 0;         // readings corrected by the nominal model
  double error_extended = 0;        // corrected by the extended model
  double gain = 0;                  // percent
  double error_exact_readings = 0;  // N, estimator's own error vs the true forces (for scale)
  std::string method;
};

struct AuditReport {
  std::string source;
  int n_samples = 0, n_train = 0, n_heldout = 0, skipped_nan_rows = 0;
  double split_time = 0;  // first held-out time
  // Blocked hold-out: the first time of each block and the last sample's
  // time (blocks + 1 values; empty when off).
  std::vector<double> block_times;
  std::string reading_units;
  bool nominal_adequate = true;
  std::vector<Cause> causes;  // strongest first
  sim::SensorModel nominal_model;
  sim::SensorModel extended_model;
  std::optional<double> given_model_heldout_rms;  // --model as given
  Diagnostics nominal, extended;
  double heldout_rms_before = 0, heldout_rms_after = 0, gain = 0;  // re-simulated; gain in percent
  std::vector<CandidateScore> candidates;
  std::optional<DownstreamGain> downstream;
  std::vector<std::string> notes;
  // Two streams: the clock offset used (reading clock minus reference clock,
  // s). Estimated = cross-correlation estimate + the audit's refinement (a
  // nuisance delay fitted with every model; a constant sensor delay is part of
  // it, indistinguishable from two streams). Fixed = as given.
  std::optional<double> clock_offset_s;
  std::string clock_offset_mode;         // "estimated" | "fixed" | "" (one CSV)
  double clock_offset_xcorr_s = 0;       // estimated: the cross-correlation stage
  double clock_offset_refinement_s = 0;  // estimated: the audit's refinement
  double clock_offset_correlation = 0;   // estimated: peak |correlation|
  // Series for plots.
  std::vector<double> t, reference, reading, predicted_nominal, predicted_extended;
};

absl::StatusOr<AuditReport> RunAudit(const MeasuredData& data, const AuditOptions& options = {});

// Writes dir/report.json, dir/summary.txt, dir/extended_model.json and
// dir/{reading_vs_reference,residual_vs_reference,residual_vs_time}.svg.
// report.json's "extended_model" is the written model's path. `source` (the
// measured CSV's name; may be empty) is named in every plot.
absl::Status WriteAuditReport(const AuditReport& report, const std::string& dir,
                              const std::string& source = "");
// The names of the files WriteAuditReport writes (what `audit --out --force`
// may replace in an earlier report's folder).
std::vector<std::string> AuditReportFileNames();
std::string AuditReportJson(const AuditReport& report,
                            const std::string& extended_model_path = "extended_model.json");
std::string FormatAuditSummary(const AuditReport& report);

}  // namespace tactforce::audit
