// client/python/plan_client.py (python3 + the stubs generated into
// <build>/python) against the live server.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tactforce/api/convert.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/json.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/simulate.h"
#include "test_support.h"

namespace tactforce::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class PythonClientTest : public ServerTest {
 protected:
  ProcessResult Python(std::vector<std::string> args, const char* script = "client/python/plan_client.py") {
    std::vector<std::string> argv = {TACTFORCE_PYTHON3, (SourceDir() / script).string()};
    argv.insert(argv.end(), args.begin(), args.end());
    return RunProcess(argv, {std::string("PYTHONPATH=") + TACTFORCE_PYTHON_STUB_DIR});
  }
};

TEST_F(PythonClientTest, PlansTheWrenchGraspLikeTheCppClient) {
  ASSERT_TRUE(fs::exists(fs::path(TACTFORCE_PYTHON_STUB_DIR) / "tactforce/v1/planner_pb2_grpc.py"))
      << "Python stubs not generated (target tactforce_python_stubs)";
  ProcessResult run = Python({"--server", server_->address(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::PlanResponse from_python;
  absl::Status parsed = api::ParseJson(run.out, &from_python);
  ASSERT_TRUE(parsed.ok()) << parsed << "\n" << run.out;

  v1::PlanResponse from_cpp;
  ASSERT_TRUE(CallPlan(*stub_, WrenchRequest(), &from_cpp).ok());
  EXPECT_EQ(from_python.status(), v1::PLAN_STATUS_OPTIMAL);
  ASSERT_EQ(from_python.forces_size(), 3);
  for (int i = 0; i < 3; ++i) {
    EXPECT_DOUBLE_EQ(from_python.forces(i).x(), from_cpp.forces(i).x());
    EXPECT_DOUBLE_EQ(from_python.forces(i).y(), from_cpp.forces(i).y());
    EXPECT_DOUBLE_EQ(from_python.forces(i).z(), from_cpp.forces(i).z());
  }
}

TEST_F(PythonClientTest, PlansAJsonFileOverAStreamAndPrintsATable) {
  const fs::path example = SourceDir() / "client/examples/sphere_pinch.json";
  ProcessResult run = Python({"--server", server_->address(), "--request", example.string(), "--solver",
                    "ipopt", "--stream"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr("status: OPTIMAL"));
  EXPECT_THAT(run.out, HasSubstr("solver: IPOPT"));
  EXPECT_THAT(run.out, HasSubstr("\nthumb "));
  EXPECT_THAT(run.out, HasSubstr("\nindex "));
}

TEST_F(PythonClientTest, ReportsInvalidRequestsAndUnreachableServers) {
  std::string pattern = (fs::temp_directory_path() / "tactforce_py.XXXXXX").string();
  ASSERT_NE(mkdtemp(pattern.data()), nullptr);
  const fs::path bad = fs::path(pattern) / "bad.json";
  std::ofstream(bad) << R"({"object": {"mass": 0.1}, "contacts": [{"normal": {}}]})";
  ProcessResult run = Python({"--server", server_->address(), "--request", bad.string()});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("INVALID_ARGUMENT: contacts[0].normal: zero length"));
  fs::remove_all(pattern);

  const std::string address = server_->address();
  // Close our idle connection first: an idle C-core client answers the
  // server's GOAWAY ping only at its next backup poll (up to 5 s), which the
  // drain would wait for.
  stub_.reset();
  channel_.reset();
  ASSERT_EQ(server_->Stop(), 0);
  server_.reset();
  run = Python({"--server", address, "--timeout", "2"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.err, HasSubstr("UNAVAILABLE"));
}

// client/python/inertia_client.py streams a CSV to Estimator.FitInertia in
// batches; its answer equals the in-process fit of the same file, and a bad
// row is reported with its line before anything wrong reaches the server.
TEST_F(PythonClientTest, StreamsAnInertiaCsvLikeTheCppFit) {
  std::string pattern = (fs::temp_directory_path() / "tactforce_py.XXXXXX").string();
  ASSERT_NE(mkdtemp(pattern.data()), nullptr);
  inertia::SimulationOptions o;
  o.duration = 3.0;
  o.noise.force_sigma = 0.3;
  o.seed = 5;
  absl::StatusOr<inertia::SimulationResult> sim = inertia::SimulateInertia(o);
  ASSERT_TRUE(sim.ok()) << sim.status();
  const std::string csv = pattern + "/log.csv", truth = pattern + "/truth.json";
  ASSERT_TRUE(inertia::WriteSimulation(*sim, csv, truth).ok());

  ProcessResult run = Python({"--server", server_->address(), "--csv", csv, "--truth", truth, "--method",
                              "factor-graph", "--batch", "64", "--json"},
                             "client/python/inertia_client.py");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::FitInertiaResponse from_python;
  absl::Status parsed = api::ParseJson(run.out, &from_python);
  ASSERT_TRUE(parsed.ok()) << parsed << "\n" << run.out;

  absl::StatusOr<inertia::InertiaSamples> samples = inertia::ReadInertiaCsvFile(csv);
  ASSERT_TRUE(samples.ok()) << samples.status();
  v1::InertiaFitOptions options;
  options.set_method(v1::INERTIA_METHOD_FACTOR_GRAPH);
  *options.mutable_truth() = api::InertialParametersToProto(sim->truth.params);
  *options.mutable_gravity() = api::ToProto(*sim->truth.gravity_world);
  absl::StatusOr<v1::FitInertiaResponse> local = api::FitInertiaSamples(*samples, options);
  ASSERT_TRUE(local.ok()) << local.status();
  EXPECT_EQ(from_python.samples_received(), local->samples_received());
  EXPECT_DOUBLE_EQ(from_python.mass(), local->mass());
  EXPECT_DOUBLE_EQ(from_python.inertia().ixy(), local->inertia().ixy());
  EXPECT_DOUBLE_EQ(from_python.errors().riemannian(), local->errors().riemannian());

  std::ofstream(pattern + "/bad.csv") << "t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz\n0,0,0,0,1,0,0,0,0,0,1,0,0,0\n"
                                         "0.1,0,zero,0,1,0,0,0,0,0,1,0,0,0\n";
  run = Python({"--server", server_->address(), "--csv", pattern + "/bad.csv"}, "client/python/inertia_client.py");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("bad.csv:3: column 'py': not a number"));
  fs::remove_all(pattern);
}

}  // namespace
}  // namespace tactforce::testing
