// `tactforce simulate inertia`: an object (built-in or from a truth JSON)
// moved along an exciting trajectory (the default, scaled, or a trajectory
// JSON), written as inertia.csv, truth.json and, for objects with a solid,
// mesh.stl (binary STL in the object frame, which `tactforce inertia --mesh`
// reads back).
#include "simulate_inertia_command.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <vector>

#include "absl/strings/str_cat.h"
#include "cli_common.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/inertia/truth.h"
#include "tactforce/io/json.h"
#include "tactforce/io/mesh.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {
namespace {

using inertia::Vec3;

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
        if (x < 0)
          return absl::InvalidArgumentError(absl::StrCat(at, ".frequency_hz: must be >= 0"));
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
      !std::all_of(v.array().begin(), v.array().end(),
                   [](const io::JsonValue& x) { return x.is_number(); }))
    return absl::InvalidArgumentError(absl::StrCat(where, ": expected an array of 3 numbers"));
  return Vec3(v.array()[0].number(), v.array()[1].number(), v.array()[2].number());
}

// {"position_offset": [x,y,z], "orientation_offset": [yaw,pitch,roll],
//  "position": [{"axis","amplitude","frequency_hz","phase"}...], "orientation": [...]}
absl::StatusOr<inertia::ExcitationTrajectory> ReadTrajectory(const std::string& path) {
  TF_ASSIGN_OR_RETURN(std::string text, ReadInput(path, "--trajectory"));
  TF_ASSIGN_OR_RETURN(io::JsonValue root, io::ParseJson(text, InputName(path)));
  if (!root.is_object())
    return absl::InvalidArgumentError(absl::StrCat(path, ": expected a JSON object"));
  inertia::ExcitationTrajectory t;
  for (const auto& [key, value] : root.members()) {
    const std::string where = absl::StrCat(path, ": ", key);
    absl::Status s;
    if (key == "position_offset" || key == "orientation_offset") {
      TF_ASSIGN_OR_RETURN(Vec3 v, ParseTriple(value, where));
      (key == "position_offset" ? t.position_offset : t.orientation_offset) = v;
    } else if (key == "position" || key == "orientation") {
      TF_ASSIGN_OR_RETURN(std::vector<inertia::SinusoidComponent> c, ParseComponents(value, where));
      (key == "position" ? t.position : t.orientation) = c;
    } else {
      return absl::InvalidArgumentError(absl::StrCat(
          where,
          ": unknown key (expected position_offset, orientation_offset, position, orientation)"));
    }
  }
  return t;
}

// Binary STL (little-endian float32; normals from the winding), the format
// `tactforce inertia --mesh` reads back.
absl::Status WriteBinaryStl(const io::TriangleMesh& mesh, const std::string& path,
                            const std::string& label) {
  std::string bytes(80, '\0');
  const std::string header =
      absl::StrCat("tactforce simulate inertia: ", label, " (object frame, m)");
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
  if (absl::Status written = io::WriteTextFile(path, bytes); !written.ok()) {
    return io::PrependPath(written, "--out");
  }
  return absl::OkStatus();
}

// The simulated object of --object or --params (a custom object from a
// truth JSON, whose gravity_world, when given, replaces the default).
absl::Status SetObject(const SimulateInertiaArgs& args, inertia::SimulationOptions* o) {
  o->object = args.object;
  if (args.params_path.empty()) return absl::OkStatus();
  TF_ASSIGN_OR_RETURN(const inertia::InertiaTruth params,
                      inertia::ReadTruthJsonFile(args.params_path));
  TF_ASSIGN_OR_RETURN(o->custom,
                      inertia::ObjectFromParameters(
                          std::filesystem::path(args.params_path).stem().string(), params.params));
  if (params.gravity_world) o->gravity = *params.gravity_world;
  return absl::OkStatus();
}

