// client/python/plan_client.py and inertia_client.py (python3 + the
// tactforce package assembled in <build>/python by tactforce_python_stubs)
// against the live server; exit codes are those of the `tactforce` CLI.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_format.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/json.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/simulate.h"
#include "support/temp_dir.h"
#include "test_support.h"

namespace tactforce::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class PythonClientTest : public ServerTest {
 protected:
  ProcessResult Python(std::vector<std::string> args,
                       const char* script = "client/python/plan_client.py") {
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
  ProcessResult run = Python({"--server", server_->address(), "--request", example.string(),
                              "--solver", "ipopt", "--stream"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr("status: OPTIMAL"));
  EXPECT_THAT(run.out, HasSubstr("solver: IPOPT"));
  EXPECT_THAT(run.out, HasSubstr("\nthumb "));
  EXPECT_THAT(run.out, HasSubstr("\nindex "));
}

TEST_F(PythonClientTest, ReportsInvalidRequestsAndUnreachableServers) {
  const TempDir temp("tactforce_py");
  const std::string pattern = temp.path().string();
  ASSERT_FALSE(pattern.empty());
  const fs::path bad = fs::path(pattern) / "bad.json";
  std::ofstream(bad) << R"({"object": {"mass": 0.1}, "contacts": [{"normal": {}}]})";
  ProcessResult run = Python({"--server", server_->address(), "--request", bad.string()});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("INVALID_ARGUMENT: contacts[0].normal: zero length"));

  const std::string address = server_->address();
  // Close our idle connection first: an idle C-core client answers the
  // server's GOAWAY ping only at its next backup poll (up to 5 s), which the
  // drain would wait for.
  stub_.reset();
  channel_.reset();
  ASSERT_EQ(server_->Stop(), 0);
  server_.reset();
  run = Python({"--server", address, "--timeout", "2"});
  EXPECT_EQ(run.exit_code, 3);  // the CLI's "unavailable"
  EXPECT_THAT(run.err, HasSubstr("UNAVAILABLE"));
}

// The build tree's grpc.health.v1 stubs live in tactforce.health.v1: no
// grpc/ folder in <build>/python shadows the real grpc package, and both
// import in one interpreter and check the server's health.
TEST_F(PythonClientTest, HealthStubsImportBesideTheRealGrpc) {
  EXPECT_FALSE(fs::exists(fs::path(TACTFORCE_PYTHON_STUB_DIR) / "grpc"));
  const std::string script =
      "import sys, grpc\n"
      "from tactforce.health.v1 import health_pb2, health_pb2_grpc\n"
      "channel = grpc.insecure_channel(sys.argv[1])\n"
      "reply = health_pb2_grpc.HealthStub(channel).Check(health_pb2.HealthCheckRequest(), "
      "timeout=10)\n"
      "print(health_pb2.HealthCheckResponse.ServingStatus.Name(reply.status), grpc.__file__)\n";
  ProcessResult run = RunProcess({TACTFORCE_PYTHON3, "-c", script, server_->address()},
                                 {std::string("PYTHONPATH=") + TACTFORCE_PYTHON_STUB_DIR});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, ::testing::StartsWith("SERVING "));
  EXPECT_THAT(run.out, ::testing::Not(HasSubstr(TACTFORCE_PYTHON_STUB_DIR)));  // the real grpc
}

// client/python/inertia_client.py streams a CSV to Estimator.FitInertia in
// batches; its answer equals the in-process fit of the same file, and a bad
// row is reported with its line before anything wrong reaches the server.
TEST_F(PythonClientTest, StreamsAnInertiaCsvLikeTheCppFit) {
  const TempDir temp("tactforce_py");
  const std::string pattern = temp.path().string();
  ASSERT_FALSE(pattern.empty());
  inertia::SimulationOptions o;
  o.duration = 3.0;
  o.noise.force_sigma = 0.3;
  o.seed = 5;
  absl::StatusOr<inertia::SimulationResult> sim = inertia::SimulateInertia(o);
  ASSERT_TRUE(sim.ok()) << sim.status();
  const std::string csv = pattern + "/log.csv", truth = pattern + "/truth.json";
  ASSERT_TRUE(inertia::WriteSimulation(*sim, csv, truth).ok());

  ProcessResult run = Python({"--server", server_->address(), "--csv", csv, "--truth", truth,
                              "--method", "factor-graph", "--batch", "64", "--json"},
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

  std::ofstream(pattern + "/bad.csv")
      << "t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz\n0,0,0,0,1,0,0,0,0,0,1,0,0,0\n"
         "0.1,0,zero,0,1,0,0,0,0,0,1,0,0,0\n";
  run = Python({"--server", server_->address(), "--csv", pattern + "/bad.csv"},
               "client/python/inertia_client.py");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("bad.csv:3: column 'py': not a number"));
}

