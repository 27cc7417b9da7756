// Estimator.FitInertia over the real server: a client stream of sample
// batches gives the same answer as the in-process fit; a bad sample in a
// later message ends the call with INVALID_ARGUMENT naming it; options
// after the first message are rejected. A DENSITY fit with the object's
// mesh in the first message equals the local one (raw stubs and the CLI's
// --server path); a mesh over --max-message-bytes is refused with a clear
// error and the server keeps serving.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>

#include "absl/strings/str_format.h"
#include "inertia/test_util.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/json.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/v1/estimator.grpc.pb.h"
#include "request_builders.h"
#include "test_support.h"
#include "support/temp_dir.h"

namespace tactforce::testing {
namespace {

using InertiaRpcTest = ServerTest;

inertia::SimulationResult Simulated(double force_variance) {
  inertia::SimulationOptions o;
  o.duration = 4.0;
  o.rate_hz = 100.0;
  o.noise.force_sigma = std::sqrt(force_variance);
  o.seed = 7;
  absl::StatusOr<inertia::SimulationResult> r = inertia::SimulateInertia(o);
  EXPECT_TRUE(r.ok()) << r.status();
  return *r;
}

TEST_F(InertiaRpcTest, StreamedFitEqualsInProcessFit) {
  const inertia::SimulationResult sim = Simulated(0.1);
  auto stub = v1::Estimator::NewStub(channel_);
  for (v1::InertiaMethod method : {v1::INERTIA_METHOD_BASELINE_LS, v1::INERTIA_METHOD_FACTOR_GRAPH,
                                   v1::INERTIA_METHOD_CONSTRAINED}) {
    v1::InertiaFitOptions options;
    options.set_method(method);
    *options.mutable_truth() = api::InertialParametersToProto(sim.truth.params);
    v1::FitInertiaResponse remote;
    const grpc::Status status = StreamInertia(*stub, sim.samples, options, 64, &remote);
    ASSERT_TRUE(status.ok()) << status.error_message();
    absl::StatusOr<v1::FitInertiaResponse> local = api::FitInertiaSamples(sim.samples, options);
    ASSERT_TRUE(local.ok()) << local.status();
    EXPECT_EQ(remote.method(), method);
    EXPECT_EQ(remote.samples_received(), static_cast<int>(sim.samples.samples.size()));
    // Same computation, same thread-independent arithmetic: equal results.
    EXPECT_DOUBLE_EQ(remote.mass(), local->mass());
    EXPECT_DOUBLE_EQ(remote.com().y(), local->com().y());
    EXPECT_DOUBLE_EQ(remote.inertia().ixy(), local->inertia().ixy());
    EXPECT_EQ(remote.physically_consistent(), local->physically_consistent());
    ASSERT_TRUE(remote.has_errors());
    EXPECT_DOUBLE_EQ(remote.errors().paper_metric(), local->errors().paper_metric());
    EXPECT_LT(remote.errors().mass_percent(), 5.0) << v1::InertiaMethod_Name(method);
  }
}

TEST_F(InertiaRpcTest, BadSampleInALaterMessageIsNamed) {
  const inertia::SimulationResult sim = Simulated(0.0);
  auto stub = v1::Estimator::NewStub(channel_);
  v1::FitInertiaResponse response;
  const grpc::Status status =
      StreamInertia(*stub, sim.samples, v1::InertiaFitOptions(), 50, &response, 137);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("samples[137].orientation"), std::string::npos)
      << status.error_message();
}

TEST_F(InertiaRpcTest, OptionsOnlyInTheFirstMessage) {
  const inertia::SimulationResult sim = Simulated(0.0);
  auto stub = v1::Estimator::NewStub(channel_);
  v1::FitInertiaResponse response;
  const grpc::Status status = StreamInertia(*stub, sim.samples, v1::InertiaFitOptions(), 100,
                                            &response, -1, /*options_twice=*/true);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("options: only the first message"), std::string::npos)
      << status.error_message();
}

TEST_F(InertiaRpcTest, EmptyStreamAndBadOptionsAreInvalidArgument) {
  auto stub = v1::Estimator::NewStub(channel_);
  {
    grpc::ClientContext context;
    v1::FitInertiaResponse response;
    auto writer = stub->FitInertia(&context, &response);
    writer->WritesDone();
    const grpc::Status status = writer->Finish();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(status.error_message().find("no samples"), std::string::npos)
        << status.error_message();
  }
  const inertia::SimulationResult sim = Simulated(0.0);
  v1::InertiaFitOptions options;
  options.mutable_noise()->set_force_sigma(-1.0);
  v1::FitInertiaResponse response;
  const grpc::Status status = StreamInertia(*stub, sim.samples, options, 200, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("options.noise.force_sigma"), std::string::npos)
      << status.error_message();
}

class InertiaRpcLimitTest : public ServerTest {
 protected:
  std::vector<std::string> server_flags() const override { return {"--max-inertia-samples", "50"}; }
};

