#include "inertia_command.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "cli_common.h"
#include "grpcpp/grpcpp.h"
#include "progress.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/json.h"
#include "tactforce/io/csv.h"
#include "tactforce/io/mesh.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/density_plot.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/inertia/truth.h"
#include "tactforce/io/json.h"
#include "tactforce/v1/estimator.grpc.pb.h"

namespace tactforce::cli {
namespace {

using inertia::Vec3;

bool IsMeshPath(const std::string& path) {
  const std::string ext = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  return ext == ".stl" || ext == ".obj" || ext == ".ply" || ext == ".json";
}

// Hull vertices from a mesh (.stl/.obj/.ply in the object frame, or a mesh
// descriptor .json) or a CSV with x,y,z columns.
absl::StatusOr<std::vector<Vec3>> ReadHullVertices(const std::string& path) {
  if (IsMeshPath(path)) {
    absl::StatusOr<io::LoadedMesh> mesh = io::LoadMesh(io::MeshRequest(path));
    if (!mesh.ok()) return mesh.status();
    return mesh->mesh.vertices;
  }
  absl::StatusOr<io::CsvTable> table = io::ReadCsvFile(path);
  if (!table.ok()) return table.status();
  if (absl::Status s = table->Require({"x", "y", "z"}); !s.ok()) return s;
  const int ix = table->ColumnIndex("x"), iy = table->ColumnIndex("y"), iz = table->ColumnIndex("z");
  std::vector<Vec3> out;
  for (const std::vector<double>& row : table->rows) out.emplace_back(row[ix], row[iy], row[iz]);
  return out;
}

// One finite number; errors name the flag and the token.
absl::StatusOr<double> ParseNumber(const std::string& token, const std::string& flag) {
  const std::string t(absl::StripAsciiWhitespace(token));
  char* end = nullptr;
  const double x = t.empty() ? 0.0 : std::strtod(t.c_str(), &end);
  if (t.empty() || end != t.c_str() + t.size())
    return absl::InvalidArgumentError(absl::StrCat(flag, ": '", token, "' is not a number"));
  if (!std::isfinite(x)) return absl::InvalidArgumentError(absl::StrCat(flag, ": '", token, "' is not finite"));
  return x;
}

// --mesh-pose x,y,z,qw,qx,qy,qz: the object frame in the mesh frame.
absl::StatusOr<io::MeshPlacement> ParseMeshPose(const std::string& text) {
  const std::vector<std::string> tokens = absl::StrSplit(text, ',');
  if (tokens.size() != 7)
    return absl::InvalidArgumentError(absl::StrCat("--mesh-pose: expected 7 numbers x,y,z,qw,qx,qy,qz (got ",
                                                   tokens.size(), " in '", text, "')"));
  std::array<double, 7> v{};
  for (size_t i = 0; i < 7; ++i) {
    absl::StatusOr<double> x = ParseNumber(tokens[i], "--mesh-pose");
    if (!x.ok()) return x.status();
    v[i] = *x;
  }
  io::MeshPlacement pose;
  pose.position = Vec3(v[0], v[1], v[2]);
  pose.orientation = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
  if (!(pose.orientation.norm() >= 1e-6))
    return absl::InvalidArgumentError(absl::StrCat("--mesh-pose: quaternion qw,qx,qy,qz has norm ",
                                                   pose.orientation.norm(), " (near zero) in '", text, "'"));
  return pose;
}

// The mesh of --mesh [--mesh-scale] [--mesh-pose], loaded and placed in the
// object frame, and the bytes of the mesh file it came from (sent to the
// fit, locally or to the server, with the same placement).
struct FlagMesh {
  io::LoadedMesh loaded;
  std::string bytes;
};

absl::StatusOr<FlagMesh> LoadFlagMesh(const InertiaArgs& args) {
  io::MeshRequest request;
  request.path = args.mesh_path;
  if (!args.mesh_scale.empty()) {
    absl::StatusOr<double> scale = ParseNumber(args.mesh_scale, "--mesh-scale");
    if (!scale.ok()) return scale.status();
    if (!(*scale > 0))
      return absl::InvalidArgumentError(absl::StrCat("--mesh-scale: must be > 0 (got ", args.mesh_scale, ")"));
    request.scale = *scale;
  }
  if (!args.mesh_pose.empty()) {
    absl::StatusOr<io::MeshPlacement> pose = ParseMeshPose(args.mesh_pose);
    if (!pose.ok()) return pose.status();
    request.pose = *pose;
  }
  std::error_code ec;
  if (!std::filesystem::exists(args.mesh_path, ec))
    return absl::InvalidArgumentError(absl::StrCat("--mesh: '", args.mesh_path, "' does not exist"));
  absl::StatusOr<io::LoadedMesh> loaded = io::LoadMesh(request);
  if (!loaded.ok()) return loaded.status();
  absl::StatusOr<std::string> bytes = ReadInput(loaded->mesh_path, "--mesh");
  if (!bytes.ok()) return bytes.status();
  return FlagMesh{*std::move(loaded), *std::move(bytes)};
}

// The FitInertia request options from the flags (and the truth/prior/mesh
// files). `mesh` receives the loaded --mesh.
absl::StatusOr<v1::InertiaFitOptions> BuildOptions(const InertiaArgs& args, std::optional<FlagMesh>* mesh) {
  v1::InertiaFitOptions o;
  const std::string method_name = !args.method.empty() ? args.method
                                  : args.mesh_path.empty() ? "constrained"
                                                           : "density";
  absl::StatusOr<inertia::InertiaMethod> method = inertia::ParseInertiaMethod(method_name);
  if (!method.ok()) return absl::InvalidArgumentError(absl::StrCat("--", method.status().message()));
  o.set_method(api::InertiaMethodToProto(*method));
  if (!args.truth_path.empty()) {
    absl::StatusOr<inertia::InertiaTruth> truth = inertia::ReadTruthJsonFile(args.truth_path);
    if (!truth.ok()) return truth.status();
    *o.mutable_truth() = api::InertialParametersToProto(truth->params);
    if (truth->gravity_world && args.gravity.empty()) *o.mutable_gravity() = api::ToProto(*truth->gravity_world);
  }
  if (!args.gravity.empty()) {
    absl::StatusOr<Eigen::Vector3d> g = ParseVec3(args.gravity, "--gravity");
    if (!g.ok()) return g.status();
    *o.mutable_gravity() = api::ToProto(*g);
  }
  if (!args.hull_path.empty()) {
    absl::StatusOr<std::vector<Vec3>> hull = ReadHullVertices(args.hull_path);
    if (!hull.ok()) return hull.status();
    for (const Vec3& v : *hull) *o.add_hull() = api::ToProto(v);
  }
  if (!args.prior_path.empty()) {
    absl::StatusOr<inertia::InertiaTruth> prior = inertia::ReadTruthJsonFile(args.prior_path);
    if (!prior.ok()) return prior.status();
    *o.mutable_prior()->mutable_params() = api::InertialParametersToProto(prior->params);
    o.mutable_prior()->set_weight(args.prior_weight);
  }
  v1::InertiaNoise* n = o.mutable_noise();
  n->set_force_sigma(args.force_sigma);
  n->set_torque_sigma(args.torque_sigma);
  n->set_position_sigma(args.position_sigma);
  n->set_orientation_sigma(args.orientation_sigma);
  n->set_angular_velocity_sigma(args.angular_velocity_sigma);
  n->set_linear_acceleration_sigma(args.acceleration_sigma);
  n->set_angular_acceleration_sigma(args.angular_acceleration_sigma);
  o.set_savitzky_golay(args.savitzky_golay);
  if (args.max_iterations < 0) return absl::InvalidArgumentError("--max-iterations: must be >= 0");
  o.set_max_iterations(static_cast<uint32_t>(args.max_iterations));

  absl::StatusOr<inertia::RegionScheme> scheme = inertia::ParseRegionScheme(args.regions);
  if (!scheme.ok()) return absl::InvalidArgumentError(absl::StrCat("--regions: ", scheme.status().message()));
  o.set_regions(api::RegionSchemeToProto(*scheme));
  if (args.target_regions < 0 || args.target_regions > 512)
    return absl::InvalidArgumentError(
        absl::StrCat("--target-regions: must be in 1..512, 0 = 12 (got ", args.target_regions, ")"));
  o.set_target_regions(static_cast<uint32_t>(args.target_regions));
  if (!args.density_regularization.empty()) {
    absl::StatusOr<double> x = ParseNumber(args.density_regularization, "--density-regularization");
    if (!x.ok()) return x.status();
    if (*x < 0)
      return absl::InvalidArgumentError(absl::StrCat("--density-regularization: must be >= 0 (got ",
                                                     args.density_regularization,
                                                     "); leave it out for the held-out choice"));
    o.set_density_regularization(*x);
  }
  if (!args.mesh_prior_weight.empty()) {
    absl::StatusOr<double> x = ParseNumber(args.mesh_prior_weight, "--mesh-prior-weight");
    if (!x.ok()) return x.status();
    if (*x < 0)
      return absl::InvalidArgumentError(
          absl::StrCat("--mesh-prior-weight: must be >= 0 (got ", args.mesh_prior_weight, ")"));
    o.set_mesh_prior_weight(*x);
  }
  if (!args.contradiction_ratio.empty()) {
    absl::StatusOr<double> x = ParseNumber(args.contradiction_ratio, "--contradiction-ratio");
    if (!x.ok()) return x.status();
    if (*x < 0)
      return absl::InvalidArgumentError(absl::StrCat("--contradiction-ratio: must be >= 0, 0 disables (got ",
                                                     args.contradiction_ratio, ")"));
    o.set_contradiction_ratio(*x);
  }
  if (!args.mesh_path.empty()) {
    absl::StatusOr<FlagMesh> loaded = LoadFlagMesh(args);
    if (!loaded.ok()) return loaded.status();
    *o.mutable_mesh() = api::MeshInputToProto(loaded->bytes, loaded->loaded.format, loaded->loaded.name,
                                              loaded->loaded.placement);
    *mesh = *std::move(loaded);
  }
  return o;
}

// --plot: the directory must exist (checked before the fit).
absl::Status CheckPlotPath(const std::string& path) {
  if (path.empty()) return absl::OkStatus();
  std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (parent.empty()) parent = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(parent, ec))
    return absl::InvalidArgumentError(
        absl::StrCat("--plot: directory '", parent.string(), "' of '", path, "' does not exist"));
  return absl::OkStatus();
}

// Writes the SVG of the fit on the mesh. `fit` is the library's result
// (local) or the server's answer converted back; the latter has no region
// model, which is rebuilt from the same mesh and options (deterministic).
absl::Status WritePlot(const InertiaArgs& args, const FlagMesh& mesh, inertia::InertiaFit fit,
                       const v1::InertiaFitOptions& options) {
  if (!fit.region_model && !fit.densities.empty()) {
    inertia::RegionOptions regions;
    absl::StatusOr<inertia::RegionScheme> scheme = inertia::ParseRegionScheme(args.regions);
    if (scheme.ok()) regions.scheme = *scheme;
    if (options.target_regions() != 0) regions.target_regions = static_cast<int>(options.target_regions());
    absl::StatusOr<inertia::RegionModel> model = inertia::BuildRegions(mesh.loaded.mesh, regions, mesh.loaded.name);
    if (model.ok() && model->regions.size() == fit.densities.size())
      fit.region_model = std::make_shared<const inertia::RegionModel>(*std::move(model));
  }
  inertia::DensityPlotOptions plot;
  plot.title = absl::StrCat(mesh.loaded.name, ": ", inertia::ToString(fit.method), " fit");
  if (options.has_truth()) plot.true_com = api::FromProto(options.truth().com());
  absl::StatusOr<std::string> svg = inertia::DensityPlotSvg(mesh.loaded.mesh, fit, plot);
  if (!svg.ok()) return absl::Status(svg.status().code(), absl::StrCat("--plot: ", svg.status().message()));
  std::ofstream out(args.plot_path, std::ios::binary);
  out << *svg;
  out.close();
  if (!out) return absl::InvalidArgumentError(absl::StrCat("--plot: cannot write '", args.plot_path, "'"));
  return absl::OkStatus();
}

// Streams the samples to Estimator.FitInertia in batches.
absl::StatusOr<v1::FitInertiaResponse> RemoteFit(const InertiaArgs& args,
                                                 const inertia::InertiaSamples& samples,
                                                 const v1::InertiaFitOptions& options,
                                                 ProgressBar& upload) {
  absl::StatusOr<std::shared_ptr<grpc::Channel>> channel =
      MakeChannel(args.connection, args.connection.server);
  if (!channel.ok()) return channel.status();
  auto stub = v1::Estimator::NewStub(*channel);
  grpc::ClientContext context;
  SetDeadline(&context, args.connection.deadline_ms);
  v1::FitInertiaResponse response;
  std::unique_ptr<grpc::ClientWriter<v1::FitInertiaRequest>> writer = stub->FitInertia(&context, &response);
  const size_t n = samples.samples.size();
  const size_t batch = static_cast<size_t>(std::max(1, args.batch));
  v1::FitInertiaRequest message;
  *message.mutable_options() = options;
  if (options.has_mesh() && n > 0) {
    // The mesh makes the options big: they travel alone, so that only the
    // mesh counts against the server's --max-message-bytes.
    if (writer->Write(message)) message.Clear();
  }
  size_t sent = 0;
  do {  // at least one message, even for an empty log
    const size_t end = std::min(n, sent + batch);
    for (size_t i = sent; i < end; ++i)
      *message.add_samples() = api::InertiaSampleToProto(samples.samples[i], samples.source);
    if (!writer->Write(message)) break;  // the server ended the call: Finish() says why
    sent = end;
    upload.Update(static_cast<double>(sent) / static_cast<double>(std::max<size_t>(n, 1)),
                  absl::StrCat(sent, "/", n, " samples"));
    message.Clear();
  } while (sent < n);
  writer->WritesDone();
  const grpc::Status status = writer->Finish();
  upload.Finish();
  if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED && options.has_mesh()) {
    // The first message carries the mesh: name the limit and how to raise it.
    v1::FitInertiaRequest first;
    *first.mutable_options() = options;
    return absl::ResourceExhaustedError(absl::StrCat(
        args.connection.server, ": ", status.error_message(), " (the first FitInertia message, ",
        first.ByteSizeLong(), " bytes, carries the mesh ", options.mesh().name(), " of ",
        options.mesh().data().size(), " bytes: start tactforce-server with a larger --max-message-bytes, or give "
        "a smaller mesh)"));
  }
  if (!status.ok()) return RpcError(status, args.connection.server, args.connection.deadline_ms, channel->get());
  return response;
}

