// `tactforce friction`: slip-trial CSVs (and the surface normal or mesh)
// to a FrictionRequest, through the Backend, the answer as a table or JSON.
#include "friction_command.h"

#include <iostream>

#include "absl/strings/str_format.h"
#include "cli_common.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/estimator/friction.h"
#include "tactforce/io/csv.h"
#include "tactforce/io/mesh.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/io/text_file.h"

namespace tactforce::cli {

CLI::App* AddFrictionCommand(CLI::App& app, FrictionArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "friction", "Estimate static friction from probing trials that end in slip");
  cmd->add_option("trials", args.trial_paths,
                  "Trial CSV files: t,fx,fy,fz,px,py,pz[,slip]; - = stdin")
      ->required()
      ->type_name("TRIAL.csv");
  auto* normal = cmd->add_option("--normal", args.normal, "Surface normal into the object, x,y,z");
  auto* mesh =
      cmd->add_option("--mesh", args.mesh_path,
                      "Object mesh (STL, OBJ or PLY; object frame, m): nearest-triangle normal");
  normal->excludes(mesh);
  AddOutputFlags(cmd, &args.output, "the FrictionResponse");
  AddBackendFlags(cmd, &args.backend, "Estimator.EstimateFriction");
  cmd->add_flag("--linear-fit", args.linear_fit,
                "Pre-slip force from line fits (ours) instead of the 5-sample average (paper)");
  cmd->add_option("--slip-distance", args.slip_distance, "Tangential travel that means slip (m)")
      ->check(GreaterThan(0))
      ->capture_default_str();
  cmd->add_option("--window", args.window, "Pre-slip samples averaged")
      ->check(Between(1, 1000))
      ->capture_default_str();
  cmd->add_option("--min-normal-force", args.min_normal_force,
                  "Samples below this normal force are ignored (N)")
      ->check(AtLeast(0))
      ->capture_default_str();
  cmd->footer(
      "Prints mu per trial and their median, mean and IQR. Examples:\n"
      "  tactforce simulate friction --mu 0.3 --out /tmp/friction\n"
      "  tactforce friction /tmp/friction/trial*.csv --normal 0,0,-1\n"
      "  tactforce friction /tmp/friction/trial*.csv --normal 0,0,-1 --linear-fit --json");
  return cmd;
}

namespace {

// The trial CSVs as FrictionTrials (the file name as the trial's name).
absl::Status AddTrials(const std::vector<std::string>& paths, v1::FrictionRequest* request) {
  for (const std::string& path : paths) {
    TF_ASSIGN_OR_RETURN(io::CsvTable table, io::ReadCsvFile(path));
    TF_ASSIGN_OR_RETURN(estimator::FrictionTrial trial, estimator::FrictionTrialFromCsv(table));
    v1::FrictionTrial* out = request->add_trials();
    out->set_name(io::SourceName(path));
    for (const auto& s : trial.samples) {
      v1::FrictionSample* smp = out->add_samples();
      smp->set_t(s.t);
      *smp->mutable_force() = api::ToProto(s.force);
      *smp->mutable_contact_point() = api::ToProto(s.contact_point);
      if (s.slip) smp->set_slip(*s.slip);
    }
  }
  return absl::OkStatus();
}

// --normal for every trial, or --mesh for the nearest-triangle normal.
absl::Status AddSurface(const FrictionArgs& args, v1::FrictionRequest* request) {
  if (!args.normal.empty()) {
    TF_ASSIGN_OR_RETURN(planner::Vec3 n, ParseVec3(args.normal, "--normal"));
    for (auto& t : *request->mutable_trials()) *t.mutable_normal() = api::ToProto(n);
    return absl::OkStatus();
  }
  TF_ASSIGN_OR_RETURN(io::TriangleMesh mesh, io::ReadMeshFile(args.mesh_path));
  for (const auto& v : mesh.vertices) *request->mutable_mesh()->add_vertices() = api::ToProto(v);
  for (const auto& t : mesh.triangles) {
    v1::Triangle* tri = request->mutable_mesh()->add_triangles();
    tri->set_a(t[0]);
    tri->set_b(t[1]);
    tri->set_c(t[2]);
  }
  return absl::OkStatus();
}

absl::StatusOr<v1::FrictionRequest> BuildFrictionRequest(const FrictionArgs& args) {
  if (args.normal.empty() && args.mesh_path.empty())
    return absl::InvalidArgumentError("give --normal x,y,z or --mesh FILE");
  v1::FrictionRequest request;
  TF_RETURN_IF_ERROR(AddTrials(args.trial_paths, &request));
  TF_RETURN_IF_ERROR(AddSurface(args, &request));
  request.set_slip_distance(args.slip_distance);
  request.set_window(static_cast<uint32_t>(args.window));
  request.set_min_normal_force(args.min_normal_force);
  request.set_pre_slip(args.linear_fit ? v1::PRE_SLIP_FORCE_LINEAR_FIT
                                       : v1::PRE_SLIP_FORCE_WINDOW_AVERAGE);
  return request;
}

// One line per trial, then the median, mean and IQR.
std::string FormatFrictionTable(const v1::FrictionResponse& response) {
  std::string out =
      absl::StrFormat("%-40s %8s %8s %10s  %s\n", "trial", "mu", "slipped", "slip t (s)", "note");
  for (const auto& t : response.trials()) {
    absl::StrAppendFormat(&out, "%-40s %8.4f %8s %10.3f  %s\n", t.name(), t.mu(),
                          t.slipped() ? "yes" : "no", t.slip_time(),
                          t.lower_bound() ? "lower bound" : t.message());
  }
  absl::StrAppendFormat(&out, "\nmu: median %.4f  mean %.4f  IQR %.4f  over %d slipped trial(s)\n",
                        response.median(), response.mean(), response.iqr(), response.count());
  return out;
}

}  // namespace

int RunFriction(const FrictionArgs& args) {
  absl::StatusOr<v1::FrictionRequest> request = BuildFrictionRequest(args);
  if (!request.ok()) return ReportError(request.status());
  absl::StatusOr<v1::FrictionResponse> response =
      CallBackend(args.backend, &Backend::EstimateFriction, *request);
  if (!response.ok()) return ReportError(response.status());
  std::cout << (args.output.json() ? api::ToJson(*response) : FormatFrictionTable(*response));
  return std::cout ? kExitOk : kExitFailure;
}

}  // namespace tactforce::cli
