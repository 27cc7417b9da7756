// The work limit: every method stops soon after its interrupt callback turns
// true, even on data sets big enough that an unpolled fit runs for seconds;
// and the region count's upper limit.
#include <chrono>
#include <map>
#include <memory>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/simulate.h"

namespace tactforce::inertia {
namespace {

using Clock = std::chrono::steady_clock;

// Bound on the time from the interrupt turning true to the fit's return:
// generous for a loaded 2-core machine (polls happen every few ms of work).
constexpr double kStopBoundMs = 500.0;

// Wrist-wrench simulation of the built-in box (its mesh serves DENSITY),
// noisy so the fits do their full work; deterministic.
const SimulationResult& BoxData(double duration_s, double rate_hz) {
  static std::map<std::pair<double, double>, std::unique_ptr<SimulationResult>> cache;
  auto& slot = cache[{duration_s, rate_hz}];
  if (!slot) {
    SimulationOptions o;
    o.object = "box";
    o.mode = SimulationMode::kWristWrench;
    o.duration = duration_s;
    o.rate_hz = rate_hz;
    o.noise.force_sigma = 0.05;
    o.noise.torque_sigma = 0.005;
    o.noise.position_sigma = 1e-4;
    o.noise.orientation_sigma = 1e-3;
    o.seed = 23;
    absl::StatusOr<SimulationResult> r = SimulateInertia(o);
    EXPECT_TRUE(r.ok()) << r.status();
    slot = std::make_unique<SimulationResult>(*std::move(r));
  }
  return *slot;
}

struct StopRun {
  absl::Status status;
  double stop_ms = 0;  // from the interrupt turning true to the return
};

// Runs FitInertia with an interrupt that turns true `after_ms` after the start.
StopRun FitInterruptedAfter(const InertiaSamples& samples, InertiaOptions options,
                            double after_ms) {
  const Clock::time_point deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double, std::milli>(after_ms));
  options.interrupt = [deadline] { return Clock::now() >= deadline; };
  StopRun run;
  run.status = FitInertia(samples, options).status();
  run.stop_ms = std::chrono::duration<double, std::milli>(Clock::now() - deadline).count();
  return run;
}

// T in [20, 200] ms, drawn from a seed per method.
double DrawInterruptMs(InertiaMethod method) {
  std::mt19937 rng(2300 + static_cast<int>(method));
  return std::uniform_int_distribution<int>(20, 200)(rng);
}

void ExpectStopsPromptly(const InertiaSamples& samples, const InertiaOptions& options) {
  const double after_ms = DrawInterruptMs(options.method);
  const StopRun run = FitInterruptedAfter(samples, options, after_ms);
  SCOPED_TRACE(absl::StrCat(ToString(options.method), ": interrupt after ", after_ms, " ms, ",
                            samples.samples.size(), " samples"));
  // The data are big enough that the fit is still running at T.
  EXPECT_EQ(run.status.code(), absl::StatusCode::kCancelled) << run.status;
  EXPECT_EQ(run.status.message(), "interrupted");
  EXPECT_LT(run.stop_ms, kStopBoundMs);
}

// Sizes: each fit without polling ran for 4-200 s here under load, well
// over T + kStopBoundMs; each data set takes about a second to simulate.
TEST(Interrupt, BaselineLsStopsPromptly) {
  const SimulationResult& data = BoxData(400.0, 500.0);
  InertiaOptions o;
  o.method = InertiaMethod::kBaselineLs;
  o.baseline_ls.savitzky_golay = true;
  ExpectStopsPromptly(data.samples, o);
}

TEST(Interrupt, ConstrainedAndFactorGraphStopPromptly) {
  const SimulationResult& data = BoxData(200.0, 500.0);
  for (InertiaMethod method : {InertiaMethod::kConstrained, InertiaMethod::kFactorGraph}) {
    InertiaOptions o;
    o.method = method;
    o.hull = data.object.hull;
    ExpectStopsPromptly(data.samples, o);
  }
}

TEST(Interrupt, DensityWithManyRegionsStopsPromptly) {
  const SimulationResult& data = BoxData(20.0, 100.0);
  InertiaOptions o;
  o.method = InertiaMethod::kDensity;
  o.mesh = std::make_shared<const io::TriangleMesh>(data.object.mesh);
  o.density.regions.scheme = RegionScheme::kGrid;
  o.density.regions.target_regions = kMaxTargetRegions;
  ExpectStopsPromptly(data.samples, o);
}

TEST(Interrupt, RegionBuildingStopsWhenInterrupted) {
  const SimulationResult& data = BoxData(20.0, 100.0);
  RegionOptions o;
  o.scheme = RegionScheme::kGrid;
  o.target_regions = kMaxTargetRegions;
  int polls = 0;
  absl::StatusOr<RegionModel> r =
      BuildRegions(data.object.mesh, o, "box", [&polls] { return ++polls > 0; });
  EXPECT_EQ(r.status().code(), absl::StatusCode::kCancelled) << r.status();
  EXPECT_EQ(r.status().message(), "interrupted");
  EXPECT_EQ(polls, 1);
  polls = 0;
  EXPECT_TRUE(BuildRegions(data.object.mesh, o, "box", [&polls] { return ++polls < 0; }).ok());
  EXPECT_GE(polls, 1);
}

TEST(TargetRegions, AboveTheLimitIsInvalidArgumentNamingTheFieldAndLimit) {
  const SimulationResult& data = BoxData(20.0, 100.0);
  InertiaOptions o;
  o.method = InertiaMethod::kDensity;
  o.mesh = std::make_shared<const io::TriangleMesh>(data.object.mesh);
  o.density.regions.target_regions = kMaxTargetRegions;
  EXPECT_TRUE(ValidateInertiaOptions(o).ok());
  o.density.regions.target_regions = kMaxTargetRegions + 1;
  const absl::Status st = ValidateInertiaOptions(o);
  EXPECT_EQ(st.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("regions.target_regions"), std::string::npos) << st;
  EXPECT_NE(st.message().find(absl::StrCat("1..", kMaxTargetRegions)), std::string::npos) << st;
  const absl::Status fit = FitInertia(data.samples, o).status();
  EXPECT_EQ(fit.code(), absl::StatusCode::kInvalidArgument) << fit;

  RegionOptions ro;
  ro.target_regions = kMaxTargetRegions + 1;
  const absl::Status built = BuildRegions(data.object.mesh, ro, "box").status();
  EXPECT_EQ(built.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(built.message().find("target_regions"), std::string::npos) << built;
}

}  // namespace
}  // namespace tactforce::inertia