// A Wavefront OBJ of `mesh` with its vertices in millimetres.
std::string ObjInMillimetres(const io::TriangleMesh& mesh) {
  std::string obj;
  for (const inertia::Vec3& v : mesh.vertices)
    obj += absl::StrFormat("v %.17g %.17g %.17g\n", 1000 * v.x(), 1000 * v.y(), 1000 * v.z());
  for (const auto& t : mesh.triangles)
    obj += absl::StrFormat("f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
  return obj;
}

// --mesh: the mesh file's bytes go in the first message (format from the
// extension); the method defaults to density, and the answer equals the
// in-process fit with the same MeshInput. A descriptor JSON carries the
// placement; bad flags are refused before any call.
TEST_F(PythonClientTest, SendsAMeshForADensityFit) {
  const TempDir temp("tactforce_py");
  const std::string pattern = temp.path().string();
  ASSERT_FALSE(pattern.empty());
  inertia::SimulationOptions o;
  o.object = "box";
  o.mode = inertia::SimulationMode::kWristWrench;
  o.duration = 3.0;
  o.write_kinematics = true;
  o.seed = 6;
  absl::StatusOr<inertia::SimulationResult> sim = inertia::SimulateInertia(o);
  ASSERT_TRUE(sim.ok()) << sim.status();
  const std::string csv = pattern + "/log.csv", truth = pattern + "/truth.json";
  ASSERT_TRUE(inertia::WriteSimulation(*sim, csv, truth).ok());
  // The box in millimetres, for --mesh-scale and the descriptor.
  const std::string obj = ObjInMillimetres(sim->object.mesh);
  std::ofstream(pattern + "/box_mm.obj") << obj;
  std::ofstream(pattern + "/box.mesh.json") << R"({"mesh": "box_mm.obj", "scale": 0.001})";

  ProcessResult run =
      Python({"--server", server_->address(), "--csv", csv, "--truth", truth, "--mesh",
              pattern + "/box_mm.obj", "--mesh-scale", "0.001", "--regions", "grid", "--json"},
             "client/python/inertia_client.py");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::FitInertiaResponse from_python;
  absl::Status parsed = api::ParseJson(run.out, &from_python);
  ASSERT_TRUE(parsed.ok()) << parsed << "\n" << run.out;
  EXPECT_EQ(from_python.method(), v1::INERTIA_METHOD_DENSITY);
  EXPECT_TRUE(from_python.density_realizable());
  EXPECT_GE(from_python.densities_size(), 2);
  EXPECT_EQ(from_python.mesh_check().faces(), 12);
  EXPECT_LT(from_python.errors().mass_percent(), 0.1);

  absl::StatusOr<inertia::InertiaSamples> samples = inertia::ReadInertiaCsvFile(csv);
  ASSERT_TRUE(samples.ok()) << samples.status();
  v1::InertiaFitOptions options;
  options.set_method(v1::INERTIA_METHOD_DENSITY);
  options.set_regions(v1::REGION_SCHEME_GRID);
  options.mutable_mesh()->set_data(obj);
  options.mutable_mesh()->set_format("obj");
  options.mutable_mesh()->set_name("box_mm.obj");
  options.mutable_mesh()->set_scale(0.001);
  *options.mutable_truth() = api::InertialParametersToProto(sim->truth.params);
  *options.mutable_gravity() = api::ToProto(*sim->truth.gravity_world);
  absl::StatusOr<v1::FitInertiaResponse> local = api::FitInertiaSamples(*samples, options);
  ASSERT_TRUE(local.ok()) << local.status();
  EXPECT_DOUBLE_EQ(from_python.mass(), local->mass());
  EXPECT_DOUBLE_EQ(from_python.inertia().ixy(), local->inertia().ixy());
  ASSERT_EQ(from_python.densities_size(), local->densities_size());
  EXPECT_DOUBLE_EQ(from_python.densities(0).density(), local->densities(0).density());

  // The descriptor: same mesh, same placement, same answer; text output.
  run = Python({"--server", server_->address(), "--csv", csv, "--mesh", pattern + "/box.mesh.json",
                "--regions", "grid"},
               "client/python/inertia_client.py");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr("density-realizable: yes"));
  EXPECT_THAT(run.out, HasSubstr("kg/m^3"));

  run = Python({"--server", server_->address(), "--csv", csv, "--mesh", pattern + "/box_mm.obj",
                "--mesh-scale", "0"},
               "client/python/inertia_client.py");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("--mesh-scale: must be > 0"));
  std::ofstream(pattern + "/bad.mesh.json") << R"({"mesh": "box_mm.obj", "units": "mm"})";
  run = Python({"--server", server_->address(), "--csv", csv, "--mesh", pattern + "/bad.mesh.json"},
               "client/python/inertia_client.py");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("bad.mesh.json: unknown key 'units'"));
  // An open mesh: the server's check, named by the file.
  std::string open = obj.substr(0, obj.rfind("f "));
  std::ofstream(pattern + "/open.obj") << open;
  run = Python({"--server", server_->address(), "--csv", csv, "--mesh", pattern + "/open.obj"},
               "client/python/inertia_client.py");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("INVALID_ARGUMENT: options.mesh: open.obj: 3 boundary edges"));
}

