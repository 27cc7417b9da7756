// The SVG picture of a density fit: a real DENSITY fit of a two-material box,
// exact colours, painter's order, back-face culling and one scale on a
// hand-made fit, the grey silhouette of a fit without regions, and errors.
#include "tactforce/inertia/density_plot.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tactforce/io/mesh.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/simulate.h"

namespace tactforce::inertia {
namespace {

using io::TriangleMesh;

// Axis-aligned box [lo, hi], triangles counter-clockwise seen from outside.
void AddBox(TriangleMesh* m, const Vec3& lo, const Vec3& hi, uint32_t color = 0) {
  const int b = static_cast<int>(m->vertices.size());
  for (int i = 0; i < 8; ++i)
    m->vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                             i & 4 ? hi.z() : lo.z());
  // Each face as a quad whose corners turn counter-clockwise about the outward normal.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    m->triangles.push_back({b + f[0], b + f[1], b + f[2]});
    m->triangles.push_back({b + f[0], b + f[2], b + f[3]});
    if (color) m->face_colors.insert(m->face_colors.end(), 2, color);
  }
}

// The part of the document between <g id="view-N"> and the next view (or the legend).
std::string View(const std::string& svg, int n) {
  const size_t begin = svg.find("<g id=\"view-" + std::to_string(n) + "\">");
  if (begin == std::string::npos) return "";
  size_t end = svg.find("<g id=\"view-" + std::to_string(n + 1) + "\">", begin);
  if (end == std::string::npos) end = svg.find("<g id=\"legend\">", begin);
  return svg.substr(begin, end - begin);
}

// Fill colours of the mesh's paths in `part` of `svg`, in document order
// (each path names a CSS class "cN" whose fill the document's style gives).
std::vector<std::string> PathFills(const std::string& svg, const std::string& part) {
  std::map<std::string, std::string> fill;
  static const std::regex rule("\\.(c[0-9]+)\\{fill:(#[0-9a-f]{6});");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), rule); it != std::sregex_iterator();
       ++it)
    fill[(*it)[1]] = (*it)[2];
  std::vector<std::string> out;
  static const std::regex path("<path class=\"(c[0-9]+)\"");
  for (auto it = std::sregex_iterator(part.begin(), part.end(), path); it != std::sregex_iterator();
       ++it) {
    const auto f = fill.find((*it)[1]);
    out.push_back(f == fill.end() ? "undefined class " + std::string((*it)[1]) : f->second);
  }
  return out;
}
std::vector<std::string> PathFills(const std::string& svg) { return PathFills(svg, svg); }