TEST_F(InertiaRpcLimitTest, StreamBeyondTheServersSampleLimitIsRejected) {
  const inertia::SimulationResult sim = Simulated(0.0);
  auto stub = v1::Estimator::NewStub(channel_);
  v1::FitInertiaResponse response;
  const grpc::Status status =
      StreamInertia(*stub, sim.samples, v1::InertiaFitOptions(), 20, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("more than 50 samples"), std::string::npos)
      << status.error_message();
}

// ------------------------------------------------------------ meshes

namespace fs = std::filesystem;

// The simulated object's mesh as a Wavefront OBJ (object frame, m), padded
// with comment lines to at least `min_bytes`.
std::string ObjText(const io::TriangleMesh& mesh, size_t min_bytes = 0) {
  std::string out = "# tactforce test mesh\n";
  for (const inertia::Vec3& v : mesh.vertices)
    out += absl::StrFormat("v %.17g %.17g %.17g\n", v.x(), v.y(), v.z());
  for (const auto& t : mesh.triangles)
    out += absl::StrFormat("f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
  while (out.size() < min_bytes)
    out += "# padding padding padding padding padding padding padding padding\n";
  return out;
}

inertia::SimulationResult SimulatedBox() {
  inertia::SimulationOptions o;
  o.object = "box";
  o.mode = inertia::SimulationMode::kWristWrench;
  o.duration = 3.0;
  o.write_kinematics = true;
  o.noise = *inertia::NadeauNoise("low");
  o.seed = 11;
  absl::StatusOr<inertia::SimulationResult> r = inertia::SimulateInertia(o);
  EXPECT_TRUE(r.ok()) << r.status();
  return *r;
}

v1::InertiaFitOptions DensityOptions(const inertia::SimulationResult& sim, size_t min_bytes = 0) {
  v1::InertiaFitOptions options;
  options.set_method(v1::INERTIA_METHOD_DENSITY);
  options.mutable_mesh()->set_data(ObjText(sim.object.mesh, min_bytes));
  options.mutable_mesh()->set_format("obj");
  options.mutable_mesh()->set_name("box.obj");
  options.set_regions(v1::REGION_SCHEME_GRID);
  options.set_target_regions(8);
  *options.mutable_truth() = api::InertialParametersToProto(sim.truth.params);
  return options;
}

void ExpectSameFit(const v1::FitInertiaResponse& a, const v1::FitInertiaResponse& b, double rel) {
  auto near = [rel](double x, double y, const char* what) {
    EXPECT_LE(std::abs(x - y), rel * std::max({std::abs(x), std::abs(y), 1e-300}))
        << what << ": " << x << " vs " << y;
  };
  EXPECT_EQ(a.method(), b.method());
  near(a.mass(), b.mass(), "mass");
  near(a.com().x(), b.com().x(), "com.x");
  near(a.com().y(), b.com().y(), "com.y");
  near(a.com().z(), b.com().z(), "com.z");
  near(a.inertia().ixx(), b.inertia().ixx(), "ixx");
  near(a.inertia().iyy(), b.inertia().iyy(), "iyy");
  near(a.inertia().izz(), b.inertia().izz(), "izz");
  near(a.inertia().ixy(), b.inertia().ixy(), "ixy");
  near(a.inertia().ixz(), b.inertia().ixz(), "ixz");
  near(a.inertia().iyz(), b.inertia().iyz(), "iyz");
  EXPECT_EQ(a.density_realizable(), b.density_realizable());
  EXPECT_EQ(a.mesh_contradicted(), b.mesh_contradicted());
  ASSERT_EQ(a.densities_size(), b.densities_size());
  for (int i = 0; i < a.densities_size(); ++i) {
    EXPECT_EQ(a.densities(i).label(), b.densities(i).label());
    near(a.densities(i).density(), b.densities(i).density(), "density");
    near(a.densities(i).volume(), b.densities(i).volume(), "volume");
  }
  EXPECT_EQ(a.mesh_check().faces(), b.mesh_check().faces());
  near(a.mesh_check().volume(), b.mesh_check().volume(), "mesh volume");
  EXPECT_EQ(a.density_regularization(), b.density_regularization());
}

TEST_F(InertiaRpcTest, DensityFitWithTheMeshInTheFirstMessageEqualsTheLocalFit) {
  const inertia::SimulationResult sim = SimulatedBox();
  auto stub = v1::Estimator::NewStub(channel_);
  const v1::InertiaFitOptions options = DensityOptions(sim);
  v1::FitInertiaResponse remote;
  const grpc::Status status = StreamInertia(*stub, sim.samples, options, 100, &remote);
  ASSERT_TRUE(status.ok()) << status.error_message();
  absl::StatusOr<v1::FitInertiaResponse> local = api::FitInertiaSamples(sim.samples, options);
  ASSERT_TRUE(local.ok()) << local.status();
  EXPECT_EQ(remote.method(), v1::INERTIA_METHOD_DENSITY);
  EXPECT_TRUE(remote.density_realizable());
  EXPECT_GE(remote.densities_size(), 2);
  EXPECT_TRUE(remote.mesh_check().closed());
  ExpectSameFit(remote, *local, 0.0);  // same computation: equal
  ASSERT_TRUE(remote.has_errors());
  EXPECT_LT(remote.errors().mass_percent(), 0.5);

  // A bad placement is INVALID_ARGUMENT naming the field; the call ends.
  v1::InertiaFitOptions bad = options;
  bad.mutable_mesh()->set_scale(-1);
  const grpc::Status rejected = StreamInertia(*stub, sim.samples, bad, 100, &remote);
  EXPECT_EQ(rejected.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(rejected.error_message(), "options.mesh.scale: must be > 0 (got -1)");
  bad = options;
  bad.mutable_mesh()->set_data("solid nothing\nendsolid nothing\n");
  bad.mutable_mesh()->set_format("stl");
  bad.mutable_mesh()->set_name("empty.stl");
  const grpc::Status unreadable = StreamInertia(*stub, sim.samples, bad, 100, &remote);
  EXPECT_EQ(unreadable.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(unreadable.error_message().find("options.mesh: empty.stl"), std::string::npos)
      << unreadable.error_message();
}

// `tactforce inertia --mesh DESCRIPTOR --server` sends the file's bytes and
// the descriptor's placement: the server's answer equals the local one.
TEST_F(InertiaRpcTest, CliSendsTheSameMeshAsItFitsLocally) {
  const auto shared = inertia::testing::SharedInertiaDir();
  if (!shared) GTEST_SKIP() << "../shared/data/inertia is absent";
  const std::vector<std::string> fit = {
      BinaryPath("tactforce").string(), "inertia", "--csv", *shared + "/Pliers.csv", "--mesh",
      *shared + "/Pliers.mesh.json",    "--json"};
  const ProcessResult local = RunProcess(fit, {}, std::chrono::seconds(120));
  ASSERT_EQ(local.exit_code, 0) << local.err;
  std::vector<std::string> remote_args = fit;
  remote_args.insert(remote_args.end(), {"--server", server_->address(), "--batch", "128"});
  const ProcessResult remote = RunProcess(remote_args, {}, std::chrono::seconds(120));
  ASSERT_EQ(remote.exit_code, 0) << remote.err;
  v1::FitInertiaResponse a, b;
  ASSERT_TRUE(api::ParseJson(local.out, &a).ok()) << local.out.substr(0, 300);
  ASSERT_TRUE(api::ParseJson(remote.out, &b).ok()) << remote.out.substr(0, 300);
  EXPECT_EQ(a.method(), v1::INERTIA_METHOD_DENSITY);
  EXPECT_TRUE(a.density_realizable());
  EXPECT_GT(a.densities_size(), 0);
  ExpectSameFit(a, b, 1e-9);
}

class InertiaRpcMessageLimitTest : public ServerTest {
 protected:
  std::vector<std::string> server_flags() const override {
    return {"--max-message-bytes", "65536"};
  }
};

// A first message over --max-message-bytes (the mesh makes it big) ends
// that call with RESOURCE_EXHAUSTED naming the limit; the next call on the
// same channel is served. The CLI adds which flag raises the limit.
TEST_F(InertiaRpcMessageLimitTest, OversizeMeshIsRefusedAndTheServerKeepsServing) {
  const inertia::SimulationResult sim = SimulatedBox();
  auto stub = v1::Estimator::NewStub(channel_);
  v1::FitInertiaResponse response;
  const grpc::Status refused =
      StreamInertia(*stub, sim.samples, DensityOptions(sim, 100'000), 20, &response);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << refused.error_message();
  EXPECT_NE(refused.error_message().find("65536"), std::string::npos) << refused.error_message();

  const grpc::Status served = StreamInertia(*stub, sim.samples, DensityOptions(sim), 20, &response);
  ASSERT_TRUE(served.ok()) << served.error_message();
  EXPECT_TRUE(response.density_realizable());

  // The CLI: the same refusal, with the flag to raise; exit code 1.
  const TempDir temp("tactforce_mesh");
  const std::string pattern = temp.path().string();
  ASSERT_FALSE(pattern.empty());
  ASSERT_TRUE(inertia::WriteSimulation(sim, pattern + "/log.csv", pattern + "/truth.json").ok());
  std::ofstream(pattern + "/big.obj") << ObjText(sim.object.mesh, 100'000);
  const ProcessResult cli =
      RunProcess({BinaryPath("tactforce").string(), "inertia", "--csv", pattern + "/log.csv",
                  "--mesh", pattern + "/big.obj", "--server", server_->address()});
  EXPECT_EQ(cli.exit_code, 1) << cli.err;
  EXPECT_NE(cli.err.find("RESOURCE_EXHAUSTED"), std::string::npos) << cli.err;
  EXPECT_NE(cli.err.find("65536"), std::string::npos) << cli.err;
  EXPECT_NE(cli.err.find("--max-message-bytes"), std::string::npos) << cli.err;
  EXPECT_NE(cli.err.find("big.obj"), std::string::npos) << cli.err;

  const grpc::Status again = StreamInertia(*stub, sim.samples, DensityOptions(sim), 50, &response);
  EXPECT_TRUE(again.ok()) << again.error_message();
}

}  // namespace
}  // namespace tactforce::testing