// Noise from --noise-level (which also writes the measured kinematics),
// --force-variance and the sigma flags.
absl::Status SetNoise(const SimulateInertiaArgs& args, inertia::SimulationOptions* o) {
  if (!(args.force_variance >= 0) || !std::isfinite(args.force_variance))
    return absl::InvalidArgumentError("--force-variance: must be finite and >= 0 (N^2)");
  if (!args.noise_level.empty()) {
    TF_ASSIGN_OR_RETURN(o->noise, inertia::NadeauNoise(args.noise_level));
    o->write_kinematics = true;  // the levels are noise on measured accelerations
  }
  if (args.force_variance > 0) o->noise.force_sigma = std::sqrt(args.force_variance);
  if (args.torque_sigma != 0) o->noise.torque_sigma = args.torque_sigma;
  o->noise.position_sigma = args.position_sigma;
  o->noise.orientation_sigma = args.orientation_sigma;
  o->write_kinematics = o->write_kinematics || args.kinematics;
  return absl::OkStatus();
}

// --trajectory FILE, or the default trajectory scaled by --amplitude-scale
// and --frequency-scale.
absl::Status SetTrajectory(const SimulateInertiaArgs& args, inertia::SimulationOptions* o) {
  if (!args.trajectory_path.empty()) {
    TF_ASSIGN_OR_RETURN(o->trajectory, ReadTrajectory(args.trajectory_path));
    return absl::OkStatus();
  }
  if (!(args.amplitude_scale > 0) || !(args.frequency_scale > 0))
    return absl::InvalidArgumentError("--amplitude-scale, --frequency-scale: must be > 0");
  for (auto* list : {&o->trajectory.position, &o->trajectory.orientation}) {
    for (inertia::SinusoidComponent& c : *list) {
      c.amplitude *= args.amplitude_scale;
      c.frequency_hz *= args.frequency_scale;
    }
  }
  return absl::OkStatus();
}

// The simulation the flags ask for; errors name the flag or file.
absl::StatusOr<inertia::SimulationOptions> SimulationOptionsFromFlags(
    const SimulateInertiaArgs& args) {
  inertia::SimulationOptions o;
  TF_RETURN_IF_ERROR(SetObject(args, &o));
  o.mode = args.mode == "wrist" ? inertia::SimulationMode::kWristWrench
                                : inertia::SimulationMode::kInHand;
  o.num_contacts = args.contacts;
  o.duration = args.seconds;
  o.rate_hz = args.rate;
  TF_RETURN_IF_ERROR(SetNoise(args, &o));
  TF_RETURN_IF_ERROR(SetTrajectory(args, &o));
  o.seed = args.seed;
  return o;
}

// OUT/inertia.csv, OUT/truth.json and, when the object has a solid,
// OUT/mesh.stl (OUT created); one line on stderr says what was written.
absl::Status WriteSimulationFiles(const inertia::SimulationResult& result,
                                  const std::string& out_dir) {
  const std::string csv = (std::filesystem::path(out_dir) / "inertia.csv").string();
  const std::string truth = (std::filesystem::path(out_dir) / "truth.json").string();
  TF_RETURN_IF_ERROR(inertia::WriteSimulation(result, csv, truth));
  const std::string mesh = (std::filesystem::path(out_dir) / "mesh.stl").string();
  const bool has_mesh = !result.object.mesh.triangles.empty();
  if (has_mesh) {
    TF_RETURN_IF_ERROR(WriteBinaryStl(result.object.mesh, mesh, result.object.name));
  }
  std::cerr << "wrote " << result.samples.samples.size() << " samples of '" << result.object.name
            << "' to " << csv << " (+ truth.json" << (has_mesh ? ", mesh.stl" : "") << ")\n";
  return absl::OkStatus();
}

}  // namespace