int Count(const std::string& s, const std::string& what) {
  int n = 0;
  for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

// Triangles drawn in a part: one "M" per triangle in the mesh's path data.
int DrawnTriangles(const std::string& part) {
  int n = 0;
  static const std::regex re(" d=\"(M[^\"]*)\"/>");
  for (auto it = std::sregex_iterator(part.begin(), part.end(), re); it != std::sregex_iterator();
       ++it) {
    const std::string d = (*it)[1];
    if (d.find('z') != std::string::npos)
      n += static_cast<int>(std::count(d.begin(), d.end(), 'M'));
  }
  return n;
}

double Luminance(const std::string& hex) {
  const unsigned v = std::stoul(hex.substr(1), nullptr, 16);
  return 0.2126 * (v >> 16 & 0xff) + 0.7152 * (v >> 8 & 0xff) + 0.0722 * (v & 0xff);
}

// ---------------------------------------------------------------- a real fit

struct TwoMaterial {
  TriangleMesh mesh;
  InertialParameters params;
};

// 0.3 x 0.08 x 0.05 m: steel (7800) for x < 0, plastic (1200) for x > 0,
// each half a closed part of its own colour.
TwoMaterial TwoMaterialBox() {
  TwoMaterial b;
  TriangleMesh steel, plastic;
  AddBox(&steel, Vec3(-0.15, -0.04, -0.025), Vec3(0, 0.04, 0.025), 0xaa0000);
  AddBox(&plastic, Vec3(0, -0.04, -0.025), Vec3(0.15, 0.04, 0.025), 0x00aa00);
  b.params = InertialParameters::FromStandard(MeshMoments(steel).Standard(7800) +
                                              MeshMoments(plastic).Standard(1200));
  b.mesh = steel;
  for (const auto& t : plastic.triangles)
    b.mesh.triangles.push_back({t[0] + 8, t[1] + 8, t[2] + 8});
  b.mesh.vertices.insert(b.mesh.vertices.end(), plastic.vertices.begin(), plastic.vertices.end());
  b.mesh.face_colors.insert(b.mesh.face_colors.end(), plastic.face_colors.begin(),
                            plastic.face_colors.end());
  return b;
}

// Wrist force-torque data of the box with the 'low' noise of Nadeau et al.
InertiaSamples WristSamples(const InertialParameters& params, InertiaOptions* options) {
  absl::StatusOr<SimulatedObject> object = ObjectFromParameters("two-material box", params);
  EXPECT_TRUE(object.ok()) << object.status();
  const SimulationNoise noise = *NadeauNoise("low");
  SimulationOptions o;
  o.custom = *object;
  o.mode = SimulationMode::kWristWrench;
  o.duration = 3.0;
  o.rate_hz = 100;
  o.write_kinematics = true;
  o.seed = 11;
  o.noise = noise;
  absl::StatusOr<SimulationResult> sim = SimulateInertia(o);
  EXPECT_TRUE(sim.ok()) << sim.status();
  options->noise.force_sigma = noise.force_sigma;
  options->noise.torque_sigma = noise.torque_sigma;
  options->noise.linear_acceleration_sigma = noise.linear_acceleration_sigma;
  options->noise.angular_acceleration_sigma = noise.angular_acceleration_sigma;
  options->noise.angular_velocity_sigma = noise.angular_velocity_sigma;
  return sim.ok() ? sim->samples : InertiaSamples{};
}

TEST(DensityPlot, TwoMaterialBoxIsColouredByItsFittedDensities) {
  const TwoMaterial box = TwoMaterialBox();
  InertiaOptions o;
  o.method = InertiaMethod::kDensity;
  o.mesh = std::make_shared<const TriangleMesh>(box.mesh);
  o.mesh_name = "box.ply";
  const InertiaSamples samples = WristSamples(box.params, &o);
  absl::StatusOr<InertiaFit> fit = FitInertia(samples, o);
  ASSERT_TRUE(fit.ok()) << fit.status();
  ASSERT_NE(fit->region_model, nullptr);
  ASSERT_EQ(fit->densities.size(), 2u);
  ASSERT_FALSE(fit->mesh_contradicted);
  const double rho_max = std::max(fit->densities[0].density, fit->densities[1].density);
  ASSERT_NEAR(rho_max, 7800, 0.02 * 7800);  // so that the colour bar ends at 8000

  DensityPlotOptions plot;
  plot.title = "two-material box <test>";
  plot.true_com = box.params.com;
  absl::StatusOr<std::string> svg = DensityPlotSvg(box.mesh, *fit, plot);
  ASSERT_TRUE(svg.ok()) << svg.status();
  EXPECT_EQ(svg->rfind("<svg", 0), 0u);
  EXPECT_EQ(svg->substr(svg->size() - 7), "</svg>\n");
  EXPECT_NE(svg->find("two-material box &lt;test&gt;"), std::string::npos) << "the title, escaped";
  EXPECT_EQ(svg->find("mesh contradicted"), std::string::npos);
  EXPECT_NE(svg->find("2 regions (colors, outlined)"), std::string::npos);
  // The colour bar: its label and ticks 0, 2000, ..., 8000 kg/m^3.
  EXPECT_NE(svg->find("density (kg/m³)"), std::string::npos);
  for (const char* tick : {">0<", ">2000<", ">4000<", ">6000<", ">8000<"})
    EXPECT_NE(svg->find(tick), std::string::npos) << tick;
  // Both markers in each of the three views, and in the legend.
  EXPECT_EQ(Count(*svg, "class=\"fitted-com\""), 3);
  EXPECT_EQ(Count(*svg, "class=\"true-com\""), 3);
  EXPECT_NE(svg->find("fitted CoM"), std::string::npos);
  EXPECT_NE(svg->find("true CoM"), std::string::npos);
  // Two fill colours, neither grey; the dense half is the brighter one
  // (the ramp's lightness grows with the density).
  const std::vector<std::string> fills = PathFills(*svg, View(*svg, 1));
  const std::set<std::string> distinct(fills.begin(), fills.end());
  ASSERT_EQ(distinct.size(), 2u);
  EXPECT_EQ(distinct.count("#d0d0d0"), 0u);
  EXPECT_GT(std::abs(Luminance(*distinct.begin()) - Luminance(*distinct.rbegin())), 50);
  for (int view = 2; view <= 3; ++view) {
    const std::vector<std::string> f = PathFills(*svg, View(*svg, view));
    ASSERT_FALSE(f.empty()) << "view " << view;
    for (const std::string& c : f) EXPECT_EQ(distinct.count(c), 1u) << "view " << view << ": " << c;
  }
  // Back faces are culled: at most three faces of each half (12 of the 24
  // triangles) face the viewer; the view along the fitted axes shows at
  // least the face of each half square to it (the fitted axes are close to,
  // not exactly, the box's, so slivers of side faces may show as well).
  for (int view = 1; view <= 3; ++view) {
    EXPECT_LE(DrawnTriangles(View(*svg, view)), 12) << "view " << view;
    EXPECT_GE(DrawnTriangles(View(*svg, view)), view == 3 ? 2 : 4) << "view " << view;
  }
}

// ------------------------------------------------------------ a hand-made fit

// Two boxes 0.2 x 0.04 x 0.02 m, one behind the other along z (regions 0
// and 1), and a small box of no region (-1) beside them.
struct HandMade {
  TriangleMesh mesh;
  InertiaFit fit;
};
HandMade HandMadeFit(double rho0, double rho1) {
  HandMade h;
  AddBox(&h.mesh, Vec3(-0.1, -0.02, -0.05), Vec3(0.1, 0.02, -0.03));  // far in view 1 (along +z)
  AddBox(&h.mesh, Vec3(-0.1, -0.02, 0.03), Vec3(0.1, 0.02, 0.05));    // near
  AddBox(&h.mesh, Vec3(-0.1, 0.03, -0.01), Vec3(-0.09, 0.04, 0.01));  // no region
  auto model = std::make_shared<RegionModel>();
  model->scheme = RegionScheme::kGrid;
  model->regions.resize(2);
  model->regions[0].label = "far";
  model->regions[1].label = "near";
  model->triangle_region.assign(12, 0);
  model->triangle_region.insert(model->triangle_region.end(), 12, 1);
  model->triangle_region.insert(model->triangle_region.end(), 12, -1);
  h.fit.method = InertiaMethod::kDensity;
  h.fit.params.mass = 1.0;
  h.fit.params.com = Vec3::Zero();
  h.fit.principal_axes = Eigen::Matrix3d::Identity();
  h.fit.region_model = model;
  h.fit.densities = {{"far", rho0, 0, 0}, {"near", rho1, 0, 0}};
  return h;
}

TEST(DensityPlot, RampEndsAtZeroAndTheRoundedMaximumAndNoRegionIsGrey) {
  const HandMade h = HandMadeFit(0.0, 8000.0);
  absl::StatusOr<std::string> svg = DensityPlotSvg(h.mesh, h.fit);
  ASSERT_TRUE(svg.ok()) << svg.status();
  const std::vector<std::string> fills = PathFills(*svg);
  const std::set<std::string> distinct(fills.begin(), fills.end());
  // 0 kg/m^3: the dark end of the ramp; 8000 (the top of the bar): the yellow end.
  EXPECT_EQ(distinct, (std::set<std::string>{"#440154", "#fde725", "#d0d0d0"}));
  EXPECT_NE(svg->find(">density fit<"), std::string::npos) << "default title";
  EXPECT_EQ(svg->find("true-com"), std::string::npos) << "no true CoM given";
  EXPECT_EQ(Count(*svg, "class=\"fitted-com\""), 3);
}

TEST(DensityPlot, ZeroDensitiesAndAnUnknownCoMStillDraw) {
  HandMade h = HandMadeFit(0.0, 0.0);
  h.fit.params.com = Vec3(std::nan(""), 0, 0);
  absl::StatusOr<std::string> svg =
      DensityPlotSvg(h.mesh, h.fit, {.title = "", .true_com = Vec3(0.01, 0, 0)});
  ASSERT_TRUE(svg.ok()) << svg.status();
  const std::vector<std::string> fills = PathFills(*svg);
  EXPECT_EQ(std::set<std::string>(fills.begin(), fills.end()),
            (std::set<std::string>{"#440154", "#d0d0d0"}));
  EXPECT_NE(svg->find(">1000<"), std::string::npos)
      << "the bar runs 0 .. 1000 when all densities are 0";
  EXPECT_EQ(svg->find("fitted-com"), std::string::npos) << "no marker for a CoM that is not finite";
  EXPECT_EQ(Count(*svg, "class=\"true-com\""), 3);
}

TEST(DensityPlot, NearSideIsDrawnLast) {
  const HandMade h = HandMadeFit(1000.0, 8000.0);
  absl::StatusOr<std::string> svg = DensityPlotSvg(h.mesh, h.fit);
  ASSERT_TRUE(svg.ok()) << svg.status();
  // View 1 looks down the z axis from +z: the far box (region 0) is hidden
  // behind the near one (region 1), so the near one's colour comes last.
  const std::vector<std::string> fills = PathFills(*svg, View(*svg, 1));
  ASSERT_EQ(fills.size(), 3u) << View(*svg, 1);
  EXPECT_EQ(fills.back(), "#fde725");
  EXPECT_NE(fills.front(), "#fde725");
  // Turning the fit's axes over (x -> -x, z -> -z, still right-handed) puts
  // the other box in front.
  HandMade flipped = h;
  flipped.fit.principal_axes = Eigen::Vector3d(-1, 1, -1).asDiagonal();
  svg = DensityPlotSvg(flipped.mesh, flipped.fit);
  ASSERT_TRUE(svg.ok()) << svg.status();
  const std::vector<std::string> again = PathFills(*svg, View(*svg, 1));
  ASSERT_EQ(again.size(), 3u);
  EXPECT_NE(again.back(), "#fde725");
  EXPECT_EQ(std::count(again.begin(), again.end(), "#fde725"), 1);
}

// The frames of the three views: (width, height) in px.
std::vector<std::pair<double, double>> Frames(const std::string& svg) {
  std::vector<std::pair<double, double>> out;
  static const std::regex re(
      "<rect class=\"frame\" x=\"[-0-9.]+\" y=\"[-0-9.]+\" width=\"([0-9.]+)\" "
      "height=\"([0-9.]+)\"");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), re); it != std::sregex_iterator();
       ++it)
    out.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  return out;
}

