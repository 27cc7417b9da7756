// `tactforce inertia`: the flags to InertiaFitOptions (truth, gravity, hull,
// prior, noise, and the mesh with its scale, pose and density settings), the
// fit through the Backend (in this process, or streamed to
// Estimator.FitInertia with --server), the SVG plot of a density fit, and
// the text or JSON answer.
#include "inertia_command.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <iostream>
#include <memory>
#include <optional>
#include <tuple>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "cli_common.h"
#include "backend.h"
#include "progress.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/json.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/density_plot.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/truth.h"
#include "tactforce/io/csv.h"
#include "tactforce/io/mesh.h"
#include "tactforce/io/text_file.h"
#include "tactforce/v1/estimator.grpc.pb.h"
#include "tactforce/io/status_macros.h"

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
    TF_ASSIGN_OR_RETURN(io::LoadedMesh mesh, io::LoadMesh(io::MeshRequest(path)));
    return mesh.mesh.vertices;
  }
  TF_ASSIGN_OR_RETURN(io::CsvTable table, io::ReadCsvFile(path));
  TF_RETURN_IF_ERROR(table.Require({"x", "y", "z"}));
  const int ix = table.ColumnIndex("x"), iy = table.ColumnIndex("y"), iz = table.ColumnIndex("z");
  std::vector<Vec3> out;
  for (const std::vector<double>& row : table.rows) out.emplace_back(row[ix], row[iy], row[iz]);
  return out;
}

// One finite number; errors name the flag and the token.
absl::StatusOr<double> ParseNumber(const std::string& token, const std::string& flag) {
  const std::string t(absl::StripAsciiWhitespace(token));
  char* end = nullptr;
  const double x = t.empty() ? 0.0 : std::strtod(t.c_str(), &end);
  if (t.empty() || end != t.c_str() + t.size())
    return absl::InvalidArgumentError(absl::StrCat(flag, ": '", token, "' is not a number"));
  if (!std::isfinite(x))
    return absl::InvalidArgumentError(absl::StrCat(flag, ": '", token, "' is not finite"));
  return x;
}

// --mesh-pose x,y,z,qw,qx,qy,qz: the object frame in the mesh frame.
absl::StatusOr<io::MeshPlacement> ParseMeshPose(const std::string& text) {
  const std::vector<std::string> tokens = absl::StrSplit(text, ',');
  if (tokens.size() != 7)
    return absl::InvalidArgumentError(
        absl::StrCat("--mesh-pose: expected 7 numbers x,y,z,qw,qx,qy,qz (got ", tokens.size(),
                     " in '", text, "')"));
  std::array<double, 7> v{};
  for (size_t i = 0; i < 7; ++i) {
    TF_ASSIGN_OR_RETURN(v[i], ParseNumber(tokens[i], "--mesh-pose"));
  }
  io::MeshPlacement pose;
  pose.position = Vec3(v[0], v[1], v[2]);
  pose.orientation = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
  if (!(pose.orientation.norm() >= 1e-6))
    return absl::InvalidArgumentError(absl::StrCat("--mesh-pose: quaternion qw,qx,qy,qz has norm ",
                                                   pose.orientation.norm(), " (near zero) in '",
                                                   text, "'"));
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
    TF_ASSIGN_OR_RETURN(const double scale, ParseNumber(args.mesh_scale, "--mesh-scale"));
    if (!(scale > 0))
      return absl::InvalidArgumentError(
          absl::StrCat("--mesh-scale: must be > 0 (got ", args.mesh_scale, ")"));
    request.scale = scale;
  }
  if (!args.mesh_pose.empty()) {
    TF_ASSIGN_OR_RETURN(request.pose, ParseMeshPose(args.mesh_pose));
  }
  std::error_code ec;
  if (!std::filesystem::exists(args.mesh_path, ec))
    return absl::InvalidArgumentError(
        absl::StrCat("--mesh: '", args.mesh_path, "' does not exist"));
  TF_ASSIGN_OR_RETURN(io::LoadedMesh loaded, io::LoadMesh(request));
  TF_ASSIGN_OR_RETURN(std::string bytes, ReadInput(loaded.mesh_path, "--mesh"));
  return FlagMesh{std::move(loaded), std::move(bytes)};
}

