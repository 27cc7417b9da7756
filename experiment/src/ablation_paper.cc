// The paper's Tables I-IV (Sundaralingam & Hermans, T-RO 2021, appendix A),
// transcribed, and their errors computed with our metrics (ablation.h
// states the convention).
#include <algorithm>
#include <array>
#include <cstring>
#include <string>

#include "tactforce/experiment/ablation.h"
#include "tactforce/inertia/metrics.h"

namespace tactforce::experiment {
namespace {

// kg, m, and the inertia in the unit of the object's row in kTruths.
struct PaperValues {
  double mass, cx, cy, cz, ixx, iyy, izz, ixy, ixz, iyz;
};

struct PaperRow {
  const char* source;  // our source name
  const char* object;
  const char* method;  // the paper's: Baseline, Baseline-FG, No C, No G, C, No G, C + G
  PaperValues values;
};

// The ground truth of each object (the tables' GT rows, the same in every
// table that holds the object), inertia in `unit`.
struct PaperTruth {
  const char* object;
  PaperValues gt;
  double unit;  // kg m^2 per table unit
};
constexpr PaperTruth kTruths[] = {
    {"seed-table1", {1.3, 0.2, 0.5, 0.1, 40.15, 12.92, 47.99, -12.97, -2.59, -6.49}, 1e-2},
    {"box_0", {0.115, 0.094, -0.037, 0.032, 37.2, 150.8, 154.0, -40.0, 34.8, -13.6}, 1e-5},
    {"box_1", {0.179, 0.071, -0.033, 0.031, 50.0, 165.3, 166.9, -45.1, 40.7, -18.8}, 1e-5},
    {"box_2", {0.179, 0.09, -0.033, 0.031, 50.0, 204.6, 206.2, -54.1, 51.4, -18.8}, 1e-5},
    {"box_3", {0.131, 0.099, -0.036, 0.033, 42.0, 182.9, 184.4, -45.8, 44.6, -15.5}, 1e-5},
    {"box_4", {0.147, 0.109, -0.035, 0.031, 43.3, 239.0, 242.0, -53.7, 49.6, -16.0}, 1e-5},
};

// Table I (simulation, the four force-noise variances and none), II
// (Wrist-FT), III (In-Hand, vision), IV (In-Hand, relaxed rigidity): the
// estimates, inertia in the object's unit.
// One row of the paper in two lines:
// clang-format off
constexpr PaperRow kRows[] = {
    {"sim-0", "seed-table1", "Baseline",
     {0.073, 0.086, 0.419, 0.068, 1.76, -0.79, 1.88, 0.15, -0.29, -0.29}},
    {"sim-0", "seed-table1", "Baseline-FG",
     {1.292, 0.199, 0.488, 0.097, 22.8, 5.38, 35.8, -9.0, -2.9, -6.06}},
    {"sim-0", "seed-table1", "No C, No G",
     {1.292, 0.198, 0.486, 0.095, 14.17, -2.71, 34.89, -0.2, -2.61, -5.28}},
    {"sim-0", "seed-table1", "C, No G",
     {1.291, 0.197, 0.486, 0.095, 18.64, 17.21, 36.26, 0.14, -0.93, -2.66}},
    {"sim-0", "seed-table1", "C + G",
     {1.291, 0.197, 0.486, 0.095, 18.64, 17.21, 36.26, 0.14, -0.93, -2.66}},
    {"sim-0.1", "seed-table1", "Baseline",
     {0.076, 0.077, 0.422, 0.048, 1.83, -1.23, 1.9, -0.15, -0.21, -0.21}},
    {"sim-0.1", "seed-table1", "Baseline-FG",
     {1.292, 0.199, 0.486, 0.097, 24.38, 4.71, 35.46, -8.95, -2.18, -6.17}},
    {"sim-0.1", "seed-table1", "No C, No G",
     {1.294, 0.198, 0.485, 0.095, 10.41, -1.93, 30.99, 0.05, -1.8, -4.28}},
    {"sim-0.1", "seed-table1", "C, No G",
     {1.293, 0.197, 0.485, 0.094, 18.61, 17.32, 36.04, 0.09, -0.7, -2.41}},
    {"sim-0.1", "seed-table1", "C + G",
     {1.293, 0.197, 0.485, 0.094, 18.61, 17.32, 36.04, 0.09, -0.7, -2.41}},
    {"sim-0.25", "seed-table1", "Baseline",
     {0.076, 0.073, 0.355, 0.074, 1.29, -1.17, 1.8, 1.27, -0.34, -0.55}},
    {"sim-0.25", "seed-table1", "Baseline-FG",
     {1.289, 0.195, 0.485, 0.098, 22.16, 4.44, 34.76, -8.24, -1.54, -6.29}},
    {"sim-0.25", "seed-table1", "No C, No G",
     {1.288, 0.196, 0.487, 0.099, 10.56, -1.98, 27.37, -0.02, -1.24, -3.86}},
    {"sim-0.25", "seed-table1", "C, No G",
     {1.288, 0.196, 0.487, 0.097, 18.13, 19.18, 35.74, 0.08, -0.57, -2.36}},
    {"sim-0.25", "seed-table1", "C + G",
     {1.288, 0.196, 0.487, 0.097, 18.13, 19.18, 35.74, 0.08, -0.57, -2.36}},
    {"sim-0.5", "seed-table1", "Baseline",
     {0.069, 0.102, 0.386, 0.115, 1.41, -0.25, 1.91, 0.34, -0.33, -0.42}},
    {"sim-0.5", "seed-table1", "Baseline-FG",
     {1.293, 0.196, 0.481, 0.098, 23.24, 3.65, 34.27, -7.78, -2.37, -5.83}},
    {"sim-0.5", "seed-table1", "No C, No G",
     {1.296, 0.193, 0.481, 0.096, 10.28, -2.46, 23.69, -0.17, -1.12, -2.32}},
    {"sim-0.5", "seed-table1", "C, No G",
     {1.294, 0.194, 0.481, 0.092, 15.05, 20.51, 34.95, 0.12, -1.17, -1.86}},
    {"sim-0.5", "seed-table1", "C + G",
     {1.294, 0.194, 0.481, 0.092, 15.05, 20.51, 34.95, 0.12, -1.17, -1.86}},
    {"sim-1", "seed-table1", "Baseline",
     {0.068, 0.159, 0.492, 0.073, 1.14, 0.11, 2.09, -0.33, -0.05, -0.22}},
    {"sim-1", "seed-table1", "Baseline-FG",
     {1.277, 0.194, 0.478, 0.107, 24.41, 4.29, 33.02, -8.43, -1.97, -6.48}},
    {"sim-1", "seed-table1", "No C, No G",
     {1.269, 0.196, 0.485, 0.104, 8.61, -1.76, 24.21, -0.06, -0.91, -3.14}},
    {"sim-1", "seed-table1", "C, No G",
     {1.273, 0.196, 0.48, 0.099, 13.93, 20.07, 33.71, 0.05, -0.43, -1.37}},
    {"sim-1", "seed-table1", "C + G",
     {1.273, 0.196, 0.48, 0.099, 13.93, 20.07, 33.71, 0.05, -0.43, -1.37}},
    {"wrist-moderate", "box_0", "Baseline-FG",
     {0.147, 0.072, -0.022, 0.067, 85.29, 87.63, 47.73, -61.94, 12.39, -52.78}},
    {"wrist-moderate", "box_0", "No C, No G",
     {0.148, 0.057, -0.01, 0.037, 82.88, 135.25, 59.3, -49.09, 23.35, -29.76}},
    {"wrist-moderate", "box_0", "C, No G",
     {0.148, 0.057, -0.01, 0.037, 82.88, 135.25, 59.3, -49.09, 23.35, -29.76}},
    {"wrist-moderate", "box_0", "C + G",
     {0.148, 0.057, -0.01, 0.038, 82.45, 144.93, 59.0, -49.08, 23.34, -29.76}},
    {"wrist-moderate", "box_1", "Baseline-FG",
     {0.195, 0.059, -0.013, 0.027, 105.63, 428.65, 74.85, -53.87, 32.51, -11.93}},
    {"wrist-moderate", "box_1", "No C, No G",
     {0.195, 0.056, -0.012, 0.03, 106.0, 357.68, 73.92, -64.52, 30.81, -37.92}},
    {"wrist-moderate", "box_1", "C, No G",
     {0.195, 0.051, -0.011, 0.031, 106.41, 82.19, 74.31, -64.56, 30.71, -38.95}},
    {"wrist-moderate", "box_1", "C + G",
     {0.194, 0.06, -0.014, 0.03, 107.25, 85.89, 70.59, -64.31, 30.58, -38.93}},
    {"wrist-moderate", "box_2", "Baseline-FG",
     {0.222, 0.071, 0.005, 0.062, 189.47, 123.73, 139.89, -103.96, 21.33, -93.52}},
    {"wrist-moderate", "box_2", "No C, No G",
     {0.228, 0.051, 0.015, 0.032, 205.99, 94.38, 168.55, -75.2, 35.97, -47.08}},
    {"wrist-moderate", "box_2", "C, No G",
     {0.215, 0.071, 0.0, 0.033, 155.93, 195.55, 120.67, -71.51, 34.01, -43.31}},
    {"wrist-moderate", "box_2", "C + G",
     {0.215, 0.071, 0.0, 0.033, 155.93, 195.57, 120.67, -71.51, 34.01, -43.31}},
    {"wrist-moderate", "box_3", "Baseline-FG",
     {0.192, 0.083, -0.056, 0.036, 51.99, 101.06, 39.46, -69.17, 27.34, -39.39}},
    {"wrist-moderate", "box_3", "No C, No G",
     {0.171, 0.082, -0.023, 0.031, 79.86, 196.46, 63.65, -56.69, 26.98, -34.01}},
    {"wrist-moderate", "box_3", "C, No G",
     {0.171, 0.083, -0.023, 0.031, 82.83, 158.3, 64.15, -56.9, 27.05, -33.85}},
    {"wrist-moderate", "box_3", "C + G",
     {0.171, 0.083, -0.023, 0.031, 82.82, 158.3, 64.14, -56.9, 27.05, -33.85}},
    {"wrist-moderate", "box_4", "Baseline-FG",
     {0.213, 0.089, -0.053, 0.034, 58.85, 120.96, 54.32, -80.44, 30.83, -43.62}},
    {"wrist-moderate", "box_4", "No C, No G",
     {0.18, 0.085, -0.014, 0.031, 75.44, 43.42, 85.34, -59.81, 28.46, -37.12}},
    {"wrist-moderate", "box_4", "C, No G",
     {0.177, 0.076, -0.019, 0.031, 68.18, 50.46, 64.09, -58.58, 27.91, -35.49}},
    {"wrist-moderate", "box_4", "C + G",
     {0.177, 0.076, -0.019, 0.031, 67.96, 50.69, 64.15, -58.59, 27.91, -35.49}},
    {"inhand-vision", "box_0", "Baseline-FG",
     {0.124, 0.451, 0.335, -0.084, 1592.04, 3843.79, 6073.08, -2243.44, -23.59, 1988.83}},
    {"inhand-vision", "box_0", "No C, No G",
     {0.09, 0.649, 0.281, -0.009, 834.25, 4923.81, 6242.05, -2011.14, -390.47, 1405.04}},
    {"inhand-vision", "box_0", "C, No G",
     {0.045, 0.244, -0.003, 0.018, 1.84, 251.99, 250.91, 3.63, -18.65, 0.27}},
    {"inhand-vision", "box_0", "C + G",
     {0.045, 0.249, -0.004, 0.019, 1.92, 259.16, 258.08, 4.81, -19.66, 0.36}},
    {"inhand-vision", "box_1", "Baseline-FG",
     {0.048, 0.469, -0.231, 0.125, 326.17, 1122.55, 1310.51, 512.78, -278.3, 136.04}},
    {"inhand-vision", "box_1", "No C, No G",
     {0.053, 0.391, -0.199, 0.105, 269.65, 877.33, 1032.11, 414.18, -219.14, 110.96}},
    {"inhand-vision", "box_1", "C, No G",
     {0.043, 0.077, -0.061, 0.006, 13.22, 9.59, 42.4, 3.22, -1.01, 1.87}},
    {"inhand-vision", "box_1", "C + G",
     {0.045, 0.07, -0.053, 0.006, 15.71, 9.29, 27.23, 1.26, -0.33, 0.74}},
    {"inhand-vision", "box_2", "Baseline-FG",
     {0.158, 0.236, 0.341, 0.105, 2025.66, 1088.09, 5277.52, -1291.44, -553.15, -271.42}},
    {"inhand-vision", "box_2", "No C, No G",
     {0.073, 0.619, 0.352, 0.18, 1159.95, 3027.48, 5525.11, -1579.93, -982.86, -555.31}},
    {"inhand-vision", "box_2", "C, No G",
     {0.04, 0.249, -0.011, 0.034, 5.49, 234.74, 235.32, 10.12, -29.32, 1.32}},
    {"inhand-vision", "box_2", "C + G",
     {0.039, 0.253, -0.011, 0.034, 5.56, 240.82, 241.31, 10.24, -29.87, 1.32}},
    {"inhand-vision", "box_3", "Baseline-FG",
     {0.063, 0.808, 0.304, 0.121, 707.37, 4283.97, 5664.51, -1598.37, -774.69, 33.34}},
    {"inhand-vision", "box_3", "No C, No G",
     {0.061, 0.928, 0.344, 0.14, 873.0, 5442.51, 7034.36, -1996.59, -961.2, -2.2}},
    {"inhand-vision", "box_3", "C, No G",
     {0.036, 0.18, -0.01, 0.014, -0.88, 127.3, 125.18, 5.6, -8.83, 0.38}},
    {"inhand-vision", "box_3", "C + G",
     {0.036, 0.18, -0.01, 0.014, -0.88, 127.29, 125.19, 5.57, -8.79, 0.37}},
    {"inhand-vision", "box_4", "Baseline-FG",
     {0.047, 1.132, -0.051, 0.289, 408.09, 6479.25, 6157.76, 261.21, -1542.02, 122.95}},
    {"inhand-vision", "box_4", "No C, No G",
     {0.045, 1.062, -0.075, 0.312, 464.67, 5512.66, 5152.4, 354.58, -1488.71, 115.84}},
    {"inhand-vision", "box_4", "C, No G",
     {0.047, 0.277, -0.013, 0.028, 6.27, 328.87, 327.81, 14.49, -36.91, 1.63}},
    {"inhand-vision", "box_4", "C + G",
     {0.047, 0.277, -0.013, 0.028, 6.2, 327.28, 326.38, 14.38, -36.41, 1.61}},
    {"inhand-kinematic", "box_0", "Baseline-FG",
     {0.048, 0.385, 0.029, 0.084, 40.46, 760.11, 781.92, -59.37, -169.54, 14.8}},
    {"inhand-kinematic", "box_0", "No C, No G",
     {0.081, 0.649, 0.227, 0.09, 574.07, 3827.66, 5589.8, -1371.28, -866.56, 618.89}},
    {"inhand-kinematic", "box_0", "C, No G",
     {0.044, 0.249, -0.012, 0.013, 1.45, 251.28, 258.47, 12.3, -12.28, 0.35}},
    {"inhand-kinematic", "box_0", "C + G",
     {0.043, 0.249, 0.0, 0.011, 0.71, 237.69, 235.8, 0.11, -17.5, 0.04}},
    {"inhand-kinematic", "box_1", "Baseline-FG",
     {0.135, 0.386, 0.044, 0.369, 2007.69, 5949.03, 3166.77, 325.31, -2325.4, -1763.91}},
    {"inhand-kinematic", "box_1", "No C, No G",
     {0.082, 0.722, -0.076, 0.311, 970.73, 6656.01, 5165.28, 909.11, -2171.8, -983.14}},
    {"inhand-kinematic", "box_1", "C, No G",
     {0.048, 0.18, -0.018, 0.002, 1.32, 151.14, 152.45, 9.13, 0.46, -0.03}},
    {"inhand-kinematic", "box_1", "C + G",
     {0.044, 0.093, -0.061, 0.0, 2.75, 6.45, 54.04, -0.12, 1.09, -0.19}},
    {"inhand-kinematic", "box_2", "Baseline-FG",
     {0.204, 0.166, 0.379, 0.14, 3417.16, 968.85, 7046.5, -1249.28, -1057.08, -1261.71}},
    {"inhand-kinematic", "box_2", "No C, No G",
     {0.167, 0.137, 0.445, 0.127, 3926.12, 1388.39, 6648.07, -496.32, -1306.25, -2505.26}},
    {"inhand-kinematic", "box_2", "C, No G",
     {0.035, 0.289, -0.01, 0.038, 6.24, 264.51, 270.28, 8.83, -34.9, 1.13}},
    {"inhand-kinematic", "box_2", "C + G",
     {0.035, 0.302, -0.011, 0.046, 8.42, 283.34, 288.11, 8.15, -43.32, 1.29}},
    {"inhand-kinematic", "box_3", "Baseline-FG",
     {0.156, 0.302, 0.528, 0.057, 4546.66, 1693.47, 9821.81, -2665.26, -1027.65, 469.28}},
    {"inhand-kinematic", "box_3", "No C, No G",
     {0.101, 0.504, 0.534, 0.068, 3022.55, 2767.84, 8344.82, -2837.71, -864.75, 320.63}},
    {"inhand-kinematic", "box_3", "C, No G",
     {0.033, 0.241, -0.016, 0.014, 1.49, 179.55, 179.06, 9.43, -13.32, 0.7}},
    {"inhand-kinematic", "box_3", "C + G",
     {0.034, 0.323, 0.0, 0.03, 2.88, 307.03, 304.18, 2.08, -26.6, 0.18}},
    {"inhand-kinematic", "box_4", "Baseline-FG",
     {0.223, 0.258, 0.276, -0.016, 1716.96, 2093.23, 5416.4, -1667.46, -64.91, 1259.15}},
    {"inhand-kinematic", "box_4", "No C, No G",
     {0.199, 0.3, 0.296, -0.025, 1760.3, 2504.49, 5870.91, -1840.5, 11.3, 1431.34}},
    {"inhand-kinematic", "box_4", "C, No G",
     {0.047, 0.252, -0.007, 0.01, 2.82, 284.03, 285.26, 7.91, -14.98, 0.4}},
    {"inhand-kinematic", "box_4", "C + G",
     {0.045, 0.247, -0.004, 0.01, 3.37, 259.3, 261.36, 4.62, -13.04, 0.21}},
};
// clang-format on
// clang-format on

const PaperTruth* TruthOf(const char* object) {
  for (const PaperTruth& t : kTruths)
    if (!std::strcmp(t.object, object)) return &t;
  return nullptr;
}

inertia::InertialParameters Params(const PaperValues& v, double unit) {
  inertia::InertialParameters p;
  p.mass = v.mass;
  p.com = inertia::Vec3(v.cx, v.cy, v.cz);
  p.inertia_com = inertia::InertiaTensor::FromArray(
      {v.ixx * unit, v.iyy * unit, v.izz * unit, v.ixy * unit, v.ixz * unit, v.iyz * unit});
  return p;
}

}  // namespace

std::vector<PaperAblationValue> PaperAblationValues() {
  std::vector<PaperAblationValue> out;
  for (const PaperRow& r : kRows) {
    std::string method;
    for (AblationMethod m : AllAblationMethods())
      if (PaperMethodName(m) == r.method) method = ToString(m);
    const PaperTruth* gt = TruthOf(r.object);
    if (method.empty() || !gt) continue;
    auto it = std::find_if(out.begin(), out.end(), [&](const PaperAblationValue& v) {
      return v.method == method && v.source == r.source;
    });
    if (it == out.end()) {
      out.push_back({method, r.source, {}, {}, {}, {}, {}, 0});
      it = out.end() - 1;
    }
    const inertia::InertiaErrors e =
        inertia::CompareInertia(Params(gt->gt, gt->unit), Params(r.values, gt->unit));
    it->objects.push_back(r.object);
    it->eq38.push_back(e.paper_metric);
    it->riemannian.push_back(e.riemannian);
    it->mass_error_percent.push_back(e.mass_percent);
    it->com_error_mm.push_back(e.com_mm);
    it->consistent += e.consistent;
  }
  return out;
}

std::optional<PaperAblationValue> FindPaperValue(const std::string& method,
                                                 const std::string& source) {
  for (PaperAblationValue& v : PaperAblationValues())
    if (v.method == method && v.source == source) return v;
  return std::nullopt;
}

}  // namespace tactforce::experiment
