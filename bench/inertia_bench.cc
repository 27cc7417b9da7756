// Inertial-fitting benchmark (issue 5): BASELINE_LS, FACTOR_GRAPH and
// CONSTRAINED on the same data, markdown tables on stdout.
//
//   inertia_bench [--runs N] [--tool-runs N] [--duration S] [--tools DIR]
//                 [--no-tools] [--no-factor-graph]
//
// 1. seed-table1 (the paper's simulation object), in-hand: 4 fingertip
//    contacts with planner forces, 100 Hz, force-noise variances 0 .. 1 N^2
//    (no pose noise, kinematics from poses), N seeded runs per variance.
//    Target: CONSTRAINED paper metric <= 1/5 of FACTOR_GRAPH's, 100 %
//    consistent.
// 1b. The same object with noise on poses as well (errors in variables).
// 2. Wrist sensor, simulated (seed-table1, box) with measured kinematics and
//    Nadeau et al. noise on accelerations and wrenches (low/moderate/high).
//    Target at moderate: mass < 1 %, CoM < 1 % of size, Riemannian < 0.5.
// 3. The same on the five shared workshop tools (../shared/data/inertia).
// 4. The paper's ablation (experiment/ablation.h, `tactforce experiment
//    ablation`): every method and factor-graph variant on every source,
//    --ablation-seeds runs per cell (0 skips it).
// Times are CPU seconds of the fitting thread (the machine is shared);
// "x LS" is the ratio to BASELINE_LS on the same data.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "tactforce/experiment/ablation.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/inertia/truth.h"

using namespace tactforce::inertia;

namespace {

constexpr InertiaMethod kMethods[] = {InertiaMethod::kBaselineLs, InertiaMethod::kFactorGraph,
                                      InertiaMethod::kConstrained};

struct Stats {
  std::vector<double> paper, riem, mass, com_mm, com_pct, cpu, wall;
  int consistent = 0, runs = 0, failed = 0;