std::string DescribeErrors(const v1::InertiaErrors& e) {
  return absl::StrFormat(
      "errors against the truth: paper metric |4 - Tr(P_gt^-1 P)| %.4g, Riemannian distance %.4g, "
      "mass %.3g %%, CoM %.3g mm, consistent %s\n",
      e.paper_metric(), e.riemannian(), e.mass_percent(), e.com_mm(), e.consistent() ? "yes" : "NO");
}

}  // namespace

CLI::App* AddInertiaCommand(CLI::App& app, InertiaArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "inertia", "Fit mass, centre of mass and inertia to object poses and applied forces");
  cmd->add_option("--csv", args.csv, "Samples: t,px..pz,qw..qz and a wrench (fx..tz) or contacts (c{i}_px..c{i}_fz)")
      ->type_name("FILE")
      ->required();
  cmd->add_option("--method", args.method,
                  "baseline-ls, factor-graph, constrained or density (default: density with --mesh, else constrained)")
      ->check(CLI::IsMember({"baseline-ls", "factor-graph", "constrained", "density"}));
  cmd->add_option("--gravity", args.gravity, "Gravity in the world, gx,gy,gz (m/s^2); default: the truth's or 0,0,-9.81");
  cmd->add_option("--truth", args.truth_path, "Truth JSON (mass, com, inertia_com): print the error metrics")
      ->type_name("FILE");
  cmd->add_option("--hull", args.hull_path,
                  "Object geometry for the CoM constraint: STL, OBJ, PLY (object frame, m), a mesh descriptor JSON "
                  "or CSV x,y,z")
      ->type_name("FILE");
  CLI::Option* mesh = cmd->add_option(
                              "--mesh", args.mesh_path,
                              "The object's closed mesh: STL, OBJ or PLY in the object frame (m), or a descriptor "
                              "JSON {\"mesh\": FILE, \"scale\": S, \"object_in_mesh\": {\"position\": [x,y,z], "
                              "\"quaternion\": [w,x,y,z]}}; needed by density, a prior for constrained")
                          ->type_name("FILE|DESCRIPTOR.json");
  cmd->add_option("--mesh-scale", args.mesh_scale, "Mesh units to m (> 0), replaces the descriptor's scale")
      ->type_name("S")
      ->needs(mesh);
  cmd->add_option("--mesh-pose", args.mesh_pose,
                  "Object frame in the mesh frame (m after scaling; quaternion w first), replaces object_in_mesh")
      ->type_name("x,y,z,qw,qx,qy,qz")
      ->needs(mesh);
  cmd->add_option("--regions", args.regions,
                  "density: regions of constant density: auto (colours if they split the mesh into closed parts, "
                  "else grid), grid, colors or single")
      ->check(CLI::IsMember({"auto", "grid", "colors", "single"}))
      ->capture_default_str()
      ->needs(mesh);
  cmd->add_option("--target-regions", args.target_regions, "density, grid: about this many regions (1..512; 0 = 12)")
      ->type_name("N")
      ->needs(mesh);
  cmd->add_option("--density-regularization", args.density_regularization,
                  "density: smoothness strength between neighbouring regions (>= 0); default: chosen by held-out "
                  "time blocks")
      ->type_name("X")
      ->needs(mesh);
  cmd->add_option("--mesh-prior-weight", args.mesh_prior_weight,
                  "constrained with --mesh: weight of the mesh's uniform-density prior (chi^2 units; default 1)")
      ->type_name("W")
      ->needs(mesh);
  cmd->add_option("--contradiction-ratio", args.contradiction_ratio,
                  "density: reject the mesh when its held-out residual exceeds constrained's by this factor "
                  "(default 1.2; 0 disables)")
      ->type_name("R")
      ->needs(mesh);
  cmd->add_option("--plot", args.plot_path,
                  "Write an SVG of the fit: the mesh in the principal planes, regions coloured by density, the "
                  "fitted (and with --truth the true) CoM")
      ->type_name("FILE.svg")
      ->needs(mesh);
  cmd->add_option("--prior", args.prior_path, "Prior parameters (truth JSON format)")->type_name("FILE");
  cmd->add_option("--prior-weight", args.prior_weight, "Weight of the prior (chi^2 units)")->capture_default_str();
  cmd->add_flag("--json", args.json, "Print the FitInertia response as proto3 JSON");
  cmd->add_option("--force-sigma", args.force_sigma, "Force noise std. dev. per component (N); 0 = estimate");
  cmd->add_option("--torque-sigma", args.torque_sigma, "Torque noise std. dev. (N m)");
  cmd->add_option("--position-sigma", args.position_sigma, "Position noise std. dev. (m)");
  cmd->add_option("--orientation-sigma", args.orientation_sigma, "Orientation noise std. dev. (rad)");
  cmd->add_option("--angular-velocity-sigma", args.angular_velocity_sigma, "Measured w noise (rad/s)");
  cmd->add_option("--acceleration-sigma", args.acceleration_sigma, "Measured a noise (m/s^2)");
  cmd->add_option("--angular-acceleration-sigma", args.angular_acceleration_sigma, "Measured dw noise (rad/s^2)");
  cmd->add_flag("--savitzky-golay", args.savitzky_golay, "baseline-ls: cubic Savitzky-Golay smoothing, window 51");
  cmd->add_option("--max-iterations", args.max_iterations, "Iteration limit (0 = 100)");
  CLI::Option* server = AddConnectionFlags(cmd, &args.connection, "--server", /*default_deadline_ms=*/120'000);
  server->description("Fit on tactforce-server (Estimator.FitInertia, streamed) instead of locally");
  server->each([&args](const std::string&) { args.remote = true; });
  cmd->add_option("--batch", args.batch, "Samples per streamed message")->capture_default_str();
  cmd->add_flag("--progress", args.progress, "Progress lines on stderr even when it is not a terminal");
  return cmd;
}

