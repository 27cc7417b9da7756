#include "inertia_command.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "cli_common.h"
#include "grpcpp/grpcpp.h"
#include "progress.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/json.h"
#include "tactforce/estimator/csv.h"
#include "tactforce/estimator/mesh.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/inertia/truth.h"
#include "tactforce/sim/json.h"
#include "tactforce/v1/estimator.grpc.pb.h"

namespace tactforce::cli {
namespace {

using inertia::Vec3;

// Hull vertices from a mesh (.stl/.obj) or a CSV with x,y,z columns.
absl::StatusOr<std::vector<Vec3>> ReadHullVertices(const std::string& path) {
  std::string ext = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  if (ext == ".stl" || ext == ".obj") {
    absl::StatusOr<estimator::TriangleMesh> mesh = estimator::ReadMeshFile(path);
    if (!mesh.ok()) return mesh.status();
    return mesh->vertices;
  }
  absl::StatusOr<estimator::CsvTable> table = estimator::ReadCsvFile(path);
  if (!table.ok()) return table.status();
  if (absl::Status s = table->Require({"x", "y", "z"}); !s.ok()) return s;
  const int ix = table->ColumnIndex("x"), iy = table->ColumnIndex("y"), iz = table->ColumnIndex("z");
  std::vector<Vec3> out;
  for (const std::vector<double>& row : table->rows) out.emplace_back(row[ix], row[iy], row[iz]);
  return out;
}

// The FitInertia request options from the flags (and the truth/prior files).
absl::StatusOr<v1::InertiaFitOptions> BuildOptions(const InertiaArgs& args) {
  v1::InertiaFitOptions o;
  absl::StatusOr<inertia::InertiaMethod> method = inertia::ParseInertiaMethod(args.method);
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
  return o;
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
  cmd->add_option("--method", args.method, "baseline-ls, factor-graph or constrained")
      ->check(CLI::IsMember({"baseline-ls", "factor-graph", "constrained"}))
      ->capture_default_str();
  cmd->add_option("--gravity", args.gravity, "Gravity in the world, gx,gy,gz (m/s^2); default: the truth's or 0,0,-9.81");
  cmd->add_option("--truth", args.truth_path, "Truth JSON (mass, com, inertia_com): print the error metrics")
      ->type_name("FILE");
  cmd->add_option("--hull", args.hull_path, "Object geometry for the CoM constraint: STL, OBJ or CSV x,y,z")
      ->type_name("FILE");
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
  absl::StatusOr<v1::InertiaFitOptions> options = BuildOptions(args);
  if (!options.ok()) return ReportError(options.status());
  absl::StatusOr<inertia::InertiaSamples> samples = inertia::ReadInertiaCsvFile(args.csv);
  if (!samples.ok()) return ReportError(samples.status());

  const bool show_progress = args.progress || ProgressBar::StderrIsTerminal();
  absl::StatusOr<v1::FitInertiaResponse> response;
  if (args.remote) {
    ProgressBar upload("upload", show_progress);
    response = RemoteFit(args, *samples, *options, upload);
  } else {
    ProgressBar fit("fit", show_progress);
    response = api::FitInertiaSamples(*samples, *options, {},
                                      [&fit](double fraction) { fit.Update(fraction); });
  }
  if (!response.ok()) return ReportError(response.status());

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

absl::StatusOr<std::vector<inertia::SinusoidComponent>> ParseComponents(const sim::JsonValue& v,
                                                                         const std::string& where) {
  if (!v.is_array()) return absl::InvalidArgumentError(absl::StrCat(where, ": expected an array"));
  std::vector<inertia::SinusoidComponent> out;
  for (size_t i = 0; i < v.array().size(); ++i) {
    const sim::JsonValue& c = v.array()[i];
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

absl::StatusOr<Vec3> ParseTriple(const sim::JsonValue& v, const std::string& where) {
  if (!v.is_array() || v.array().size() != 3 ||
      !std::all_of(v.array().begin(), v.array().end(), [](const sim::JsonValue& x) { return x.is_number(); }))
    return absl::InvalidArgumentError(absl::StrCat(where, ": expected an array of 3 numbers"));
  return Vec3(v.array()[0].number(), v.array()[1].number(), v.array()[2].number());
}

// {"position_offset": [x,y,z], "orientation_offset": [yaw,pitch,roll],
//  "position": [{"axis","amplitude","frequency_hz","phase"}...], "orientation": [...]}
absl::StatusOr<inertia::ExcitationTrajectory> ReadTrajectory(const std::string& path) {
  absl::StatusOr<std::string> text = ReadInput(path, "--trajectory");
  if (!text.ok()) return text.status();
  absl::StatusOr<sim::JsonValue> root = sim::ParseJson(*text, path);
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
  cmd->add_option("--out", args.out_dir, "Output directory (inertia.csv, truth.json)")->required();
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
  std::cerr << "wrote " << result->samples.samples.size() << " samples of '" << result->object.name << "' to "
            << csv << " (+ truth.json)\n";
  return kExitOk;
}

}  // namespace tactforce::cli