TEST(DensityPlot, OneScaleInAllViews) {
  const HandMade h = HandMadeFit(1000.0, 2000.0);
  absl::StatusOr<std::string> svg = DensityPlotSvg(h.mesh, h.fit);
  ASSERT_TRUE(svg.ok()) << svg.status();
  const auto frames = Frames(*svg);
  ASSERT_EQ(frames.size(), 3u);
  // Extents: x 0.2 m, y 0.06 m, z 0.1 m; each frame adds 10 px around the mesh.
  const double pad = 2 * 10;
  const double scale = (frames[0].first - pad) / 0.2;  // px per metre
  EXPECT_NEAR((frames[1].first - pad) / 0.2, scale, 0.01 * scale);
  EXPECT_NEAR((frames[2].first - pad) / 0.06, scale, 0.01 * scale);
  // One height for all, the tallest (z, 0.1 m).
  for (const auto& f : frames) EXPECT_NEAR((f.second - pad) / 0.1, scale, 0.01 * scale);
  // Tick labels in mm from the fitted CoM: the x axis runs -100 .. 100.
  EXPECT_NE(View(*svg, 1).find(">-100<"), std::string::npos);
  EXPECT_NE(View(*svg, 1).find(">100<"), std::string::npos);
  EXPECT_NE(svg->find("axis 1 (mm)"), std::string::npos);
}