int RunInertia(const InertiaArgs& args) {
  if (args.batch < 1) return ReportError(absl::InvalidArgumentError("--batch: must be >= 1"));
  if (absl::Status s = CheckPlotPath(args.plot_path); !s.ok()) return ReportError(s);
  std::optional<FlagMesh> mesh;
  absl::StatusOr<v1::InertiaFitOptions> options = BuildOptions(args, &mesh);
  if (!options.ok()) return ReportError(options.status());
  absl::StatusOr<inertia::InertiaSamples> samples = inertia::ReadInertiaCsvFile(args.csv);
  if (!samples.ok()) return ReportError(samples.status());

  const bool show_progress = args.progress || ProgressBar::StderrIsTerminal();
  absl::StatusOr<v1::FitInertiaResponse> response;
  std::optional<inertia::InertiaFit> local_fit;
  if (args.remote) {
    ProgressBar upload("upload", show_progress);
    response = RemoteFit(args, *samples, *options, upload);
  } else {
    ProgressBar bar("fit", show_progress);
    local_fit.emplace();
    response = api::FitInertiaSamples(*samples, *options, {},
                                      [&bar](double fraction) { bar.Update(fraction); }, &*local_fit);
  }
  if (!response.ok()) return ReportError(response.status());
  if (!args.plot_path.empty() && mesh) {
    if (absl::Status s = WritePlot(args, *mesh, local_fit ? *local_fit : api::InertiaFitFromProto(*response), *options);
        !s.ok())
      return ReportError(s);
  }

  if (args.json) {
    std::cout << api::ToJson(*response);
  } else {
    std::cout << inertia::DescribeFit(api::InertiaFitFromProto(*response));
    if (response->has_errors()) std::cout << DescribeErrors(response->errors());
  }
  return std::cout ? kExitOk : kExitFailure;
}