// An optional number flag that must be >= 0: nullopt when not given, else
// the number; the error says "FLAG: must be >= 0<rule> (got TEXT)<advice>".
absl::StatusOr<std::optional<double>> ParseNonNegative(const std::string& text,
                                                       const std::string& flag,
                                                       const std::string& rule = "",
                                                       const std::string& advice = "") {
  if (text.empty()) return std::nullopt;
  TF_ASSIGN_OR_RETURN(const double x, ParseNumber(text, flag));
  if (x < 0)
    return absl::InvalidArgumentError(
        absl::StrCat(flag, ": must be >= 0", rule, " (got ", text, ")", advice));
  return x;
}

// The method (default: density with --mesh, else constrained), --truth,
// --gravity, --hull and --prior.
absl::Status SetModelOptions(const InertiaArgs& args, v1::InertiaFitOptions* o) {
  const std::string method_name = !args.method.empty()     ? args.method
                                  : args.mesh_path.empty() ? "constrained"
                                                           : "density";
  absl::StatusOr<inertia::InertiaMethod> method = inertia::ParseInertiaMethod(method_name);
  if (!method.ok())
    return absl::InvalidArgumentError(absl::StrCat("--", method.status().message()));
  o->set_method(api::InertiaMethodToProto(*method));
  if (!args.truth_path.empty()) {
    TF_ASSIGN_OR_RETURN(const inertia::InertiaTruth truth,
                        inertia::ReadTruthJsonFile(args.truth_path));
    *o->mutable_truth() = api::InertialParametersToProto(truth.params);
    if (truth.gravity_world && args.gravity.empty())
      *o->mutable_gravity() = api::ToProto(*truth.gravity_world);
  }
  if (!args.gravity.empty()) {
    TF_ASSIGN_OR_RETURN(Eigen::Vector3d g, ParseVec3(args.gravity, "--gravity"));
    *o->mutable_gravity() = api::ToProto(g);
  }
  if (!args.hull_path.empty()) {
    TF_ASSIGN_OR_RETURN(std::vector<Vec3> hull, ReadHullVertices(args.hull_path));
    for (const Vec3& v : hull) *o->add_hull() = api::ToProto(v);
  }
  if (!args.prior_path.empty()) {
    TF_ASSIGN_OR_RETURN(inertia::InertiaTruth prior, inertia::ReadTruthJsonFile(args.prior_path));
    *o->mutable_prior()->mutable_params() = api::InertialParametersToProto(prior.params);
    o->mutable_prior()->set_weight(args.prior_weight);
  }
  return absl::OkStatus();
}

// The noise sigmas, Savitzky-Golay smoothing and --max-iterations.
absl::Status SetSolverOptions(const InertiaArgs& args, v1::InertiaFitOptions* o) {
  v1::InertiaNoise* n = o->mutable_noise();
  n->set_force_sigma(args.force_sigma);
  n->set_torque_sigma(args.torque_sigma);
  n->set_position_sigma(args.position_sigma);
  n->set_orientation_sigma(args.orientation_sigma);
  n->set_angular_velocity_sigma(args.angular_velocity_sigma);
  n->set_linear_acceleration_sigma(args.acceleration_sigma);
  n->set_angular_acceleration_sigma(args.angular_acceleration_sigma);
  o->set_savitzky_golay(args.savitzky_golay);
  if (!args.fg_variant.empty()) {
    absl::StatusOr<inertia::FactorGraphVariant> v =
        inertia::ParseFactorGraphVariant(args.fg_variant);
    if (!v.ok()) return io::PrependPath(v.status(), "--fg-variant");
    if (*v == inertia::FactorGraphVariant::kConstraintPrior && args.prior_path.empty())
      return absl::InvalidArgumentError(
          "--fg-variant fg-c-g needs --prior FILE (its geodesic prior; truth JSON format)");
    o->set_fg_variant(api::FactorGraphVariantToProto(*v));
  }
  if (args.max_iterations < 0) return absl::InvalidArgumentError("--max-iterations: must be >= 0");
  o->set_max_iterations(static_cast<uint32_t>(args.max_iterations));
  return absl::OkStatus();
}