TEST(DensityPlot, ContradictedMeshIsSaidUnderTheTitle) {
  HandMade h = HandMadeFit(1000.0, 2000.0);
  h.fit.mesh_contradicted = true;
  absl::StatusOr<std::string> svg =
      DensityPlotSvg(h.mesh, h.fit, {.title = "Hammer", .true_com = std::nullopt});
  ASSERT_TRUE(svg.ok()) << svg.status();
  const size_t title = svg->find(">Hammer<");
  const size_t warning = svg->find("mesh contradicted by the data: densities of the rejected fit");
  ASSERT_NE(title, std::string::npos);
  ASSERT_NE(warning, std::string::npos);
  EXPECT_LT(title, warning);
  EXPECT_NE(svg->find("colour-bar"), std::string::npos) << "the rejected densities are still drawn";
}

TEST(DensityPlot, ClosedMeshShowsOnlyItsFrontFaces) {
  const HandMade h = HandMadeFit(1000.0, 2000.0);
  absl::StatusOr<std::string> svg = DensityPlotSvg(h.mesh, h.fit);
  ASSERT_TRUE(svg.ok()) << svg.status();
  // Looking along each axis, each of the three boxes shows one face (two
  // triangles): the face towards the viewer; the one behind it is culled and
  // the four side faces are edge-on.
  for (int view = 1; view <= 3; ++view)
    EXPECT_EQ(DrawnTriangles(View(*svg, view)), 6) << "view " << view;
}