CLI::App* AddSimulateInertiaCommand(CLI::App& simulate, SimulateInertiaArgs& args) {
  CLI::App* cmd = simulate.add_subcommand(
      "inertia", "Simulate an object moved along an exciting trajectory: inertia.csv + truth.json");
  auto* object =
      cmd->add_option("--object", args.object, "Built-in object: seed-table1 (the paper's) or box")
          ->check(CLI::IsMember(inertia::BuiltInObjectNames()))
          ->capture_default_str();
  cmd->add_option("--params", args.params_path,
                  "Custom object: truth JSON (mass, com, inertia_com)")
      ->type_name("FILE")
      ->excludes(object);
  cmd->add_option("--mode", args.mode,
                  "in-hand (fingertip contact forces) or wrist (wrench sensor)")
      ->check(CLI::IsMember({"in-hand", "wrist"}))
      ->capture_default_str();
  cmd->add_option("--contacts", args.contacts, "in-hand: number of fingertips (2-4)")
      ->check(Between(2, 4))
      ->capture_default_str();
  AddRecordingClockFlags(cmd, &args.seconds, &args.rate);
  auto* variance = cmd->add_option("--force-variance", args.force_variance,
                                   "Force noise variance per component (N^2; the paper used 0-1)")
                       ->check(AtLeast(0))
                       ->capture_default_str();
  cmd->add_option("--torque-sigma", args.torque_sigma, "wrist: torque noise std. dev. (N m)")
      ->check(AtLeast(0));
  cmd->add_option("--position-sigma", args.position_sigma, "Pose position noise std. dev. (m)")
      ->check(AtLeast(0));
  cmd->add_option("--orientation-sigma", args.orientation_sigma,
                  "Pose orientation noise std. dev. (rad)")
      ->check(AtLeast(0));
  cmd->add_option("--noise-level", args.noise_level,
                  "Nadeau et al. 2023 level (wrist, with measured kinematics): low, moderate, high")
      ->check(CLI::IsMember({"low", "moderate", "high"}))
      ->excludes(variance);
  cmd->add_flag("--kinematics", args.kinematics, "Write measured kinematics columns (w, v, dw, a)");
  auto* amp = cmd->add_option("--amplitude-scale", args.amplitude_scale,
                              "Scale the default excitation amplitudes")
                  ->check(Between(0.01, 100))
                  ->capture_default_str();
  auto* freq = cmd->add_option("--frequency-scale", args.frequency_scale,
                               "Scale the default excitation frequencies")
                   ->check(Between(0.01, 100))
                   ->capture_default_str();
  cmd->add_option("--trajectory", args.trajectory_path,
                  "Excitation trajectory JSON instead of the default")
      ->type_name("FILE")
      ->excludes(amp)
      ->excludes(freq);
  cmd->add_option("--seed", args.seed, "Random seed")->capture_default_str();
  cmd->add_option("--out", args.out_dir,
                  "Output directory: inertia.csv, truth.json and mesh.stl (the object's closed "
                  "solid, object frame, "
                  "m: inertia --mesh OUT/mesh.stl); must be empty unless --force")
      ->required();
  cmd->add_flag("--force", args.force,
                "Replace the inertia.csv, truth.json and mesh.stl of an earlier run in --out");
  cmd->footer(
      "Writes OUT/inertia.csv, OUT/truth.json and OUT/mesh.stl. Examples:\n"
      "  tactforce simulate inertia --out /tmp/inertia\n"
      "  tactforce simulate inertia --mode wrist --noise-level moderate --kinematics --out "
      "/tmp/wrist\n"
      "  tactforce inertia --csv /tmp/inertia/inertia.csv --truth /tmp/inertia/truth.json");
  return cmd;
}

int RunSimulateInertia(const SimulateInertiaArgs& args) {
  absl::StatusOr<inertia::SimulationOptions> options = SimulationOptionsFromFlags(args);
  if (!options.ok()) return ReportError(options.status());
  if (absl::Status s =
          PrepareOutputDir(args.out_dir, args.force, {"inertia.csv", "truth.json", "mesh.stl"});
      !s.ok()) {
    return ReportError(s);
  }
  absl::StatusOr<inertia::SimulationResult> result = inertia::SimulateInertia(*options);
  if (!result.ok()) return ReportError(result.status());
  if (absl::Status s = WriteSimulationFiles(*result, args.out_dir); !s.ok()) return ReportError(s);
  return kExitOk;
}

}  // namespace tactforce::cli