// --regions, --target-regions, --density-regularization,
// --mesh-prior-weight and --contradiction-ratio.
absl::Status SetDensityOptions(const InertiaArgs& args, v1::InertiaFitOptions* o) {
  absl::StatusOr<inertia::RegionScheme> scheme = inertia::ParseRegionScheme(args.regions);
  if (!scheme.ok()) return io::PrependPath(scheme.status(), "--regions");
  o->set_regions(api::RegionSchemeToProto(*scheme));
  if (args.target_regions < 0 || args.target_regions > inertia::kMaxTargetRegions)
    return absl::InvalidArgumentError(absl::StrCat("--target-regions: must be in 1..",
                                                   inertia::kMaxTargetRegions, ", 0 = 12 (got ",
                                                   args.target_regions, ")"));
  o->set_target_regions(static_cast<uint32_t>(args.target_regions));
  TF_ASSIGN_OR_RETURN(std::optional<double> regularization,
                      ParseNonNegative(args.density_regularization, "--density-regularization", "",
                                       "; leave it out for the held-out choice"));
  if (regularization.has_value()) o->set_density_regularization(*regularization);
  TF_ASSIGN_OR_RETURN(std::optional<double> prior_weight,
                      ParseNonNegative(args.mesh_prior_weight, "--mesh-prior-weight"));
  if (prior_weight.has_value()) o->set_mesh_prior_weight(*prior_weight);
  TF_ASSIGN_OR_RETURN(std::optional<double> tolerance,
                      ParseNonNegative(args.mesh_tolerance, "--mesh-tolerance", ", 0 disables"));
  if (tolerance.has_value()) o->set_mesh_tolerance(*tolerance);
  return absl::OkStatus();
}

// The FitInertia request options from the flags (and the truth/prior/mesh
// files). `mesh` receives the loaded --mesh.
absl::StatusOr<v1::InertiaFitOptions> BuildOptions(const InertiaArgs& args,
                                                   std::optional<FlagMesh>* mesh) {
  v1::InertiaFitOptions o;
  TF_RETURN_IF_ERROR(SetModelOptions(args, &o));
  TF_RETURN_IF_ERROR(SetSolverOptions(args, &o));
  TF_RETURN_IF_ERROR(SetDensityOptions(args, &o));
  if (!args.mesh_path.empty()) {
    TF_ASSIGN_OR_RETURN(FlagMesh loaded, LoadFlagMesh(args));
    *o.mutable_mesh() = api::MeshInputToProto(loaded.bytes, loaded.loaded.format,
                                              loaded.loaded.name, loaded.loaded.placement);
    *mesh = std::move(loaded);
  }
  return o;
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
    if (options.target_regions() != 0)
      regions.target_regions = static_cast<int>(options.target_regions());
    absl::StatusOr<inertia::RegionModel> model =
        inertia::BuildRegions(mesh.loaded.mesh, regions, mesh.loaded.name);
    if (model.ok() && model->regions.size() == fit.densities.size())
      fit.region_model = std::make_shared<const inertia::RegionModel>(*std::move(model));
  }
  inertia::DensityPlotOptions plot;
  plot.title = absl::StrCat(mesh.loaded.name, ": ", inertia::ToString(fit.method), " fit");
  if (options.has_truth()) plot.true_com = api::FromProto(options.truth().com());
  plot.source = absl::StrCat("--csv ", args.csv, " --mesh ", args.mesh_path);
  absl::StatusOr<std::string> svg = inertia::DensityPlotSvg(mesh.loaded.mesh, fit, plot);
  if (!svg.ok()) return io::PrependPath(svg.status(), "--plot");
  if (absl::Status written = io::WriteTextFile(args.plot_path, *svg); !written.ok()) {
    return io::PrependPath(written, "--plot");
  }
  return absl::OkStatus();
}

std::string DescribeErrors(const v1::InertiaErrors& e) {
  return absl::StrFormat(
      "errors against the truth: paper metric |4 - Tr(P_gt^-1 P)| %.4g, Riemannian distance %.4g, "
      "mass %.3g %%, CoM %.3g mm, consistent %s\n",
      e.paper_metric(), e.riemannian(), e.mass_percent(), e.com_mm(),
      e.consistent() ? "yes" : "NO");
}