class PythonClientMessageLimitTest : public PythonClientTest {
 protected:
  std::vector<std::string> server_flags() const override {
    return {"--max-message-bytes", "65536"};
  }
};

// A mesh over the server's message limit: RESOURCE_EXHAUSTED (exit 1) with
// the flag that raises it.
TEST_F(PythonClientMessageLimitTest, OversizeMeshNamesTheServersLimit) {
  const TempDir temp("tactforce_py");
  const std::string pattern = temp.path().string();
  ASSERT_FALSE(pattern.empty());
  inertia::SimulationOptions o;
  o.object = "box";
  o.duration = 2.0;
  absl::StatusOr<inertia::SimulationResult> sim = inertia::SimulateInertia(o);
  ASSERT_TRUE(sim.ok()) << sim.status();
  ASSERT_TRUE(inertia::WriteSimulation(*sim, pattern + "/log.csv", pattern + "/truth.json").ok());
  std::string obj;
  for (const inertia::Vec3& v : sim->object.mesh.vertices)
    obj += absl::StrFormat("v %.17g %.17g %.17g\n", v.x(), v.y(), v.z());
  for (const auto& t : sim->object.mesh.triangles)
    obj += absl::StrFormat("f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
  std::ofstream(pattern + "/box.obj") << obj;
  while (obj.size() < 100'000)
    obj += "# padding padding padding padding padding padding padding padding\n";
  std::ofstream(pattern + "/big.obj") << obj;
  ProcessResult run = Python({"--server", server_->address(), "--csv", pattern + "/log.csv",
                              "--mesh", pattern + "/big.obj"},
                             "client/python/inertia_client.py");
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_THAT(run.err, HasSubstr("RESOURCE_EXHAUSTED"));
  EXPECT_THAT(run.err, HasSubstr("65536"));
  EXPECT_THAT(run.err, HasSubstr("--max-message-bytes"));
  // The server still serves: the small mesh fits.
  run = Python({"--server", server_->address(), "--csv", pattern + "/log.csv", "--mesh",
                pattern + "/box.obj"},
               "client/python/inertia_client.py");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr("density-realizable: yes"));
}

}  // namespace
}  // namespace tactforce::testing
