// `tactforce plan --inertia FIT.json --friction FRICTION.json`: a fit's and a
// friction estimate's JSON, as the CLI writes them, fill the request with
// their uncertainty unchanged (issue 28).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/cli_fixture.h"
#include "tactforce/api/estimates.h"
#include "tactforce/api/json.h"
#include "tactforce/api/services.h"

namespace tactforce {
namespace {

using ::testing::HasSubstr;

constexpr char kPinch[] = R"({
  "object": {"mass": 0.1},
  "contacts": [
    {"name": "thumb", "position": {"x": 0.03}, "normal": {"x": -1}, "friction": 0.8, "sigma": 0.1},
    {"name": "index", "position": {"x": -0.03}, "normal": {"x": 1}, "friction": 0.8, "sigma": 0.1},
    {"name": "middle", "position": {"x": -0.02, "y": 0.02}, "normal": {"x": 0.7071, "y": -0.7071},
     "friction": 0.8, "sigma": 0.1}
  ]
})";

class PlanEstimatesCliTest : public testing::CliTest {
 protected:
  // The fit of the shipped inertia example, as `tactforce inertia --json` writes it.
  std::string FitJson() {
    const std::string csv = testing::SourceDir().string() + "/client/examples/inertia_log.csv";
    const testing::CliRun run = Tactforce({"inertia", "--csv", csv, "--json"});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return run.out;
  }
};

TEST_F(PlanEstimatesCliTest, FitJsonRoundTripsIntoThePlan) {
  const std::string fit_json = FitJson();
  v1::FitInertiaResponse fit;
  ASSERT_TRUE(api::ParseJson(fit_json, &fit).ok());
  ASSERT_EQ(fit.covariance_size(), 100) << "the fit reports its covariance";
  const std::string friction_json = R"({"median": 0.7, "mu_sigma": 0.03, "count": 4})";
  const testing::CliRun run =
      Tactforce({"plan", "--local", "--json", "--request", Write("pinch.json", kPinch).string(),
                 "--inertia", Write("fit.json", fit_json).string(), "--friction",
                 Write("mu.json", friction_json).string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::PlanResponse cli;
  ASSERT_TRUE(api::ParseJson(run.out, &cli).ok()) << run.out;

  // The same request built in-process from the parsed messages: bit-equal answer.
  absl::StatusOr<v1::PlanRequest> request = api::ParsePlanRequestJson(kPinch);
  ASSERT_TRUE(request.ok());
  ASSERT_TRUE(api::ApplyInertiaFit(fit, "--inertia", &*request).ok());
  v1::FrictionResponse mu;
  ASSERT_TRUE(api::ParseJson(friction_json, &mu).ok());
  ASSERT_TRUE(api::ApplyFrictionEstimate(mu, "--friction", &*request).ok());
  for (int k = 0; k < 100; ++k)
    EXPECT_EQ(request->object().uncertainty().covariance(k), fit.covariance(k));
  absl::StatusOr<v1::PlanResponse> local = api::HandlePlan(*request);
  ASSERT_TRUE(local.ok()) << local.status();
  EXPECT_EQ(cli.status(), local->status());
  ASSERT_EQ(cli.forces_size(), local->forces_size());
  for (int i = 0; i < cli.forces_size(); ++i) {
    EXPECT_EQ(cli.forces(i).x(), local->forces(i).x());
    EXPECT_EQ(cli.forces(i).y(), local->forces(i).y());
    EXPECT_EQ(cli.forces(i).z(), local->forces(i).z());
  }
  // The margins name both sources.
  ASSERT_GT(cli.row_margins_size(), 0);
  double parameters = 0.0;
  for (const v1::RowMargin& m : cli.row_margins())
    parameters = std::max(parameters, m.parameters());
  EXPECT_GT(parameters, 0.0);
}

TEST_F(PlanEstimatesCliTest, BadEstimatesAreBadInputNamingTheFlag) {
  const std::string pinch = Write("pinch.json", kPinch).string();
  testing::CliRun run =
      Tactforce({"plan", "--local", "--request", pinch, "--inertia",
                 Write("bad.json", R"({"mass": 0.2, "covariance": [1, 2]})").string()});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("--inertia"));
  EXPECT_EQ(run.out, "");
  run = Tactforce({"plan", "--local", "--request", pinch, "--friction",
                   Write("mu.json", R"({"count": 0})").string()});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("--friction"));
  // A covariance that is not symmetric: the planner names the entry.
  std::string asym = R"({"mass": 0.2, "covariance": [)";
  for (int k = 0; k < 100; ++k)
    asym += (k ? "," : "") + std::string(k == 1 ? "0.5" : (k % 11 == 0 ? "1e-4" : "0"));
  asym += "]}";
  run = Tactforce(
      {"plan", "--local", "--request", pinch, "--inertia", Write("asym.json", asym).string()});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("object.uncertainty.covariance[1]"));
  EXPECT_EQ(run.out, "");
}

TEST_F(PlanEstimatesCliTest, WrongLengthCovarianceInARequestIsNamed) {
  const testing::CliRun run =
      Tactforce({"plan", "--local", "--request", "-"},
                R"({"object": {"mass": 0.1, "uncertainty": {"covariance": [1, 0, 0]}},
      "contacts": [{"position": {"x": 0.03}, "normal": {"x": -1}, "friction": 0.8}]})");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("object.uncertainty.covariance: 3 entries, need 100"));
}

}  // namespace
}  // namespace tactforce
