// Every kind of picture is legible: parsed back from its SVG, no two text
// labels overlap (boxes estimated from font size and character count), all
// text lies inside the canvas, and every labelled axis has at least three
// tick labels. Pictures: the plan and trajectory plots (api), the density
// plot (inertia), the audit's three plots, the experiments' trace plot
// (io::RenderSvg). Inputs are drawn from seeds: contacts on a sphere
// (including the pinch whose labels coincide in one view), trajectories,
// boxes of any aspect (long tools) with regions of one or many densities,
// sensor logs, force traces.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include "absl/strings/str_format.h"
#include "tactforce/api/json.h"
#include "tactforce/api/plan_plot.h"
#include "tactforce/api/services.h"
#include "tactforce/audit/audit.h"
#include "tactforce/experiment/grasp.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/density_plot.h"
#include "tactforce/io/svg.h"
#include "support/svg_legibility.h"
#include "support/temp_dir.h"

namespace tactforce {
namespace {

using test_support::ExpectLegible;
using test_support::Parse;
using test_support::Parsed;

// The checks catch what they are for: coinciding labels ("thindexb"), a
// title past the canvas's edge, an axis with one tick label.
TEST(PlotLegibility, TheChecksCatchOverlapsTextOutsideAndSingleTicks) {
  // A legible base (two axes of five ticks) and one defect each.
  auto picture = [](int defect) {
    io::SvgCanvas canvas(300, 200, 12);
    const io::PlotFrame frame{60, 40, 200, 100, 0, 1, 0, 1};
    io::DrawAxes(canvas, frame, io::TicksAt(0, 1, 0.25), {},
                 io::TicksAt(0, 1, defect == 2 ? 1.5 : 0.25), {});
    if (defect == 0) canvas.Text(100, 100, "thumb"), canvas.Text(105, 100, "index");
    if (defect == 1)
      canvas.Text(10, 20, "Plan: INFEASIBLE \u2014 a title far longer than the canvas is wide");
    return canvas.Finish();
  };
  ExpectLegible(picture(-1), "the base");
  EXPECT_NONFATAL_FAILURE(ExpectLegible(picture(0), "control"), "\"thumb\" overlaps \"index\"");
  EXPECT_NONFATAL_FAILURE(ExpectLegible(picture(1), "control"), "outside the 300 x 200 canvas");
  EXPECT_NONFATAL_FAILURE(ExpectLegible(picture(2), "control"), "an axis with 1 tick labels");
}

// ---- Plan and trajectory ---------------------------------------------------------

const char* const kNames[] = {"thumb", "index", "middle", "ring"};

// `n` contacts on a sphere of radius r, pointing inward; the first two are
// opposite on the x axis (seen from x they coincide: both labels at one point).
// max_force (N, 0: none) bounds every normal force: a small one makes the plan infeasible.
v1::PlanRequest DrawnPlan(std::mt19937& rng, int n, double mass, double max_force = 0) {
  std::uniform_real_distribution<double> unit(-1, 1), r(0.015, 0.08), mu(0.3, 1.0);
  const double radius = r(rng);
  std::string contacts;
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d d = i < 2 ? Eigen::Vector3d(i == 0 ? 1 : -1, 0, 0)
                              : Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    d.normalize();
    const Eigen::Vector3d p = radius * d;
    contacts += absl::StrFormat(
        "%s{\"name\": \"%s\", \"position\": {\"x\": %.4f, \"y\": %.4f, \"z\": %.4f}, "
        "\"normal\": {\"x\": %.4f, \"y\": %.4f, \"z\": %.4f}, \"friction\": %.2f, \"sigma\": 0.2, "
        "\"max_normal_force\": %g}",
        i ? ", " : "", kNames[i], p.x(), p.y(), p.z(), -d.x(), -d.y(), -d.z(), mu(rng), max_force);
  }
  const std::string json =
      absl::StrFormat("{\"object\": {\"mass\": %.3f}, \"contacts\": [%s]}", mass, contacts);
  absl::StatusOr<v1::PlanRequest> request = api::ParsePlanRequestJson(json);
  EXPECT_TRUE(request.ok()) << request.status();
  return request.ok() ? *request : v1::PlanRequest();
}

TEST(PlotLegibility, PlanPlotsOfDrawnGraspsIncludingInfeasibleOnes) {
  std::mt19937 rng(2501);
  std::uniform_int_distribution<int> contacts(2, 4);
  std::uniform_real_distribution<double> mass(0.02, 0.5);
  int infeasible = 0;
  for (int trial = 0; trial < 8; ++trial) {
    // Every third cannot hold its weight within 0.05 N per contact: an infeasible plan with a long
    // message.
    const v1::PlanRequest request =
        DrawnPlan(rng, contacts(rng), mass(rng), trial % 3 == 2 ? 0.05 : 0);
    absl::StatusOr<v1::PlanResponse> response = api::HandlePlan(request);
    ASSERT_TRUE(response.ok()) << response.status();
    infeasible += response->status() != v1::PLAN_STATUS_OPTIMAL;
    absl::StatusOr<std::string> svg =
        api::PlanSvg(request, *response, "client/examples/a_drawn_request.json");
    ASSERT_TRUE(svg.ok()) << svg.status();
    ExpectLegible(*svg, absl::StrFormat("plan %d", trial));
    EXPECT_NE(svg->find("source: client/examples/a_drawn_request.json"), std::string::npos);
  }
  EXPECT_GE(infeasible, 1) << "the infeasible case was drawn";
}

TEST(PlotLegibility, TrajectoryPlotsOfDrawnTilts) {
  std::mt19937 rng(2502);
  std::uniform_int_distribution<int> steps(1, 9);
  std::uniform_real_distribution<double> tilt(0.05, 0.8);
  for (int trial = 0; trial < 3; ++trial) {
    v1::TrajectoryRequest request;
    *request.mutable_plan() = DrawnPlan(rng, 3, 0.1);
    request.mutable_plan()->mutable_object()->mutable_inertia()->set_ixx(4e-4);
    request.mutable_plan()->mutable_object()->mutable_inertia()->set_iyy(4e-4);
    request.mutable_plan()->mutable_object()->mutable_inertia()->set_izz(4e-4);
    const int n = steps(rng);
    const double max_tilt = tilt(rng);
    for (int k = 0; k < n; ++k) {
      const double a = max_tilt * k / std::max(1, n - 1);
      v1::TrajectoryStep* step = request.add_steps();
      step->mutable_gravity()->set_y(-9.81 * std::sin(a));
      step->mutable_gravity()->set_z(-9.81 * std::cos(a));
    }
    absl::StatusOr<v1::TrajectoryResponse> response = api::HandleTrajectory(request);
    ASSERT_TRUE(response.ok()) << response.status();
    absl::StatusOr<std::string> svg =
        api::TrajectorySvg(request, *response, "drawn_trajectory.json");
    ASSERT_TRUE(svg.ok()) << svg.status();
    ExpectLegible(*svg, absl::StrFormat("trajectory %d (%d steps)", trial, n));
  }
}

// ---- Density ------------------------------------------------------------------------

// A closed box of half-sizes h (m), outward triangles.
io::TriangleMesh Box(const Eigen::Vector3d& h) {
  io::TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

TEST(PlotLegibility, DensityPlotsOfDrawnBoxesLongAndShort) {
  std::mt19937 rng(2503);
  std::uniform_real_distribution<double> log_size(std::log(0.004), std::log(0.15)), unit(-1, 1),
      rho(200, 9000);
  for (int trial = 0; trial < 6; ++trial) {
    const Eigen::Vector3d h(std::exp(log_size(rng)), std::exp(log_size(rng)),
                            std::exp(log_size(rng)));
    const io::TriangleMesh mesh = Box(h);
    inertia::InertiaFit fit;
    fit.method = inertia::InertiaMethod::kDensity;
    fit.params.mass = 0.3;
    fit.params.com = 0.2 * h.cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
    absl::StatusOr<inertia::RegionModel> regions =
        inertia::BuildRegions(mesh, {.scheme = inertia::RegionScheme::kGrid, .target_regions = 4});
    ASSERT_TRUE(regions.ok()) << regions.status();
    const bool one_density =
        trial % 2 == 0;  // a single-colour box: only the outlines show its regions
    const double common = rho(rng);
    for (size_t r = 0; r < regions->regions.size(); ++r)
      fit.densities.push_back({absl::StrCat("cell ", r), one_density ? common : rho(rng), 0, 0});
    fit.region_model = std::make_shared<const inertia::RegionModel>(*std::move(regions));
    inertia::DensityPlotOptions options{
        .title = "box.stl: DENSITY fit",
        .true_com = Eigen::Vector3d(fit.params.com),  // coincident markers
        .source = "--csv drawn.csv --mesh box.stl"};
    absl::StatusOr<std::string> svg = inertia::DensityPlotSvg(mesh, fit, options);
    ASSERT_TRUE(svg.ok()) << svg.status();
    const std::string what = absl::StrFormat("density %d (%.0f x %.0f x %.0f mm)", trial,
                                             2000 * h.x(), 2000 * h.y(), 2000 * h.z());
    ExpectLegible(*svg, what);
    if (fit.densities.size() > 1)
      EXPECT_NE(svg->find("class=\"region-outline\""), std::string::npos) << what;
    EXPECT_NE(svg->find("class=\"true-com\""), std::string::npos);
    const Parsed p = Parse(*svg);
    EXPECT_LE(p.width / p.height, 3.0) << what << ": not a strip";
  }
}

// ---- Audit and experiment -----------------------------------------------------------

TEST(PlotLegibility, AuditPlotsOfADrawnSensorLog) {
  std::mt19937 rng(2504);
  std::normal_distribution<double> noise(0, 0.02);
  audit::MeasuredData data;
  data.source = "drawn_run.csv";
  double state = 0;
  for (int i = 0; i < 2000; ++i) {
    const double t = 0.005 * i, f = 4 + 3.5 * std::sin(0.9 * t) * std::sin(0.13 * t + 0.4);
    state += 0.05 * (f - state);  // a lag the nominal model does not have
    data.t.push_back(t);
    data.reference.push_back(f);
    data.reading.push_back(0.9 * f + 0.1 * state + noise(rng));
    data.trial.push_back(0);
  }
  data.segment_starts = {0};
  audit::AuditOptions options;
  options.downstream_gain = false;
  absl::StatusOr<audit::AuditReport> report = audit::RunAudit(data, options);
  ASSERT_TRUE(report.ok()) << report.status();
  const tactforce::testing::TempDir temp("tactforce_plot_legibility_audit");
  const std::filesystem::path dir = temp.path();
  ASSERT_TRUE(audit::WriteAuditReport(*report, dir.string(), "drawn_run.csv").ok());
  for (const char* name :
       {"reading_vs_reference.svg", "residual_vs_reference.svg", "residual_vs_time.svg"}) {
    std::ifstream in(dir / name);
    std::stringstream svg;
    svg << in.rdbuf();
    ExpectLegible(svg.str(), name);
    EXPECT_NE(svg.str().find("source: drawn_run.csv"), std::string::npos) << name;
  }
  std::filesystem::remove_all(dir);
}

TEST(PlotLegibility, ExperimentTracePlotOfADrawnTrial) {
  std::mt19937 rng(2505);
  std::normal_distribution<double> noise(0, 0.05);
  experiment::TrialResult trial;
  const experiment::Phase phases[] = {experiment::Phase::kClose, experiment::Phase::kSettle,
                                      experiment::Phase::kHold, experiment::Phase::kLift};
  for (int k = 0; k < 800; ++k) {
    experiment::TraceSample s;
    s.t = 0.005 * k;
    s.phase =
        phases[std::min(3, k / 60)];  // phase changes close together: their labels must not collide
    for (int f = 0; f < 3; ++f) {
      const double want = 1 + f;
      s.desired.push_back(want);
      s.truth.push_back(want * (k > 40) + noise(rng));
      s.raw.push_back(0.8 * want * (k > 40) + noise(rng));
      s.estimated.push_back(want * (k > 40) + 0.5 * noise(rng));
    }
    s.slip = k > 200 ? 1e-4 * (k - 200) / 600 : 0;
    s.rotation_deg = k > 200 ? 0.4 * (k - 200) / 600 : 0;
    trial.trace.push_back(s);
  }
  const io::SvgPlot plot =
      experiment::TracePlot(trial, {"index", "middle", "thumb"},
                            "wrench, estimated feedback, trial 0 (success): desired / estimated / "
                            "raw / true normal force, a title long "
                            "enough to need shortening on a 900 px canvas");
  for (const io::SvgPanel& panel : plot.panels) {
    EXPECT_EQ(panel.y_label.find(','), std::string::npos) << "one unit per axis: " << panel.y_label;
  }
  ExpectLegible(io::RenderSvg(plot), "experiment trace");
}

}  // namespace
}  // namespace tactforce