// ------------------------------------------------------------ simulate inertia

namespace {

absl::StatusOr<std::vector<inertia::SinusoidComponent>> ParseComponents(const io::JsonValue& v,
                                                                         const std::string& where) {
  if (!v.is_array()) return absl::InvalidArgumentError(absl::StrCat(where, ": expected an array"));
  std::vector<inertia::SinusoidComponent> out;
  for (size_t i = 0; i < v.array().size(); ++i) {
    const io::JsonValue& c = v.array()[i];
    const std::string at = absl::StrCat(where, "[", i, "]");
    if (!c.is_object()) return absl::InvalidArgumentError(absl::StrCat(at, ": expected an object"));
    inertia::SinusoidComponent s;
    for (const auto& [key, value] : c.members()) {
      if (!value.is_number() || !std::isfinite(value.number()))
        return absl::InvalidArgumentError(absl::StrCat(at, ".", key, ": expected a number"));
      const double x = value.number();
      if (key == "axis") {
        if (x != 0 && x != 1 && x != 2)
          return absl::InvalidArgumentError(absl::StrCat(at, ".axis: must be 0, 1 or 2"));
        s.axis = static_cast<int>(x);
      } else if (key == "amplitude") {
        s.amplitude = x;
      } else if (key == "frequency_hz") {
        if (x < 0) return absl::InvalidArgumentError(absl::StrCat(at, ".frequency_hz: must be >= 0"));
        s.frequency_hz = x;
      } else if (key == "phase") {
        s.phase = x;
      } else {
        return absl::InvalidArgumentError(absl::StrCat(
            at, ": unknown key '", key, "' (expected axis, amplitude, frequency_hz, phase)"));
      }
    }
    out.push_back(s);
  }
  return out;
}

absl::StatusOr<Vec3> ParseTriple(const io::JsonValue& v, const std::string& where) {
  if (!v.is_array() || v.array().size() != 3 ||
      !std::all_of(v.array().begin(), v.array().end(), [](const io::JsonValue& x) { return x.is_number(); }))
    return absl::InvalidArgumentError(absl::StrCat(where, ": expected an array of 3 numbers"));
  return Vec3(v.array()[0].number(), v.array()[1].number(), v.array()[2].number());
}

// {"position_offset": [x,y,z], "orientation_offset": [yaw,pitch,roll],
//  "position": [{"axis","amplitude","frequency_hz","phase"}...], "orientation": [...]}
absl::StatusOr<inertia::ExcitationTrajectory> ReadTrajectory(const std::string& path) {
  absl::StatusOr<std::string> text = ReadInput(path, "--trajectory");
  if (!text.ok()) return text.status();
  absl::StatusOr<io::JsonValue> root = io::ParseJson(*text, path);
  if (!root.ok()) return root.status();
  if (!root->is_object()) return absl::InvalidArgumentError(absl::StrCat(path, ": expected a JSON object"));
  inertia::ExcitationTrajectory t;
  for (const auto& [key, value] : root->members()) {
    const std::string where = absl::StrCat(path, ": ", key);
    absl::Status s;
    if (key == "position_offset" || key == "orientation_offset") {
      absl::StatusOr<Vec3> v = ParseTriple(value, where);
      if (!v.ok()) return v.status();
      (key == "position_offset" ? t.position_offset : t.orientation_offset) = *v;
    } else if (key == "position" || key == "orientation") {
      absl::StatusOr<std::vector<inertia::SinusoidComponent>> c = ParseComponents(value, where);
      if (!c.ok()) return c.status();
      (key == "position" ? t.position : t.orientation) = *c;
    } else {
      return absl::InvalidArgumentError(absl::StrCat(
          where, ": unknown key (expected position_offset, orientation_offset, position, orientation)"));
    }
  }
  return t;
}

// Binary STL (little-endian float32; normals from the winding), the format
// `tactforce inertia --mesh` reads back.
absl::Status WriteBinaryStl(const io::TriangleMesh& mesh, const std::string& path, const std::string& label) {
  std::string bytes(80, '\0');
  const std::string header = absl::StrCat("tactforce simulate inertia: ", label, " (object frame, m)");
  std::memcpy(bytes.data(), header.data(), std::min<size_t>(header.size(), 80));
  auto put32 = [&bytes](uint32_t v) {
    for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  };
  auto put_float = [&put32](double x) {
    const float f = static_cast<float>(x);
    uint32_t v = 0;
    std::memcpy(&v, &f, sizeof v);
    put32(v);
  };
  put32(static_cast<uint32_t>(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[t[0]];
    const Vec3& b = mesh.vertices[t[1]];
    const Vec3& c = mesh.vertices[t[2]];
    Vec3 cross = (b - a).cross(c - a);
    if (cross.norm() > 0) cross.normalize();
    const Vec3 normal = cross;
    for (const Vec3* v : {&normal, &a, &b, &c})
      for (int k = 0; k < 3; ++k) put_float((*v)(k));
    bytes.push_back('\0');  // attribute byte count
    bytes.push_back('\0');
  }
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) return absl::InvalidArgumentError(absl::StrCat("--out: cannot write '", path, "'"));
  return absl::OkStatus();
}

}  // namespace

