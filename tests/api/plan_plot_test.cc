// api/plan_plot.h: the scene (the robust cones as drawn are inside the
// planner's tightened rows; the exact cone is the tightened cone; the spread
// is S_ii) and the SVG read back with a tiny tag walk over the classes and
// ids the module promises (one glyph per contact per view, CoM, gravity,
// legend with units, trajectory panels).
#include "tactforce/api/plan_plot.h"

#include <cmath>
#include <map>
#include <numbers>
#include <regex>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/api/services.h"
#include "tactforce/planner/force_model.h"
#include "tactforce/planner/validation.h"

namespace tactforce::api {
namespace {

using ::testing::HasSubstr;

constexpr char kPinch[] = R"({
  "object": {"mass": 0.082},
  "contacts": [
    {"name": "thumb", "position": {"x": 0.03}, "normal": {"x": -1}, "friction": 0.8, "sigma": 0.2},
    {"name": "index", "position": {"x": -0.03}, "normal": {"x": 1}, "friction": 0.8, "sigma": 0.2}
  ]
})";

// Three fingers, tilted normals, an off-centre CoM and sideways gravity.
constexpr char kThreeFingers[] = R"({
  "object": {"mass": 0.3, "com": {"x": 0.01, "z": 0.005}, "gravity": {"y": -1.7, "z": -9.66}},
  "contacts": [
    {"name": "index", "position": {"x": 0.02, "y": 0.012}, "normal": {"y": -1, "z": 0.2}, "friction": 0.9, "sigma": 0.5},
    {"name": "middle", "position": {"x": -0.02, "y": 0.012}, "normal": {"y": -1, "x": 0.1}, "friction": 0.9, "sigma": 0.5},
    {"name": "thumb", "position": {"y": -0.012}, "normal": {"y": 1}, "friction": 0.9, "sigma": 0.5}
  ],
  "cone_sides": 8,
  "confidence": 1.5
})";

v1::PlanRequest Request(const char* json) {
  absl::StatusOr<v1::PlanRequest> request = ParsePlanRequestJson(json);
  EXPECT_TRUE(request.ok()) << request.status();
  return request.ok() ? *request : v1::PlanRequest();
}

// A <g> that carries a class, where it sits.
struct Glyph {
  std::string css_class, view, contact, step;
  std::string body;  // the element tags inside it (names only, in order)
};