TEST(DensityPlot, OpenMeshKeepsItsBackFaces) {
  HandMade h = HandMadeFit(1000.0, 2000.0);
  // Remove the near box's top (+z) face: the mesh is open, so nothing is
  // culled and view 1 shows that box's bottom face through the hole.
  h.mesh.triangles.erase(h.mesh.triangles.begin() + 14, h.mesh.triangles.begin() + 16);
  auto model = std::make_shared<RegionModel>(*h.fit.region_model);
  model->triangle_region.erase(model->triangle_region.begin() + 14,
                               model->triangle_region.begin() + 16);
  h.fit.region_model = model;
  absl::StatusOr<std::string> svg = DensityPlotSvg(h.mesh, h.fit);
  ASSERT_TRUE(svg.ok()) << svg.status();
  // Faces seen face-on in view 1: two per box top/bottom (2 x 2 + 1 x 2 + 2 x 2
  // for the small box), the side faces are edge-on (no area).
  EXPECT_EQ(DrawnTriangles(View(*svg, 1)), 10);
}

TEST(DensityPlot, FitWithoutRegionsIsAGreySilhouette) {
  const TwoMaterial box = TwoMaterialBox();
  InertiaOptions o;
  o.method = InertiaMethod::kConstrained;
  const InertiaSamples samples = WristSamples(box.params, &o);
  absl::StatusOr<InertiaFit> fit = FitInertia(samples, o);
  ASSERT_TRUE(fit.ok()) << fit.status();
  ASSERT_EQ(fit->region_model, nullptr);
  absl::StatusOr<std::string> svg = DensityPlotSvg(box.mesh, *fit);
  ASSERT_TRUE(svg.ok()) << svg.status();
  const std::vector<std::string> fills = PathFills(*svg);
  ASSERT_FALSE(fills.empty());
  EXPECT_EQ(std::set<std::string>(fills.begin(), fills.end()), std::set<std::string>{"#d0d0d0"});
  EXPECT_EQ(svg->find("colour-bar"), std::string::npos);
  EXPECT_EQ(svg->find("kg/m³"), std::string::npos);
  EXPECT_NE(svg->find(">constrained fit<"), std::string::npos);
  EXPECT_NE(svg->find("no density regions"), std::string::npos);
  EXPECT_EQ(Count(*svg, "class=\"fitted-com\""), 3);
}

TEST(DensityPlot, BadInputIsInvalidArgument) {
  const HandMade h = HandMadeFit(1000.0, 2000.0);
  auto error = [](const TriangleMesh& mesh, const InertiaFit& fit) {
    absl::StatusOr<std::string> svg = DensityPlotSvg(mesh, fit);
    EXPECT_FALSE(svg.ok());
    EXPECT_EQ(svg.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(svg.status().message());
  };
  EXPECT_NE(error(TriangleMesh{}, h.fit).find("the mesh is empty"), std::string::npos);
  TriangleMesh fewer = h.mesh;
  fewer.triangles.pop_back();
  EXPECT_NE(error(fewer, h.fit).find("the mesh has 35 triangles but the fit's region model has 36"),
            std::string::npos)
      << error(fewer, h.fit);
  InertiaFit short_fit = h.fit;
  short_fit.densities.pop_back();
  EXPECT_NE(error(h.mesh, short_fit).find("1 densities for 2 regions"), std::string::npos);
  TriangleMesh bad_index = h.mesh;
  bad_index.triangles[3][1] = 99;
  EXPECT_NE(error(bad_index, h.fit).find("mesh.triangles[3]: vertex index 99"), std::string::npos);
}

}  // namespace
}  // namespace tactforce::inertia