CLI::App* AddSimulateInertiaCommand(CLI::App& simulate, SimulateInertiaArgs& args) {
  CLI::App* cmd = simulate.add_subcommand(
      "inertia", "Simulate an object moved along an exciting trajectory: inertia.csv + truth.json");
  auto* object = cmd->add_option("--object", args.object, "Built-in object: seed-table1 (the paper's) or box")
                     ->check(CLI::IsMember(inertia::BuiltInObjectNames()))
                     ->capture_default_str();
  cmd->add_option("--params", args.params_path, "Custom object: truth JSON (mass, com, inertia_com)")
      ->type_name("FILE")
      ->excludes(object);
  cmd->add_option("--mode", args.mode, "in-hand (fingertip contact forces) or wrist (wrench sensor)")
      ->check(CLI::IsMember({"in-hand", "wrist"}))
      ->capture_default_str();
  cmd->add_option("--contacts", args.contacts, "in-hand: number of fingertips (2-4)")->capture_default_str();
  cmd->add_option("--seconds", args.seconds, "Duration (s)")->capture_default_str();
  cmd->add_option("--rate", args.rate, "Sample rate (Hz)")->capture_default_str();
  auto* variance = cmd->add_option("--force-variance", args.force_variance,
                                   "Force noise variance per component (N^2; the paper used 0-1)")
                       ->capture_default_str();
  cmd->add_option("--torque-sigma", args.torque_sigma, "wrist: torque noise std. dev. (N m)");
  cmd->add_option("--position-sigma", args.position_sigma, "Pose position noise std. dev. (m)");
  cmd->add_option("--orientation-sigma", args.orientation_sigma, "Pose orientation noise std. dev. (rad)");
  cmd->add_option("--noise-level", args.noise_level,
                  "Nadeau et al. 2023 level (wrist, with measured kinematics): low, moderate, high")
      ->check(CLI::IsMember({"low", "moderate", "high"}))
      ->excludes(variance);
  cmd->add_flag("--kinematics", args.kinematics, "Write measured kinematics columns (w, v, dw, a)");
  auto* amp = cmd->add_option("--amplitude-scale", args.amplitude_scale, "Scale the default excitation amplitudes")
                  ->capture_default_str();
  auto* freq = cmd->add_option("--frequency-scale", args.frequency_scale, "Scale the default excitation frequencies")
                   ->capture_default_str();
  cmd->add_option("--trajectory", args.trajectory_path, "Excitation trajectory JSON instead of the default")
      ->type_name("FILE")
      ->excludes(amp)
      ->excludes(freq);
  cmd->add_option("--seed", args.seed, "Random seed")->capture_default_str();
  cmd->add_option("--out", args.out_dir,
                  "Output directory: inertia.csv, truth.json and mesh.stl (the object's closed solid, object frame, "
                  "m: inertia --mesh OUT/mesh.stl)")
      ->required();
  return cmd;
}