// Walks the tags of `svg`: checks that they nest, and lists every classed
// <g> with the view and step panel around it and the tags inside it.
std::vector<Glyph> Walk(const std::string& svg) {
  static const std::regex tag(R"(<(/?)([a-zA-Z]+)([^>]*?)(/?)>)");
  static const std::regex cls(R"(class="([^"]*)\")"), id(R"(\bid="([^"]*)\")"),
      contact(R"(data-contact="(\d+)\")"), step(R"(data-step="(\d+)\")");
  auto attr = [](const std::string& attrs, const std::regex& re) {
    std::smatch m;
    return std::regex_search(attrs, m, re) ? m[1].str() : std::string();
  };
  std::vector<Glyph> out;
  std::vector<std::pair<std::string, int>> stack;  // open tag, index into `out` or -1
  std::string view, panel;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), tag); it != std::sregex_iterator();
       ++it) {
    const std::string name = (*it)[2], attrs = (*it)[3];
    const bool closing = (*it)[1] == "/", empty = (*it)[4] == "/";
    if (closing) {
      EXPECT_FALSE(stack.empty()) << "</" << name << "> without an open tag";
      if (stack.empty()) return out;
      EXPECT_EQ(stack.back().first, name);
      stack.pop_back();
      continue;
    }
    for (const auto& [open, index] : stack)
      if (index >= 0) out[index].body += name + " ";
    if (name == "g" && attr(attrs, cls) == "view") view = attr(attrs, id);
    if (name == "g" && attr(attrs, cls) == "step-panel") panel = attr(attrs, step);
    int index = -1;
    if (name == "g" && !attr(attrs, cls).empty()) {
      out.push_back({attr(attrs, cls), view, attr(attrs, contact), panel, ""});
      index = static_cast<int>(out.size()) - 1;
    }
    if (!empty) stack.push_back({name, index});
  }
  EXPECT_TRUE(stack.empty()) << stack.size() << " tags left open";
  return out;
}

// How many glyphs of `css_class` each (step, view, contact) has.
std::map<std::string, int> Counts(const std::vector<Glyph>& glyphs, const std::string& css_class) {
  std::map<std::string, int> n;
  for (const Glyph& g : glyphs)
    if (g.css_class == css_class) ++n[g.step + "/" + g.view + "/" + g.contact];
  return n;
}

void ExpectOnePerContactPerView(const std::vector<Glyph>& glyphs, int contacts,
                                const std::string& step, const std::string& prefix) {
  for (const char* css : {"cone", "force-arrow", "spread-ellipse", "contact-point", "normal"}) {
    const std::map<std::string, int> n = Counts(glyphs, css);
    for (const char* view : {"view-xy", "view-xz", "view-yz"})
      for (int i = 0; i < contacts; ++i) {
        const std::string key = step + "/" + prefix + view + "/" + std::to_string(i);
        EXPECT_EQ(n.count(key) ? n.at(key) : 0, 1) << css << " " << key;
      }
  }
  for (const char* css : {"com", "gravity"}) {
    const std::map<std::string, int> n = Counts(glyphs, css);
    for (const char* view : {"view-xy", "view-xz", "view-yz"}) {
      const std::string key = step + "/" + prefix + view + "/";
      EXPECT_EQ(n.count(key) ? n.at(key) : 0, 1) << css << " " << key;
    }
  }
}

int CountOf(const std::string& s, const std::string& what) {
  int n = 0;
  for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

TEST(PlanPlot, EveryContactHasOneOfEachGlyphInEveryView) {
  for (const char* json : {kPinch, kThreeFingers}) {
    const v1::PlanRequest request = Request(json);
    absl::StatusOr<v1::PlanResponse> response = HandlePlan(request);
    ASSERT_TRUE(response.ok()) << response.status();
    ASSERT_EQ(response->status(), v1::PLAN_STATUS_OPTIMAL);
    absl::StatusOr<std::string> svg = PlanSvg(request, *response);
    ASSERT_TRUE(svg.ok()) << svg.status();
    EXPECT_EQ(svg->rfind("<svg xmlns=\"http://www.w3.org/2000/svg\"", 0), 0u);
    const std::vector<Glyph> glyphs = Walk(*svg);
    ExpectOnePerContactPerView(glyphs, request.contacts_size(), "", "");
    int views = 0;
    for (const Glyph& g : glyphs) {
      if (g.css_class == "view") ++views;
      if (g.css_class == "force-arrow") {
        EXPECT_EQ(g.body, "line path ") << "shaft and head";
      }
      if (g.css_class == "spread-ellipse") {
        EXPECT_EQ(g.body, "ellipse ");
      }
      if (g.css_class == "cone") {
        EXPECT_EQ(g.body, "path path ") << "rim and edges";
      }
      if (g.css_class == "gravity") {
        EXPECT_THAT(g.body, HasSubstr("path")) << "an arrow head or the away cross";
      }
    }
    EXPECT_EQ(views, 3);
    EXPECT_EQ(CountOf(*svg, "id=\"legend\""), 1);
    EXPECT_THAT(*svg, HasSubstr("N per m (1 N = "));
    EXPECT_THAT(*svg, HasSubstr("positions in m"));
    for (const char* axis : {">x (m)</text>", ">y (m)</text>", ">z (m)</text>"})
      EXPECT_EQ(CountOf(*svg, axis), 2) << axis;
    EXPECT_THAT(*svg, HasSubstr("Plan: OPTIMAL"));
    EXPECT_EQ(*svg, *PlanSvg(request, *response)) << "deterministic";
  }
}

// The arrow starts on the contact's point; the thumb (+x, pushing -x) points
// left in the x-y view; gravity (-z) is seen end on, away from you, in x-y.
TEST(PlanPlot, ArrowsStartAtTheirContactsAndPointAlongTheForce) {
  const v1::PlanRequest request = Request(kPinch);
  const v1::PlanResponse response = *HandlePlan(request);
  const std::string svg = *PlanSvg(request, response);
  const std::regex point(
      R"re(<g class="contact-point" data-contact="0">\n<circle cx="([-\d.]+)" cy="([-\d.]+)")re");
  const std::regex arrow(
      R"re(<g class="force-arrow" data-contact="0">\n<line x1="([-\d.]+)" y1="([-\d.]+)" x2="([-\d.]+)" y2="([-\d.]+)")re");
  std::smatch p, a;
  ASSERT_TRUE(std::regex_search(svg, p, point));
  ASSERT_TRUE(std::regex_search(svg, a, arrow));
  EXPECT_EQ(p[1], a[1]);
  EXPECT_EQ(p[2], a[2]);
  EXPECT_LT(std::stod(a[3]), std::stod(a[1]) - 10) << "toward -x";
  const size_t xy = svg.find("id=\"view-xy\""), gravity = svg.find("class=\"gravity\"", xy);
  ASSERT_NE(gravity, std::string::npos);
  EXPECT_THAT(svg.substr(gravity, 300), HasSubstr("l8,8m0,-8l-8,8")) << "the away cross";
}

TEST(PlanPlot, ThePyramidAsDrawnLiesInsideEveryTightenedRowAndTouchesOne) {
  const v1::PlanRequest request = Request(kThreeFingers);
  const PlanCall call = *FromProto(request);
  const absl::StatusOr<PlanScene> scene =
      BuildPlanScene(call.problem, call.options, v1::PlanResponse());
  ASSERT_TRUE(scene.ok()) << scene.status();
  const planner::PreparedProblem prepared =
      planner::Prepare(*planner::ValidateProblem(call.problem, call.options), call.options);
  ASSERT_EQ(scene->contacts.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const ContactGlyph& c = scene->contacts[i];
    EXPECT_EQ(c.cone_sides, 8);
    EXPECT_FALSE(c.has_force);
    EXPECT_GT(c.apex_shift, 0);
    EXPECT_TRUE(c.covariance.isApprox(prepared.ellipsoid.ContactCovariance(i)));
    const planner::Vec3 apex = c.apex_shift * c.normal;
    double tightest = -1e300;
    for (size_t r = 0; r < prepared.rows.info.size(); ++r) {
      if (prepared.rows.info[r].contact != i ||
          prepared.rows.info[r].kind != planner::RowKind::kFrictionFacet)
        continue;
      const planner::Vec3 a = prepared.rows.directions.row(r).transpose();
      EXPECT_LE(a.dot(apex), prepared.rows.rhs(r) + 1e-12);
      tightest = std::max(tightest, a.dot(apex) - prepared.rows.rhs(r));
      for (int m = 0; m < c.cone_sides; ++m) {  // every edge direction stays inside
        const double phi = 2 * std::numbers::pi * (m + 0.5) / c.cone_sides;
        const planner::Vec3 edge =
            c.normal + c.friction * (std::cos(phi) * c.tangent1 + std::sin(phi) * c.tangent2);
        EXPECT_LE(a.dot(edge), 1e-12);
      }
    }
    EXPECT_NEAR(tightest, 0, 1e-12) << "the apex is on the most tightened facet";
  }
}

TEST(PlanPlot, TheExactConeAsDrawnIsTheTightenedCone) {
  v1::PlanRequest request = Request(kThreeFingers);
  request.set_cone(v1::CONE_MODEL_EXACT);
  const PlanCall call = *FromProto(request);
  const PlanScene scene = *BuildPlanScene(call.problem, call.options, v1::PlanResponse());
  const planner::PreparedProblem prepared =
      planner::Prepare(*planner::ValidateProblem(call.problem, call.options), call.options);
  for (int i = 0; i < 3; ++i) {
    const ContactGlyph& c = scene.contacts[i];
    EXPECT_EQ(c.cone_sides, 0);
    // Apex at shift/mu along n: mu n.f - shift = mu (n.f - apex_shift).
    EXPECT_NEAR(c.apex_shift * c.friction, prepared.cone_shift[i], 1e-12);
    const planner::Vec3 apex = c.apex_shift * c.normal;
    EXPECT_NEAR(planner::ExactConeSlack(c.normal, c.friction, prepared.cone_shift[i], apex), 0,
                1e-12);
  }
  const std::string svg = *PlanSvg(request, v1::PlanResponse());
  ExpectOnePerContactPerView(Walk(svg), 3, "", "");
  EXPECT_THAT(svg, HasSubstr("exactly the tightened cone"));
}

TEST(PlanPlot, AResponseWithoutForcesDrawsNoArrows) {
  const v1::PlanRequest request = Request(kPinch);
  v1::PlanResponse response;
  response.set_status(v1::PLAN_STATUS_INFEASIBLE);
  const std::string svg = *PlanSvg(request, response);
  for (const Glyph& g : Walk(svg)) {
    if (g.css_class == "force-arrow") {
      EXPECT_EQ(g.body, "");
    }
  }
  EXPECT_THAT(svg, HasSubstr("no forces in the response"));
  EXPECT_THAT(svg, HasSubstr("Plan: INFEASIBLE"));
}

TEST(PlanPlot, InvalidRequestNamesTheField) {
  v1::PlanRequest request = Request(kPinch);
  request.mutable_contacts(1)->mutable_normal()->Clear();
  absl::StatusOr<std::string> svg = PlanSvg(request, v1::PlanResponse());
  EXPECT_EQ(svg.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(svg.status().message()), HasSubstr("contacts[1].normal"));
}

TEST(PlanPlot, PlottedStepsSubsampleEvenlyWithBothEnds) {
  EXPECT_EQ(PlottedSteps(0), std::vector<int>{});
  EXPECT_EQ(PlottedSteps(3), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(PlottedSteps(24).size(), 24u);
  for (int n : {25, 50, 1000}) {
    const std::vector<int> shown = PlottedSteps(n);
    ASSERT_EQ(shown.size(), 24u) << n;
    EXPECT_EQ(shown.front(), 0);
    EXPECT_EQ(shown.back(), n - 1);
    for (size_t j = 1; j < shown.size(); ++j) EXPECT_GT(shown[j], shown[j - 1]);
  }
}

v1::TrajectoryRequest Trajectory(int steps) {
  v1::TrajectoryRequest request;
  *request.mutable_plan() = Request(kThreeFingers);
  request.mutable_plan()->mutable_object()->mutable_inertia()->set_ixx(4e-4);
  request.mutable_plan()->mutable_object()->mutable_inertia()->set_iyy(2.5e-3);
  request.mutable_plan()->mutable_object()->mutable_inertia()->set_izz(2.7e-3);
  for (int k = 0; k < steps; ++k) {
    v1::TrajectoryStep* step = request.add_steps();
    const double tilt = 0.3 * k / std::max(1, steps - 1);
    step->mutable_gravity()->set_y(-9.81 * std::sin(tilt));
    step->mutable_gravity()->set_z(-9.81 * std::cos(tilt));
    step->mutable_angular_velocity()->set_x(0.2);
  }
  return request;
}

TEST(PlanPlot, TrajectoryHasOnePanelPerStepWithThreeViews) {
  const v1::TrajectoryRequest request = Trajectory(4);
  absl::StatusOr<v1::TrajectoryResponse> response = HandleTrajectory(request);
  ASSERT_TRUE(response.ok()) << response.status();
  absl::StatusOr<std::string> svg = TrajectorySvg(request, *response);
  ASSERT_TRUE(svg.ok()) << svg.status();
  const std::vector<Glyph> glyphs = Walk(*svg);
  int panels = 0;
  for (const Glyph& g : glyphs) panels += g.css_class == "step-panel";
  EXPECT_EQ(panels, 4);
  for (int k = 0; k < 4; ++k) {
    const std::string s = std::to_string(k);
    ExpectOnePerContactPerView(glyphs, 3, s, "step" + s + "-");
  }
  EXPECT_THAT(*svg, HasSubstr("4 steps (4 optimal, 0 infeasible, 0 failed); one panel per step"));
  EXPECT_EQ(CountOf(*svg, "id=\"legend\""), 1);
}

TEST(PlanPlot, LongTrajectoriesShowAtMost24StepsAndSayWhich) {
  const v1::TrajectoryRequest request = Trajectory(30);
  const v1::TrajectoryResponse response = *HandleTrajectory(request);
  const std::string svg = *TrajectorySvg(request, response);
  EXPECT_EQ(CountOf(svg, "class=\"step-panel\""), kMaxPlotSteps);
  EXPECT_THAT(svg, HasSubstr("showing 24 evenly spaced steps: 0, 1, "));
  EXPECT_THAT(svg, HasSubstr(", 29</text>"));
  EXPECT_EQ(CountOf(svg, "data-step=\"29\""), 1);
}

}  // namespace
}  // namespace tactforce::api