// --mesh and what refines it (scale, pose, regions, the density options, --plot).
void AddMeshFlags(CLI::App* cmd, InertiaArgs& args) {
  CLI::Option* mesh =
      cmd->add_option(
             "--mesh", args.mesh_path,
             "The object's closed mesh: STL, OBJ or PLY in the object frame (m), or a descriptor "
             "JSON {\"mesh\": FILE, \"scale\": S, \"object_in_mesh\": {\"position\": [x,y,z], "
             "\"quaternion\": [w,x,y,z]}}; needed by density, a prior for constrained")
          ->type_name("FILE|DESCRIPTOR.json");
  cmd->add_option("--mesh-scale", args.mesh_scale,
                  "Mesh units to m (> 0), replaces the descriptor's scale")
      ->type_name("S")
      ->needs(mesh);
  cmd->add_option("--mesh-pose", args.mesh_pose,
                  "Object frame in the mesh frame (m after scaling; quaternion w first), replaces "
                  "object_in_mesh")
      ->type_name("x,y,z,qw,qx,qy,qz")
      ->needs(mesh);
  cmd->add_option("--regions", args.regions,
                  "density: regions of constant density: auto (colours if they split the mesh into "
                  "closed parts, "
                  "else grid), grid, colors or single")
      ->check(CLI::IsMember({"auto", "grid", "colors", "single"}))
      ->capture_default_str()
      ->needs(mesh);
  cmd->add_option("--target-regions", args.target_regions,
                  "density, grid: about this many regions (1..100; 0 = 12)")
      ->type_name("N")
      ->needs(mesh);
  cmd->add_option("--density-regularization", args.density_regularization,
                  "density: smoothness strength between neighbouring regions (>= 0); default: "
                  "chosen by held-out "
                  "time blocks")
      ->type_name("X")
      ->needs(mesh);
  cmd->add_option("--mesh-prior-weight", args.mesh_prior_weight,
                  "constrained with --mesh: weight of the mesh's uniform-density prior (chi^2 "
                  "units; default 1)")
      ->type_name("W")
      ->needs(mesh);
  cmd->add_option("--mesh-tolerance", args.mesh_tolerance,
                  "density: the mesh is rejected when every density it can carry is farther than T "
                  "(first-order "
                  "Riemannian; default 0.03 = 3 % of the mass) from what the data allow; 0 "
                  "disables the test")
      ->type_name("T")
      ->needs(mesh);
  cmd->add_option("--plot", args.plot_path,
                  "Write an SVG of the fit: the mesh in the principal planes, regions coloured by "
                  "density, the "
                  "fitted (and with --truth the true) CoM")
      ->type_name("FILE.svg")
      ->needs(mesh);
}

}  // namespace

