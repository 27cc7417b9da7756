// `tactforce estimate` (contact forces from tactile readings, in this
// process or through Estimator.EstimateForces), `tactforce friction` (mu
// from slip trials) and `tactforce simulate friction` (trials with their
// truth): flags, input files to requests, responses to text.
#include "estimate_command.h"

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "cli_common.h"
#include "remote_call.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/api/names.h"
#include "tactforce/api/services.h"
#include "tactforce/estimator/friction.h"
#include "tactforce/io/csv.h"
#include "tactforce/io/json.h"
#include "tactforce/io/mesh.h"
#include "tactforce/io/text_file.h"
#include "tactforce/v1/estimator.grpc.pb.h"

namespace tactforce::cli {

CLI::App* AddEstimateCommand(CLI::App& app, EstimateArgs& args) {
  CLI::App* cmd = app.add_subcommand("estimate", "Estimate contact forces from tactile readings");
  CLI::Option* local = cmd->add_flag("--local", args.local, "Estimate in this process (no server)");
  CLI::Option* server = AddConnectionFlags(cmd, &args.connection);
  local->excludes(server);
  cmd->add_option("--request", args.request_path,
                  "EstimateRequest as JSON (object, contacts, readings, method, ...); - = stdin")
      ->required()
      ->type_name("FILE");
  AddOutputFlags(cmd, &args.output, "the EstimateResponse");
  cmd->footer(
      "Prints the force of every contact (request order, object frame, N) and the\n"
      "residual of every reading. Examples:\n"
      "  tactforce estimate --local --request client/examples/estimate_request.json\n"
      "  tactforce estimate --server localhost:50051 --request client/examples/estimate_request.json --json\n"
      "  cat client/examples/estimate_request.json | tactforce estimate --local --request -");
  return cmd;
}

namespace {

// One line per contact and per reading.
std::string FormatEstimateTable(const v1::EstimateRequest& request, const v1::EstimateResponse& response) {
  std::string out = absl::StrFormat("status: %s%s%s  (method %s, %d us)\n", api::ShortEnumName(response.status()),
                                    response.message().empty() ? "" : ": ", response.message(),
                                    api::ShortEnumName(response.method()), response.solve_time_us());
  absl::StrAppendFormat(&out, "%-4s %-12s %10s %10s %10s %12s\n", "#", "contact", "fx (N)", "fy (N)", "fz (N)",
                        "normal (N)");
  for (int i = 0; i < response.forces_size(); ++i) {
    const v1::Vec3& f = response.forces(i);
    const std::string name = i < request.contacts_size() ? request.contacts(i).name() : "";
    absl::StrAppendFormat(&out, "%-4d %-12s %10.4f %10.4f %10.4f %12.4f\n", i, name, f.x(), f.y(), f.z(),
                          i < response.normal_forces_size() ? response.normal_forces(i) : 0.0);
  }
  for (int k = 0; k < response.residuals_size(); ++k) {
    absl::StrAppendFormat(&out, "reading %d: residual %+.4f N\n", k, response.residuals(k));
  }
  return out;
}

}  // namespace

int RunEstimate(const EstimateArgs& args) {
  absl::StatusOr<std::string> text = ReadInput(args.request_path);
  if (!text.ok()) return ReportError(text.status());
  v1::EstimateRequest request;
  if (absl::Status s = api::ParseJson(*text, &request, InputName(args.request_path)); !s.ok()) return ReportError(s);
  absl::StatusOr<v1::EstimateResponse> response =
      args.local ? api::HandleEstimate(request)
                 : CallUnary(args.connection, &v1::Estimator::Stub::EstimateForces, request);
  if (!response.ok()) return ReportError(response.status());
  std::cout << (args.output.json() ? api::ToJson(*response) : FormatEstimateTable(request, *response));
  return std::cout ? kExitOk : kExitFailure;
}

CLI::App* AddFrictionCommand(CLI::App& app, FrictionArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "friction", "Estimate static friction from probing trials that end in slip");
  cmd->add_option("trials", args.trial_paths, "Trial CSV files: t,fx,fy,fz,px,py,pz[,slip]; - = stdin")
      ->required()
      ->type_name("TRIAL.csv");
  auto* normal = cmd->add_option("--normal", args.normal, "Surface normal into the object, x,y,z");
  auto* mesh = cmd->add_option("--mesh", args.mesh_path,
                               "Object mesh (STL, OBJ or PLY; object frame, m): nearest-triangle normal");
  normal->excludes(mesh);
  AddOutputFlags(cmd, &args.output, "the FrictionResponse");
  cmd->add_flag("--linear-fit", args.linear_fit,
                "Pre-slip force from line fits (ours) instead of the 5-sample average (paper)");
  cmd->add_option("--slip-distance", args.slip_distance, "Tangential travel that means slip (m)")
      ->check(GreaterThan(0))
      ->capture_default_str();
  cmd->add_option("--window", args.window, "Pre-slip samples averaged")->check(Between(1, 1000))->capture_default_str();
  cmd->add_option("--min-normal-force", args.min_normal_force, "Samples below this normal force are ignored (N)")
      ->check(AtLeast(0))
      ->capture_default_str();
  cmd->footer(
      "Prints mu per trial and their median, mean and IQR. Examples:\n"
      "  tactforce simulate friction --mu 0.3 --out /tmp/friction\n"
      "  tactforce friction /tmp/friction/trial*.csv --normal 0,0,-1\n"
      "  tactforce friction /tmp/friction/trial*.csv --normal 0,0,-1 --linear-fit --json");
  return cmd;
}

