// Inertia from geometry and motion (issue 12): DENSITY against the mesh-free
// methods on the same data, markdown tables on stdout.
//
//   inertia_mesh_bench [--seeds N] [--tools DIR] [--levels low,moderate,high]
//                      [--no-speed] [--no-in-hand]
//
// 1. The five shared workshop tools (Nadeau et al. 2023 simulation, wrist
//    sensor, measured kinematics, 100 Hz) with their CAD meshes
//    (<Tool>.mesh.json), Nadeau noise at each level, N seeds per tool:
//    BASELINE_LS, CONSTRAINED, CONSTRAINED with the mesh prior, and DENSITY
//    with the automatic regions (face colours when they bound closed parts,
//    else the grid), with the grid only (no part information), and with one
//    region (uniform density). Median over seeds per tool; the summary row is
//    the median and maximum over tools.
//    Targets (moderate): DENSITY median Riemannian <= 0.25, every tool <=
//    0.6, mass error <= 0.5 %, 100 % density-realizable; low: median <= 0.15.
// 2. In-hand data (fingertip contacts, planner forces) of the built-in
//    objects with their box meshes: DENSITY no worse than CONSTRAINED.
// 3. Speed: mesh loading + regions + fit (1,000 samples) per tool mesh, and
//    the growth with the number of regions on the hammer (115k faces).
// Times are CPU seconds of the calling thread.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/str_split.h"
#include "tactforce/io/mesh.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/inertia/truth.h"

using namespace tactforce;
using namespace tactforce::inertia;