CLI::App* AddInertiaCommand(CLI::App& app, InertiaArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "inertia", "Fit mass, centre of mass and inertia to object poses and applied forces");
  cmd->add_option("--csv", args.csv,
                  "Samples: t,px..pz,qw..qz and a wrench (fx..tz) or contacts (c{i}_px..c{i}_fz)")
      ->type_name("FILE")
      ->required();
  cmd->add_option("--method", args.method,
                  "baseline-ls, factor-graph, constrained or density (default: density with "
                  "--mesh, else constrained)")
      ->check(CLI::IsMember({"baseline-ls", "factor-graph", "constrained", "density"}));
  cmd->add_option("--gravity", args.gravity,
                  "Gravity in the world, gx,gy,gz (m/s^2); default: the truth's or 0,0,-9.81");
  cmd->add_option("--truth", args.truth_path,
                  "Truth JSON (mass, com, inertia_com): print the error metrics")
      ->type_name("FILE");
  cmd->add_option("--hull", args.hull_path,
                  "Object geometry for the CoM constraint: STL, OBJ, PLY (object frame, m), a mesh "
                  "descriptor JSON "
                  "or CSV x,y,z")
      ->type_name("FILE");
  AddMeshFlags(cmd, args);
  cmd->add_option("--prior", args.prior_path, "Prior parameters (truth JSON format)")
      ->type_name("FILE");
  cmd->add_option("--prior-weight", args.prior_weight, "Weight of the prior (chi^2 units)")
      ->check(AtLeast(0))
      ->capture_default_str();
  AddOutputFlags(cmd, &args.output, "the FitInertiaResponse");
  for (auto [flag, value, what] :
       std::initializer_list<std::tuple<const char*, double*, const char*>>{
           {"--force-sigma", &args.force_sigma,
            "Force noise std. dev. per component (N); 0 = estimate"},
           {"--torque-sigma", &args.torque_sigma, "Torque noise std. dev. (N m)"},
           {"--position-sigma", &args.position_sigma, "Position noise std. dev. (m)"},
           {"--orientation-sigma", &args.orientation_sigma, "Orientation noise std. dev. (rad)"},
           {"--angular-velocity-sigma", &args.angular_velocity_sigma, "Measured w noise (rad/s)"},
           {"--acceleration-sigma", &args.acceleration_sigma, "Measured a noise (m/s^2)"},
           {"--angular-acceleration-sigma", &args.angular_acceleration_sigma,
            "Measured dw noise (rad/s^2)"}}) {
    cmd->add_option(flag, *value, what)->check(AtLeast(0));
  }
  cmd->add_flag("--savitzky-golay", args.savitzky_golay,
                "baseline-ls: cubic Savitzky-Golay smoothing, window 51");
  cmd->add_option("--fg-variant", args.fg_variant,
                  "factor-graph ablation variant: baseline-fg, fg-no-c, fg-c (default) or fg-c-g "
                  "(needs --prior)");
  cmd->add_option("--max-iterations", args.max_iterations, "Iteration limit (0 = 100)")
      ->check(Between(0, 100000));
  AddBackendFlags(cmd, &args.backend, "Estimator.FitInertia, streamed",
                  /*default_deadline_ms=*/120'000);
  cmd->add_option("--batch", args.batch, "Samples per streamed message")
      ->check(Between(1, 100000))
      ->capture_default_str();
  cmd->add_flag("--progress", args.progress,
                "Progress lines on stderr even when it is not a terminal");
  cmd->footer(
      "Prints mass, CoM and inertia with their standard errors (and the errors\n"
      "against --truth); warnings also go to stderr. Examples:\n"
      "  tactforce simulate inertia --out /tmp/inertia\n"
      "  tactforce inertia --csv /tmp/inertia/inertia.csv --truth /tmp/inertia/truth.json\n"
      "  tactforce inertia --csv client/examples/inertia_log.csv --hull "
      "client/examples/inertia_box.stl --json\n"
      "  tactforce inertia --csv /tmp/inertia/inertia.csv --server localhost:50051");
  return cmd;
}

int RunInertia(const InertiaArgs& args) {
  if (absl::Status s = CheckPlotPath(args.plot_path); !s.ok()) return ReportError(s);
  std::optional<FlagMesh> mesh;
  InertiaCall call;
  absl::StatusOr<v1::InertiaFitOptions> options = BuildOptions(args, &mesh);
  if (!options.ok()) return ReportError(options.status());
  call.options = *std::move(options);
  absl::StatusOr<inertia::InertiaSamples> samples = inertia::ReadInertiaCsvFile(args.csv);
  if (!samples.ok()) return ReportError(samples.status());
  call.samples = &*samples;
  call.batch = args.batch;
  call.show_progress = args.progress || ProgressBar::StderrIsTerminal();
  absl::StatusOr<InertiaAnswer> answer = CallBackend(args.backend, &Backend::FitInertia, call);
  if (!answer.ok()) return ReportError(answer.status());
  if (!args.plot_path.empty() && mesh) {
    if (absl::Status s = WritePlot(args, *mesh, answer->fit, call.options); !s.ok())
      return ReportError(s);
  }
  const v1::FitInertiaResponse& response = answer->response;
  for (const std::string& note : response.notes()) {
    if (absl::StartsWith(note, "warning:")) std::cerr << note << "\n";
  }
  if (args.output.json()) {
    std::cout << api::ToJson(response);
  } else {
    std::cout << inertia::DescribeFit(answer->fit);
    if (response.has_errors()) std::cout << DescribeErrors(response.errors());
  }
  return std::cout ? kExitOk : kExitFailure;
}

}  // namespace tactforce::cli