int RunFriction(const FrictionArgs& args) {
  if (args.normal.empty() && args.mesh_path.empty())
    return ReportError(absl::InvalidArgumentError("give --normal x,y,z or --mesh FILE"));
  v1::FrictionRequest request;
  for (const std::string& path : args.trial_paths) {
    absl::StatusOr<io::CsvTable> table = io::ReadCsvFile(path);
    if (!table.ok()) return ReportError(table.status());
    absl::StatusOr<estimator::FrictionTrial> trial = estimator::FrictionTrialFromCsv(*table);
    if (!trial.ok()) return ReportError(trial.status());
    v1::FrictionTrial* out = request.add_trials();
    out->set_name(io::SourceName(path));
    for (const auto& s : trial->samples) {
      v1::FrictionSample* smp = out->add_samples();
      smp->set_t(s.t);
      *smp->mutable_force() = api::ToProto(s.force);
      *smp->mutable_contact_point() = api::ToProto(s.contact_point);
      if (s.slip) smp->set_slip(*s.slip);
    }
  }
  if (!args.normal.empty()) {
    absl::StatusOr<planner::Vec3> n = ParseVec3(args.normal, "--normal");
    if (!n.ok()) return ReportError(n.status());
    for (auto& t : *request.mutable_trials()) *t.mutable_normal() = api::ToProto(*n);
  } else {
    absl::StatusOr<io::TriangleMesh> mesh = io::ReadMeshFile(args.mesh_path);
    if (!mesh.ok()) return ReportError(mesh.status());
    for (const auto& v : mesh->vertices) *request.mutable_mesh()->add_vertices() = api::ToProto(v);
    for (const auto& t : mesh->triangles) {
      v1::Triangle* tri = request.mutable_mesh()->add_triangles();
      tri->set_a(t[0]);
      tri->set_b(t[1]);
      tri->set_c(t[2]);
    }
  }
  request.set_slip_distance(args.slip_distance);
  request.set_window(static_cast<uint32_t>(args.window));
  request.set_min_normal_force(args.min_normal_force);
  request.set_pre_slip(args.linear_fit ? v1::PRE_SLIP_FORCE_LINEAR_FIT : v1::PRE_SLIP_FORCE_WINDOW_AVERAGE);
  absl::StatusOr<v1::FrictionResponse> response = api::HandleFriction(request);
  if (!response.ok()) return ReportError(response.status());
  if (args.output.json()) {
    std::cout << api::ToJson(*response);
    return std::cout ? kExitOk : kExitFailure;
  }
  std::cout << absl::StrFormat("%-40s %8s %8s %10s  %s\n", "trial", "mu", "slipped", "slip t (s)", "note");
  for (const auto& t : response->trials()) {
    std::cout << absl::StrFormat("%-40s %8.4f %8s %10.3f  %s\n", t.name(), t.mu(),
                                 t.slipped() ? "yes" : "no", t.slip_time(),
                                 t.lower_bound() ? "lower bound" : t.message());
  }
  std::cout << absl::StrFormat("\nmu: median %.4f  mean %.4f  IQR %.4f  over %d slipped trial(s)\n",
                               response->median(), response->mean(), response->iqr(), response->count());
  return std::cout ? kExitOk : kExitFailure;
}