namespace {

double CpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

double Median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string Fmt(double v, const char* f = "%.3g") {
  if (std::isnan(v)) return "-";
  if (std::isinf(v)) return "inf";
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

struct Variant {
  const char* name;
  InertiaMethod method;
  bool mesh;
  RegionScheme regions;
};

const Variant kVariants[] = {
    {"baseline-ls", InertiaMethod::kBaselineLs, false, RegionScheme::kAuto},
    {"constrained", InertiaMethod::kConstrained, false, RegionScheme::kAuto},
    {"constrained + mesh prior", InertiaMethod::kConstrained, true, RegionScheme::kAuto},
    {"density (auto regions)", InertiaMethod::kDensity, true, RegionScheme::kAuto},
    {"density (grid only)", InertiaMethod::kDensity, true, RegionScheme::kGrid},
    {"density (uniform)", InertiaMethod::kDensity, true, RegionScheme::kSingle},
};
constexpr int kNumVariants = sizeof(kVariants) / sizeof(kVariants[0]);

struct Cell {
  std::vector<double> riem, mass, com_mm, cpu;
  int consistent = 0, realizable = 0, contradicted = 0, runs = 0, failed = 0;
  std::string regions;
};

InertiaOptions NoisyOptions(const SimulationNoise& n) {
  InertiaOptions o;
  o.noise.force_sigma = n.force_sigma;
  o.noise.torque_sigma = n.torque_sigma;
  o.noise.position_sigma = n.position_sigma;
  o.noise.orientation_sigma = n.orientation_sigma;
  o.noise.linear_acceleration_sigma = n.linear_acceleration_sigma;
  o.noise.angular_acceleration_sigma = n.angular_acceleration_sigma;
  o.noise.angular_velocity_sigma = n.angular_velocity_sigma;
  return o;
}

void FitInto(const InertiaSamples& s, const InertialParameters& truth, InertiaOptions o,
             const Variant& v, const std::shared_ptr<const io::TriangleMesh>& mesh,
             const std::string& mesh_name, Cell* cell) {
  o.method = v.method;
  if (v.mesh) {
    o.mesh = mesh;
    o.mesh_name = mesh_name;
    o.density.regions.scheme = v.regions;
  }
  absl::StatusOr<InertiaFit> f = FitInertia(s, o);
  if (!f.ok()) {
    std::fprintf(stderr, "\n%s (%s): %s\n", mesh_name.c_str(), v.name,
                 std::string(f.status().message()).c_str());
    ++cell->failed;
    return;
  }
  const InertiaErrors e = CompareInertia(truth, f->params);
  cell->riem.push_back(e.riemannian);
  cell->mass.push_back(e.mass_percent);
  cell->com_mm.push_back(e.com_mm);
  cell->cpu.push_back(f->cpu_seconds);
  cell->consistent += e.consistent;
  cell->realizable += f->density_realizable;
  cell->contradicted += f->mesh_contradicted;
  if (f->region_model)
    cell->regions =
        std::to_string(f->region_model->regions.size()) + " " + ToString(f->region_model->scheme);
  ++cell->runs;
}

struct Tool {
  std::string name;
  InertiaSamples samples;
  InertialParameters truth;
  Vec3 gravity;
  std::shared_ptr<const io::TriangleMesh> mesh;
  std::string mesh_name;
  int faces = 0;
};

void ToolTable(const std::vector<Tool>& tools, const std::string& level, int seeds) {
  const SimulationNoise noise = *NadeauNoise(level);
  std::printf("### Shared workshop tools, '%s' noise, %d seeds per tool (median over seeds)\n\n",
              level.c_str(), seeds);
  std::printf(
      "| tool | method | Riemannian | mass %% | CoM mm | consistent | realizable | contradicted | "
      "regions | "
      "CPU ms |\n|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<std::vector<double>> per_tool(kNumVariants);  // median Riemannian per tool
  std::vector<double> max_mass(kNumVariants, 0.0);
  std::vector<int> realizable(kNumVariants, 0), runs(kNumVariants, 0);
  for (size_t t = 0; t < tools.size(); ++t) {
    Cell cells[kNumVariants];
    for (int seed = 0; seed < seeds; ++seed) {
      InertiaSamples s = tools[t].samples;
      AddNoise(s, noise, 12000 + 101 * seed + t);
      InertiaOptions o = NoisyOptions(noise);
      o.gravity = tools[t].gravity;
      for (int v = 0; v < kNumVariants; ++v)
        FitInto(s, tools[t].truth, o, kVariants[v], tools[t].mesh, tools[t].mesh_name, &cells[v]);
      std::fprintf(stderr, ".");
    }
    for (int v = 0; v < kNumVariants; ++v) {
      const Cell& c = cells[v];
      per_tool[v].push_back(Median(c.riem));
      max_mass[v] = std::max(max_mass[v], Median(c.mass));
      realizable[v] += c.realizable;
      runs[v] += c.runs;
      std::printf("| %s | %s | %s | %s | %s | %d/%d | %d/%d | %d | %s | %s |\n",
                  tools[t].name.c_str(), kVariants[v].name, Fmt(Median(c.riem)).c_str(),
                  Fmt(Median(c.mass)).c_str(), Fmt(Median(c.com_mm)).c_str(), c.consistent, c.runs,
                  c.realizable, c.runs, c.contradicted, c.regions.empty() ? "-" : c.regions.c_str(),
                  Fmt(1e3 * Median(c.cpu)).c_str());
    }
  }
  std::printf(
      "\n| method | median over tools (Riemannian) | worst tool | worst mass %% | realizable "
      "|\n|---|---|---|---|---|\n");
  for (int v = 0; v < kNumVariants; ++v) {
    std::printf("| %s | %s | %s | %s | %d/%d |\n", kVariants[v].name,
                Fmt(Median(per_tool[v])).c_str(),
                Fmt(*std::max_element(per_tool[v].begin(), per_tool[v].end())).c_str(),
                Fmt(max_mass[v]).c_str(), realizable[v], runs[v]);
  }
  std::printf("\n");
}

struct Args {
  int seeds = 5;
  std::string dir;
  std::vector<std::string> levels = {"low", "moderate", "high"};
  bool speed = true, in_hand = true;
};

// Fills `a` from the command line; false (after the usage line) on bad input.
bool ParseArgs(int argc, char** argv, Args& a) {
  const char* src = std::getenv("TACTFORCE_SOURCE_DIR");
  a.dir = std::string(src ? src : ".") + "/../shared/data/inertia";
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto next = [&]() { return i + 1 < argc ? argv[++i] : ""; };
    if (k == "--seeds")
      a.seeds = std::max(1, std::atoi(next()));
    else if (k == "--tools")
      a.dir = next();
    else if (k == "--levels")
      a.levels = absl::StrSplit(next(), ',');
    else if (k == "--no-speed")
      a.speed = false;
    else if (k == "--no-in-hand")
      a.in_hand = false;
    else {
      std::fprintf(
          stderr,
          "usage: inertia_mesh_bench [--seeds N] [--tools DIR] [--levels low,moderate,high] "
          "[--no-speed] [--no-in-hand]\n");
      return false;
    }
  }
  return true;
}

// The shared tools with their meshes; empty (after a note) if one is unreadable.
std::vector<Tool> LoadTools(const std::string& dir) {
  std::vector<Tool> tools;
  for (const char* name : {"Hammer", "Screwdriver", "Pliers", "Ruler", "C_Clamp"}) {
    Tool t;
    t.name = name;
    absl::StatusOr<InertiaSamples> s = ReadInertiaCsvFile(dir + "/" + name + ".csv");
    absl::StatusOr<InertiaTruth> truth = ReadTruthJsonFile(dir + "/" + name + ".truth.json");
    absl::StatusOr<io::LoadedMesh> mesh = io::LoadMesh({dir + "/" + name + ".mesh.json"});
    if (!s.ok() || !truth.ok() || !mesh.ok()) {
      std::printf("Shared tools skipped: %s\n\n", std::string((!s.ok()       ? s.status()
                                                               : !truth.ok() ? truth.status()
                                                                             : mesh.status())
                                                                  .message())
                                                      .c_str());
      return {};
    }
    t.samples = *s;
    t.truth = truth->params;
    t.gravity = truth->gravity_world.value_or(Vec3(0, 0, -9.81));
    t.faces = static_cast<int>(mesh->mesh.triangles.size());
    t.mesh = std::make_shared<const io::TriangleMesh>(std::move(mesh->mesh));
    t.mesh_name = mesh->name;
    tools.push_back(std::move(t));
  }
  return tools;
}

// Section 2: in-hand data of the built-in objects with their box meshes.
// False if a simulation fails.
bool InHandSection(int seeds) {
  std::printf(
      "## 2. In-hand data (4 fingertips, planner forces, force variance 0.1 N^2), built-in "
      "objects with "
      "their box meshes, %d seeds\n\n",
      seeds);
  std::printf(
      "| object | method | Riemannian | mass %% | CoM mm | consistent | realizable | "
      "contradicted | CPU ms |\n"
      "|---|---|---|---|---|---|---|---|---|\n");
  for (const char* object : {"seed-table1", "box"}) {
    Cell cells[kNumVariants];
    for (int seed = 0; seed < seeds; ++seed) {
      SimulationOptions so;
      so.object = object;
      so.mode = SimulationMode::kInHand;
      so.noise.force_sigma = std::sqrt(0.1);
      so.seed = 500 + seed;
      absl::StatusOr<SimulationResult> sim = SimulateInertia(so);
      if (!sim.ok()) {
        std::fprintf(stderr, "%s\n", std::string(sim.status().message()).c_str());
        return false;
      }
      auto mesh = std::make_shared<const io::TriangleMesh>(sim->object.mesh);
      InertiaOptions o;
      o.noise.force_sigma = so.noise.force_sigma;
      for (int v : {1, 2, 3})
        FitInto(sim->samples, sim->truth.params, o, kVariants[v], mesh, "box mesh", &cells[v]);
      std::fprintf(stderr, ".");
    }
    for (int v : {1, 2, 3}) {
      const Cell& c = cells[v];
      std::printf("| %s | %s | %s | %s | %s | %d/%d | %d/%d | %d | %s |\n", object,
                  kVariants[v].name, Fmt(Median(c.riem)).c_str(), Fmt(Median(c.mass)).c_str(),
                  Fmt(Median(c.com_mm)).c_str(), c.consistent, c.runs, c.realizable, c.runs,
                  c.contradicted, Fmt(1e3 * Median(c.cpu)).c_str());
    }
  }
  std::printf("\n");
  return true;
}

// CPU seconds (median of 3) of loading a tool's mesh, building its regions
// and a DENSITY fit of 1,000 samples, and the number of regions built.
struct Timing {
  double load = 0, build = 0, fit = 0;
  int regions = 0;
};

Timing TimeOne(const std::string& dir, const Tool& t, const RegionOptions& ro) {
  const SimulationNoise noise = *NadeauNoise("moderate");
  std::vector<double> l, b, f;
  Timing timing;
  for (int rep = 0; rep < 3; ++rep) {
    double c0 = CpuSeconds();
    absl::StatusOr<io::LoadedMesh> m = io::LoadMesh({dir + "/" + t.name + ".mesh.json"});
    double c1 = CpuSeconds();
    absl::StatusOr<RegionModel> r = BuildRegions(m->mesh, ro, m->name);
    double c2 = CpuSeconds();
    InertiaSamples s = t.samples;
    AddNoise(s, noise, 99);
    InertiaOptions o = NoisyOptions(noise);
    o.gravity = t.gravity;
    o.method = InertiaMethod::kDensity;
    o.mesh = std::make_shared<const io::TriangleMesh>(m->mesh);
    o.mesh_name = m->name;
    o.density.regions = ro;
    absl::StatusOr<InertiaFit> fit = FitInertia(s, o);
    double c3 = CpuSeconds();
    l.push_back(c1 - c0), b.push_back(c2 - c1), f.push_back(c3 - c2);
    timing.regions = r.ok() ? static_cast<int>(r->regions.size()) : 0;
    if (!fit.ok()) std::fprintf(stderr, "%s\n", std::string(fit.status().message()).c_str());
  }
  timing.load = Median(l), timing.build = Median(b), timing.fit = Median(f);
  return timing;
}

// Section 3: speed per tool mesh, and the growth with the number of regions.
void SpeedSection(const std::string& dir, const std::vector<Tool>& tools) {
  std::printf(
      "## 3. Speed: load the mesh + build the regions + fit 1,000 samples (DENSITY, 'moderate' "
      "noise; "
      "CPU ms, median of 3)\n\n");
  std::printf(
      "| mesh | faces | regions | load | regions | fit (incl. regions) | total "
      "|\n|---|---|---|---|---|---|---|\n");
  for (const Tool& t : tools) {
    RegionOptions grid;
    grid.scheme = RegionScheme::kGrid;
    const Timing m = TimeOne(dir, t, grid);
    std::printf("| %s | %d | %d grid | %s | %s | %s | %s |\n", t.mesh_name.c_str(), t.faces,
                m.regions, Fmt(1e3 * m.load).c_str(), Fmt(1e3 * m.build).c_str(),
                Fmt(1e3 * m.fit).c_str(), Fmt(1e3 * (m.load + m.fit)).c_str());
  }
  std::printf(
      "\nGrowth with the number of regions (Hammer.ply):\n\n| target regions | regions | regions "
      "ms | "
      "fit ms (incl. regions) |\n|---|---|---|---|\n");
  for (int target : {4, 8, 16, 32, 64, kMaxTargetRegions}) {
    RegionOptions grid;
    grid.scheme = RegionScheme::kGrid;
    grid.target_regions = target;
    const Timing m = TimeOne(dir, tools[0], grid);
    std::printf("| %d | %d | %s | %s |\n", target, m.regions, Fmt(1e3 * m.build).c_str(),
                Fmt(1e3 * m.fit).c_str());
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  if (!ParseArgs(argc, argv, a)) return 2;
  const std::vector<Tool> tools = LoadTools(a.dir);
  if (!tools.empty()) {
    std::printf("## 1. Shared workshop tools with their meshes\n\n");
    for (const std::string& level : a.levels) ToolTable(tools, level, a.seeds);
  }
  if (a.in_hand && !InHandSection(a.seeds)) return 1;
  if (a.speed && !tools.empty()) SpeedSection(a.dir, tools);
  std::fprintf(stderr, "\n");
  return 0;
}