int RunSimulateInertia(const SimulateInertiaArgs& args) {
  inertia::SimulationOptions o;
  o.object = args.object;
  if (!args.params_path.empty()) {
    absl::StatusOr<inertia::InertiaTruth> params = inertia::ReadTruthJsonFile(args.params_path);
    if (!params.ok()) return ReportError(params.status());
    absl::StatusOr<inertia::SimulatedObject> custom =
        inertia::ObjectFromParameters(std::filesystem::path(args.params_path).stem().string(), params->params);
    if (!custom.ok()) return ReportError(custom.status());
    o.custom = *custom;
    if (params->gravity_world) o.gravity = *params->gravity_world;
  }
  o.mode = args.mode == "wrist" ? inertia::SimulationMode::kWristWrench : inertia::SimulationMode::kInHand;
  o.num_contacts = args.contacts;
  o.duration = args.seconds;
  o.rate_hz = args.rate;
  if (!(args.force_variance >= 0) || !std::isfinite(args.force_variance))
    return ReportError(absl::InvalidArgumentError("--force-variance: must be finite and >= 0 (N^2)"));
  if (!args.noise_level.empty()) {
    absl::StatusOr<inertia::SimulationNoise> level = inertia::NadeauNoise(args.noise_level);
    if (!level.ok()) return ReportError(level.status());
    o.noise = *level;
    o.write_kinematics = true;  // the levels are noise on measured accelerations
  }
  if (args.force_variance > 0) o.noise.force_sigma = std::sqrt(args.force_variance);
  if (args.torque_sigma != 0) o.noise.torque_sigma = args.torque_sigma;
  o.noise.position_sigma = args.position_sigma;
  o.noise.orientation_sigma = args.orientation_sigma;
  o.write_kinematics = o.write_kinematics || args.kinematics;
  if (!args.trajectory_path.empty()) {
    absl::StatusOr<inertia::ExcitationTrajectory> t = ReadTrajectory(args.trajectory_path);
    if (!t.ok()) return ReportError(t.status());
    o.trajectory = *t;
  } else {
    if (!(args.amplitude_scale > 0) || !(args.frequency_scale > 0))
      return ReportError(absl::InvalidArgumentError("--amplitude-scale, --frequency-scale: must be > 0"));
    for (auto* list : {&o.trajectory.position, &o.trajectory.orientation}) {
      for (inertia::SinusoidComponent& c : *list) {
        c.amplitude *= args.amplitude_scale;
        c.frequency_hz *= args.frequency_scale;
      }
    }
  }
  o.seed = args.seed;
  absl::StatusOr<inertia::SimulationResult> result = inertia::SimulateInertia(o);
  if (!result.ok()) return ReportError(result.status());
  std::error_code ec;
  std::filesystem::create_directories(args.out_dir, ec);
  if (ec) return ReportError(absl::InvalidArgumentError(absl::StrCat("--out: cannot create '", args.out_dir, "': ", ec.message())));
  const std::string csv = (std::filesystem::path(args.out_dir) / "inertia.csv").string();
  const std::string truth = (std::filesystem::path(args.out_dir) / "truth.json").string();
  if (absl::Status s = inertia::WriteSimulation(*result, csv, truth); !s.ok()) return ReportError(s);
  const std::string mesh = (std::filesystem::path(args.out_dir) / "mesh.stl").string();
  const bool has_mesh = !result->object.mesh.triangles.empty();
  if (has_mesh) {
    if (absl::Status s = WriteBinaryStl(result->object.mesh, mesh, result->object.name); !s.ok()) return ReportError(s);
  }
  std::cerr << "wrote " << result->samples.samples.size() << " samples of '" << result->object.name << "' to "
            << csv << " (+ truth.json" << (has_mesh ? ", mesh.stl" : "") << ")\n";
  return kExitOk;
}

}  // namespace tactforce::cli