CLI::App* AddSimulateFrictionCommand(CLI::App& simulate, SimulateFrictionArgs& args) {
  CLI::App* cmd = simulate.add_subcommand(
      "friction", "Write simulated probing trials (CSV per trial) and truth.json");
  cmd->add_option("--mu", args.mu, "True static friction coefficient")->check(Between(0.01, 10))->capture_default_str();
  cmd->add_option("--trials", args.trials, "Number of trials")->check(Between(1, 10000))->capture_default_str();
  cmd->add_option("--noise", args.noise, "Force noise std. dev. per component (N)")
      ->check(AtLeast(0))
      ->capture_default_str();
  cmd->add_option("--rate", args.rate, "Sample rate (Hz)")->check(Between(1, 1e5))->capture_default_str();
  cmd->add_option("--ramp", args.ramp, "Normal-force ramp-down rate (N/s)")->check(GreaterThan(0))->capture_default_str();
  cmd->add_option("--tangential-force", args.tangential_force, "Held tangential force (N)")
      ->check(GreaterThan(0))
      ->capture_default_str();
  cmd->add_flag("--slip-flags", args.slip_flags, "Also write a slip column (0/1)");
  cmd->add_option("--seed", args.seed, "Random seed")->capture_default_str();
  cmd->add_option("--out", args.out_dir, "Output directory (created; must be empty unless --force)")->required();
  cmd->add_flag("--force", args.force, "Replace the trial*.csv and truth.json of an earlier run in --out");
  cmd->footer(
      "Writes OUT/trial<i>.csv and OUT/truth.json. Example:\n"
      "  tactforce simulate friction --mu 0.3 --trials 10 --out /tmp/friction && \\\n"
      "    tactforce friction /tmp/friction/trial*.csv --normal 0,0,-1");
  return cmd;
}

int RunSimulateFriction(const SimulateFrictionArgs& args) {
  if (absl::Status s = PrepareOutputDir(args.out_dir, args.force, {"trial*.csv", "truth.json"}); !s.ok()) {
    return ReportError(s);
  }
  estimator::FrictionSimOptions sim;
  sim.mu = args.mu;
  sim.trials = args.trials;
  sim.force_noise = args.noise;
  sim.rate = args.rate;
  sim.ramp = args.ramp;
  sim.tangential_force = args.tangential_force;
  sim.write_slip_flags = args.slip_flags;
  sim.seed = args.seed;
  const estimator::SimulatedFriction data = estimator::SimulateFriction(sim);
  for (size_t i = 0; i < data.trials.size(); ++i) {
    std::string csv = absl::StrCat("t,fx,fy,fz,px,py,pz", args.slip_flags ? ",slip" : "", "\n");
    for (const auto& s : data.trials[i].samples) {
      absl::StrAppendFormat(&csv, "%.6f,%.6f,%.6f,%.6f,%.8f,%.8f,%.8f", s.t, s.force.x(), s.force.y(), s.force.z(),
                            s.contact_point.x(), s.contact_point.y(), s.contact_point.z());
      if (args.slip_flags) absl::StrAppend(&csv, ",", s.slip.value_or(false) ? 1 : 0);
      csv += "\n";
    }
    const std::string path = absl::StrCat(args.out_dir, "/trial", i, ".csv");
    if (absl::Status st = io::WriteTextFile(path, csv); !st.ok()) return ReportError(st);
  }
  io::JsonWriter truth;
  truth.BeginObject();
  truth.Field("mu", args.mu);
  truth.NumberArray("normal", {data.normal.x(), data.normal.y(), data.normal.z()});
  truth.NumberArray("slip_times", data.true_slip_time);
  truth.Field("force_noise", args.noise);
  truth.Field("rate", args.rate);
  truth.Field("ramp", args.ramp);
  truth.FieldInt("seed", static_cast<long long>(args.seed));
  truth.EndObject();
  if (absl::Status st = io::WriteTextFile(args.out_dir + "/truth.json", truth.str() + "\n"); !st.ok())
    return ReportError(st);
  std::cerr << "wrote " << data.trials.size() << " trials and truth.json to " << args.out_dir << "\n";
  return kExitOk;
}

}  // namespace tactforce::cli