  void Add(const InertiaErrors& e, double size, const InertiaFit& f) {
    paper.push_back(e.paper_metric);
    if (std::isfinite(e.riemannian)) riem.push_back(e.riemannian);
    mass.push_back(e.mass_percent);
    com_mm.push_back(e.com_mm);
    com_pct.push_back(size > 0 ? 100.0 * e.com_mm / 1000.0 / size : 0.0);
    cpu.push_back(f.cpu_seconds);
    wall.push_back(f.time_seconds);
    consistent += e.consistent;
    ++runs;
  }
};

double Mean(const std::vector<double>& v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  double s = 0;
  for (double x : v) s += x;
  return s / v.size();
}

std::string Fmt(double v, const char* f = "%.3g") {
  if (std::isnan(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

std::string Riem(const Stats& s) {
  const int inf = s.runs - static_cast<int>(s.riem.size());
  if (s.riem.empty()) return "inf";
  std::string out = Fmt(Mean(s.riem));
  if (inf > 0) out += " (" + std::to_string(inf) + "/" + std::to_string(s.runs) + " inf)";
  return out;
}

InertiaOptions Options(InertiaMethod m, const SimulationNoise& n, bool give_kinematic_noise) {
  InertiaOptions o;
  o.method = m;
  o.noise.force_sigma = n.force_sigma;
  o.noise.torque_sigma = n.torque_sigma;
  o.noise.position_sigma = n.position_sigma;
  o.noise.orientation_sigma = n.orientation_sigma;
  if (give_kinematic_noise) {
    o.noise.linear_acceleration_sigma = n.linear_acceleration_sigma;
    o.noise.angular_acceleration_sigma = n.angular_acceleration_sigma;
    o.noise.angular_velocity_sigma = n.angular_velocity_sigma;
  }
  return o;
}

void Run(const InertiaSamples& s, const InertialParameters& truth, const InertiaOptions& base,
         double size, Stats (&stats)[3], bool fg) {
  for (int i = 0; i < 3; ++i) {
    if (kMethods[i] == InertiaMethod::kFactorGraph && !fg) continue;
    InertiaOptions o = base;
    o.method = kMethods[i];
    absl::StatusOr<InertiaFit> f = FitInertia(s, o);
    if (!f.ok()) {
      std::fprintf(stderr, "fit failed (%s): %s\n", ToString(kMethods[i]),
                   std::string(f.status().message()).c_str());
      ++stats[i].failed;
      continue;
    }
    stats[i].Add(CompareInertia(truth, f->params), size, *f);
  }
}

struct Args {
  int runs = 5, tool_runs = 3, ablation_seeds = 3;
  double duration = 10.0;
  std::string tools;
  bool no_tools = false, fg = true;
};

// Fills `a` from the command line; false (after a message) on bad input.
bool ParseArgs(int argc, char** argv, Args& a) {
  const char* src = std::getenv("TACTFORCE_SOURCE_DIR");
  a.tools = std::string(src ? src : ".") + "/../shared/data/inertia";
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto next = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", k.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (k == "--runs")
      a.runs = std::max(1, std::atoi(next()));
    else if (k == "--tool-runs")
      a.tool_runs = std::max(1, std::atoi(next()));
    else if (k == "--duration")
      a.duration = std::atof(next());
    else if (k == "--tools")
      a.tools = next();
    else if (k == "--no-tools")
      a.no_tools = true;
    else if (k == "--no-factor-graph")
      a.fg = false;
    else if (k == "--ablation-seeds")
      a.ablation_seeds = std::max(0, std::atoi(next()));
    else {
      std::fprintf(stderr,
                   "usage: inertia_bench [--runs N] [--tool-runs N] [--duration S] [--tools DIR] "
                   "[--no-tools] "
                   "[--no-factor-graph] [--ablation-seeds N]\n");
      return false;
    }
  }
  return true;
}

// One row per method of section 1's table.
void PrintForceNoiseRows(double var, const Stats (&st)[3]) {
  const double ls_cpu = Mean(st[0].cpu);
  for (int i = 0; i < 3; ++i) {
    if (st[i].runs == 0) continue;
    std::printf("| %s | %s | %s | %s | %s | %s | %d/%d | %s | %s |\n", Fmt(var).c_str(),
                ToString(kMethods[i]), Fmt(Mean(st[i].paper)).c_str(), Riem(st[i]).c_str(),
                Fmt(Mean(st[i].mass)).c_str(), Fmt(Mean(st[i].com_mm)).c_str(), st[i].consistent,
                st[i].runs, Fmt(1e3 * Mean(st[i].cpu)).c_str(),
                Fmt(Mean(st[i].cpu) / ls_cpu, "%.1f").c_str());
  }
}

struct TargetRow {
  double var, ratio;
  bool consistent;
};

// Section 1's target table and the speed line.
void PrintForceNoiseTargets(const std::vector<TargetRow>& targets, int samples,
                            double cpu_constrained, double wall_constrained) {
  std::printf(
      "\nPaper Table I (best variant, for orientation): paper metric 0.39, 0.55, 1.26, 1.13, 1.05 "
      "at "
      "variances 0, 0.1, 0.25, 0.5, 1.0; baselines about 4-5.\n\n");
  std::printf("Target (CONSTRAINED paper metric <= 1/5 of FACTOR_GRAPH's, 100 %% consistent):\n\n");
  std::printf("| var (N^2) | CONSTRAINED / FACTOR_GRAPH | consistent | met |\n|---|---|---|---|\n");
  for (const TargetRow& t : targets)
    std::printf("| %s | %s | %s | %s |\n", Fmt(t.var).c_str(), Fmt(t.ratio).c_str(),
                t.consistent ? "100 %" : "no", t.ratio <= 0.2 && t.consistent ? "yes" : "NO");
  std::printf("\nSpeed: CONSTRAINED on %d samples: %s ms CPU (%s ms wall).\n\n", samples,
              Fmt(1e3 * cpu_constrained).c_str(), Fmt(1e3 * wall_constrained).c_str());
}

// Section 1: seed-table1 in-hand over the paper's force-noise variances.
// False if a simulation fails.
bool ForceNoiseSection(const Args& a) {
  std::printf(
      "## seed-table1, in-hand (4 fingertips, planner forces), %.0f s at 100 Hz, %d runs per "
      "row\n\n",
      a.duration, a.runs);
  std::printf(
      "Force noise on every contact force component (variance in N^2); poses noise-free, "
      "kinematics from "
      "poses. Mean over runs; Riemannian over consistent runs (count of inconsistent ones in "
      "brackets).\n\n");
  std::printf(
      "| var (N^2) | method | paper metric | Riemannian | mass %% | CoM mm | consistent | CPU ms | "
      "x LS |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  std::vector<TargetRow> targets;
  double cpu_constrained_1000 = 0, wall_constrained_1000 = 0;
  int samples_1000 = 0;
  for (double var : kPaperForceVariances) {
    Stats st[3];
    for (int r = 0; r < a.runs; ++r) {
      SimulationOptions so;
      so.duration = a.duration;
      so.noise.force_sigma = std::sqrt(var);
      so.seed = 1000 + r;
      absl::StatusOr<SimulationResult> sim = SimulateInertia(so);
      if (!sim.ok()) {
        std::fprintf(stderr, "simulation failed: %s\n",
                     std::string(sim.status().message()).c_str());
        return false;
      }
      samples_1000 = static_cast<int>(sim->samples.samples.size());
      Run(sim->samples, sim->truth.params, Options(InertiaMethod::kConstrained, so.noise, true),
          EquivalentBoxSize(sim->truth.params), st, a.fg);
      std::fprintf(stderr, ".");
    }
    PrintForceNoiseRows(var, st);
    if (st[1].runs > 0 && st[2].runs > 0)
      targets.push_back(
          {var, Mean(st[2].paper) / Mean(st[1].paper), st[2].consistent == st[2].runs});
    cpu_constrained_1000 = Mean(st[2].cpu);
    wall_constrained_1000 = Mean(st[2].wall);
  }
  PrintForceNoiseTargets(targets, samples_1000, cpu_constrained_1000, wall_constrained_1000);
  return true;
}

// Section 1b: errors in forces and poses. False if a simulation fails.
bool PoseNoiseSection(const Args& a) {
  std::printf("## seed-table1, in-hand, errors in forces AND poses, %d runs per row\n\n",
              a.tool_runs);
  std::printf(
      "Force variance 0.25 N^2 plus pose noise (position sigma, orientation sigma); the fits are "
      "given the "
      "noise levels (BASELINE_LS with and without Savitzky-Golay smoothing).\n\n");
  std::printf(
      "| pose noise | method | paper metric | Riemannian | mass %% | CoM mm | consistent | CPU "
      "ms | x LS |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& [ps, rs] : {std::pair{1e-4, 1e-3}, std::pair{5e-4, 5e-3}}) {
    Stats st[3], sg;
    for (int r = 0; r < a.tool_runs; ++r) {
      SimulationOptions so;
      so.duration = a.duration;
      so.noise.force_sigma = 0.5;
      so.noise.position_sigma = ps;
      so.noise.orientation_sigma = rs;
      so.seed = 3000 + r;
      absl::StatusOr<SimulationResult> sim = SimulateInertia(so);
      if (!sim.ok()) return false;
      const InertiaOptions o = Options(InertiaMethod::kConstrained, so.noise, true);
      Run(sim->samples, sim->truth.params, o, 0.0, st, a.fg);
      InertiaOptions og = o;
      og.method = InertiaMethod::kBaselineLs;
      og.baseline_ls.savitzky_golay = true;
      absl::StatusOr<InertiaFit> f = FitInertia(sim->samples, og);
      if (f.ok()) sg.Add(CompareInertia(sim->truth.params, f->params), 0.0, *f);
      std::fprintf(stderr, ".");
    }
    const double ls_cpu = Mean(st[0].cpu);
    const std::string label = Fmt(ps * 1e3) + " mm, " + Fmt(rs * 1e3) + " mrad";
    auto row = [&](const char* name, const Stats& x) {
      std::printf("| %s | %s | %s | %s | %s | %s | %d/%d | %s | %s |\n", label.c_str(), name,
                  Fmt(Mean(x.paper)).c_str(), Riem(x).c_str(), Fmt(Mean(x.mass)).c_str(),
                  Fmt(Mean(x.com_mm)).c_str(), x.consistent, x.runs, Fmt(1e3 * Mean(x.cpu)).c_str(),
                  Fmt(Mean(x.cpu) / ls_cpu, "%.1f").c_str());
    };
    row("baseline-ls", st[0]);
    row("baseline-ls + SG 51", sg);
    if (st[1].runs) row("factor-graph", st[1]);
    row("constrained", st[2]);
  }
  std::printf("\n");
  return true;
}

// The objects of a wrist-sensor table, one entry per object.
struct WristData {
  std::vector<std::string> names;
  std::vector<InertiaSamples> data;
  std::vector<InertialParameters> truths;
  std::vector<Vec3> gravities;
};

// One noise level's rows for object j, with the target line at "moderate";
// false if the target is not met.
bool WristRows(const char* level, const WristData& w, size_t j, int runs, bool fg) {
  const SimulationNoise noise = *NadeauNoise(level);
  Stats st[3];
  const double size = EquivalentBoxSize(w.truths[j]);
  for (int r = 0; r < runs; ++r) {
    InertiaSamples s = w.data[j];
    AddNoise(s, noise, 7000 + 31 * r + j);
    InertiaOptions o = Options(InertiaMethod::kConstrained, noise, true);
    o.gravity = w.gravities[j];
    Run(s, w.truths[j], o, size, st, fg);
    std::fprintf(stderr, ".");
  }
  const double ls_cpu = Mean(st[0].cpu);
  for (int i = 0; i < 3; ++i) {
    if (st[i].runs == 0) continue;
    std::printf("| %s | %s | %s | %s | %s | %s | %s | %d/%d | %s | %s |\n", level,
                w.names[j].c_str(), ToString(kMethods[i]), Fmt(Mean(st[i].mass)).c_str(),
                Fmt(Mean(st[i].com_pct)).c_str(), Riem(st[i]).c_str(),
                Fmt(Mean(st[i].paper)).c_str(), st[i].consistent, st[i].runs,
                Fmt(1e3 * Mean(st[i].cpu)).c_str(), Fmt(Mean(st[i].cpu) / ls_cpu, "%.1f").c_str());
  }
  if (std::string(level) != "moderate") return true;
  const Stats& c = st[2];
  const bool met = Mean(c.mass) < 1.0 && Mean(c.com_pct) < 1.0 &&
                   static_cast<int>(c.riem.size()) == c.runs && Mean(c.riem) < 0.5;
  std::printf(
      "| | | *target (moderate): mass < 1 %%, CoM < 1 %%, Riemannian < 0.5* | | | | | | | "
      "%s |\n",
      met ? "met" : "NOT met");
  return met;
}

// Sections 2 and 3: a wrist-sensor table over Nadeau et al.'s noise levels;
// true if every moderate-level target is met.
bool WristTable(const std::string& title, const WristData& w, int runs, bool fg) {
  std::printf("## %s, %d runs per row\n\n", title.c_str(), runs);
  std::printf(
      "Noise (Nadeau et al. 2023) on measured accelerations and the wrench; the fits are given "
      "the noise "
      "levels. CoM error in %% of the object's size (longest edge of the uniform box with the "
      "same "
      "inertia).\n\n");
  std::printf(
      "| level | object | method | mass %% | CoM %% size | Riemannian | paper metric | "
      "consistent | CPU ms | "
      "x LS |\n|---|---|---|---|---|---|---|---|---|---|\n");
  bool all_met = true;
  for (const char* level : {"low", "moderate", "high"}) {
    for (size_t j = 0; j < w.data.size(); ++j)
      all_met = WristRows(level, w, j, runs, fg) && all_met;
  }
  std::printf("\n");
  return all_met;
}

// Section 2's objects, simulated with measured kinematics; nullopt if a
// simulation fails.
std::optional<WristData> SimulatedWristData(const Args& a) {
  WristData w;
  for (const char* obj : {"seed-table1", "box"}) {
    SimulationOptions so;
    so.object = obj;
    so.mode = SimulationMode::kWristWrench;
    so.duration = a.duration;
    so.write_kinematics = true;
    absl::StatusOr<SimulationResult> sim = SimulateInertia(so);
    if (!sim.ok()) return std::nullopt;
    w.names.push_back(obj);
    w.data.push_back(sim->samples);
    w.truths.push_back(sim->truth.params);
    w.gravities.push_back(so.gravity);
  }
  return w;
}

// Section 3's shared workshop tools; empty (after a note) if one is unreadable.
WristData SharedToolData(const Args& a) {
  WristData w;
  for (const char* tool : {"Hammer", "Screwdriver", "Pliers", "Ruler", "C_Clamp"}) {
    absl::StatusOr<InertiaSamples> s = ReadInertiaCsvFile(a.tools + "/" + tool + ".csv");
    absl::StatusOr<InertiaTruth> t = ReadTruthJsonFile(a.tools + "/" + tool + ".truth.json");
    if (!s.ok() || !t.ok()) {
      std::printf("## Shared workshop tools: skipped (%s not readable)\n\n", a.tools.c_str());
      return WristData{};
    }
    w.names.push_back(tool);
    w.data.push_back(*s);
    w.truths.push_back(t->params);
    w.gravities.push_back(t->gravity_world.value_or(Vec3(0, 0, -9.81)));
  }
  return w;
}

// Section 4: the paper's ablation. False if it fails.
bool AblationSection(const Args& a) {
  tactforce::experiment::AblationConfig c;
  c.seeds = a.ablation_seeds;
  c.duration = a.duration;
  absl::StatusOr<tactforce::experiment::AblationTable> t = tactforce::experiment::RunAblation(c);
  if (!t.ok()) {
    std::fprintf(stderr, "ablation failed: %s\n", std::string(t.status().message()).c_str());
    return false;
  }
  std::printf("%s\n", tactforce::experiment::AblationMarkdown(*t).c_str());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  if (!ParseArgs(argc, argv, a)) return 2;
  if (!ForceNoiseSection(a) || !PoseNoiseSection(a)) return 1;
  const std::optional<WristData> simulated = SimulatedWristData(a);
  if (!simulated) return 1;
  WristTable("Wrist sensor, simulated (100 Hz, measured kinematics)", *simulated, a.tool_runs,
             a.fg);
  if (!a.no_tools) {
    const WristData tools = SharedToolData(a);
    if (!tools.names.empty())
      WristTable("Wrist sensor, shared workshop tools (Nadeau et al. 2023 simulation, 100 Hz)",
                 tools, a.tool_runs, a.fg);
  }
  if (a.ablation_seeds > 0 && !AblationSection(a)) return 1;
  std::fprintf(stderr, "\n");
  return 0;
}
