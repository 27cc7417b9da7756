#include "tactforce/inertia/metrics.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "tactforce/inertia/hull.h"
#include "tactforce/inertia/truth.h"

namespace tactforce::inertia {
namespace {

InertialParameters Make(double m, Vec3 c, std::array<double, 6> h) {
  InertialParameters p;
  p.mass = m;
  p.com = c;
  p.inertia_com = InertiaTensor::FromArray(h);
  return p;
}

TEST(InertiaMetrics, PseudoInertiaHandComputed) {
  // m = 2, c = (0.1, 0, 0), H_c = diag(0.02, 0.03, 0.04):
  // H_o = H_c + m(|c|^2 I - c c^T) = diag(0.02, 0.05, 0.06),
  // 1/2 tr(H_o) I - H_o = diag(0.045, 0.015, 0.005), m c = (0.2, 0, 0).
  const InertialParameters p = Make(2.0, Vec3(0.1, 0, 0), {0.02, 0.03, 0.04, 0, 0, 0});
  Eigen::Matrix4d expected;
  expected << 0.045, 0, 0, 0.2,  //
      0, 0.015, 0, 0,            //
      0, 0, 0.005, 0,            //
      0.2, 0, 0, 2.0;
  EXPECT_LT((PseudoInertia(p) - expected).norm(), 1e-15);
  const InertialParameters back = FromPseudoInertia(expected);
  EXPECT_NEAR(back.mass, 2.0, 1e-15);
  EXPECT_LT((back.com - p.com).norm(), 1e-15);
  EXPECT_LT((back.inertia_com.Matrix() - p.inertia_com.Matrix()).norm(), 1e-15);
  EXPECT_TRUE(IsPhysicallyConsistent(p));
}

TEST(InertiaMetrics, StandardParametersRoundTrip) {
  const InertialParameters p =
      Make(1.3, Vec3(0.2, 0.5, 0.1), {0.4015, 0.1292, 0.4799, -0.1297, -0.0259, -0.0649});
  const Vector10d pi = p.ToStandard();
  EXPECT_NEAR(pi(0), 1.3, 1e-15);
  EXPECT_NEAR(pi(2), 0.65, 1e-15);
  // Ixx about the origin: 0.4015 + 1.3 (0.25 + 0.01) = 0.7395
  EXPECT_NEAR(pi(4), 0.7395, 1e-12);
  // Ixy about the origin: -0.1297 - 1.3 * 0.2 * 0.5 = -0.2597
  EXPECT_NEAR(pi(7), -0.2597, 1e-12);
  const InertialParameters q = InertialParameters::FromStandard(pi);
  EXPECT_LT((q.inertia_com.Matrix() - p.inertia_com.Matrix()).norm(), 1e-14);
  EXPECT_LT((q.com - p.com).norm(), 1e-15);
}

TEST(InertiaMetrics, PaperMetricZeroButEstimateWrong) {
  // Truth: m = 1, c = 0, second moment I -> P_gt = I (H_c = 2 I).
  const InertialParameters truth = Make(1.0, Vec3::Zero(), {2, 2, 2, 0, 0, 0});
  ASSERT_LT((PseudoInertia(truth) - Eigen::Matrix4d::Identity()).norm(), 1e-15);
  // Estimate: second moment diag(2, 0.5, 0.5) -> H_c = tr I - S = diag(1, 2.5, 2.5);
  // eig(P_gt^-1 P_est) = (2, 0.5, 0.5, 1) sums to 4: paper metric 0.
  const InertialParameters est = Make(1.0, Vec3::Zero(), {1.0, 2.5, 2.5, 0, 0, 0});
  const InertiaErrors e = CompareInertia(truth, est);
  EXPECT_NEAR(e.paper_metric, 0.0, 1e-14);
  EXPECT_NEAR(e.riemannian, std::sqrt(3.0) * std::log(2.0), 1e-12);  // 1.2006
  EXPECT_NEAR(e.mass_percent, 0.0, 1e-12);
  EXPECT_NEAR(e.com_mm, 0.0, 1e-12);
  EXPECT_TRUE(e.consistent);
}

TEST(InertiaMetrics, ScaledEstimate) {
  // Doubling every parameter doubles P: Tr = 8, eigenvalues all 2.
  const InertialParameters truth = Make(2.0, Vec3(0.1, 0, 0), {0.02, 0.03, 0.04, 0, 0, 0});
  InertialParameters est = truth;
  est.mass = 4.0;
  est.inertia_com = InertiaTensor::FromArray({0.04, 0.06, 0.08, 0, 0, 0});
  const InertiaErrors e = CompareInertia(truth, est);
  EXPECT_NEAR(e.paper_metric, 4.0, 1e-12);
  EXPECT_NEAR(e.riemannian, 2.0 * std::log(2.0), 1e-12);
  EXPECT_NEAR(e.mass_percent, 100.0, 1e-12);
  EXPECT_NEAR(e.com_mm, 0.0, 1e-12);
  const InertiaErrors same = CompareInertia(truth, truth);
  EXPECT_NEAR(same.paper_metric, 0.0, 1e-12);
  EXPECT_NEAR(same.riemannian, 0.0, 1e-7);
}

TEST(InertiaMetrics, InconsistentEstimate) {
  // Izz > Ixx + Iyy violates the triangle inequality.
  const InertialParameters truth = Make(1.0, Vec3(0.01, 0.02, 0.03), {0.02, 0.03, 0.04, 0, 0, 0});
  const InertialParameters bad = Make(1.0, Vec3(0.01, 0.02, 0.03), {0.01, 0.01, 0.05, 0, 0, 0});
  EXPECT_FALSE(IsPhysicallyConsistent(bad));
  EXPECT_LT(ScaledPseudoInertiaMinEigenvalue(bad), 0.0);
  const InertiaErrors e = CompareInertia(truth, bad);
  EXPECT_FALSE(e.consistent);
  EXPECT_TRUE(std::isinf(e.riemannian));
  EXPECT_TRUE(std::isfinite(e.paper_metric));
  // Negative mass: inconsistent.
  EXPECT_FALSE(IsPhysicallyConsistent(Make(-1.0, Vec3::Zero(), {1, 1, 1, 0, 0, 0})));
  // mass % and CoM mm.
  InertialParameters off = truth;
  off.mass = 1.05;
  off.com += Vec3(0.003, 0.004, 0);
  const InertiaErrors e2 = CompareInertia(truth, off);
  EXPECT_NEAR(e2.mass_percent, 5.0, 1e-9);
  EXPECT_NEAR(e2.com_mm, 5.0, 1e-9);
}

TEST(InertiaMetrics, PrincipalAxesAndBoxSize) {
  // Uniform box 0.3 x 0.2 x 0.1 m, 1.2 kg, rotated.
  const double m = 1.2;
  const Vec3 d =
      m / 12.0 * Vec3(0.2 * 0.2 + 0.1 * 0.1, 0.3 * 0.3 + 0.1 * 0.1, 0.3 * 0.3 + 0.2 * 0.2);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vec3(1, -1, 2).normalized()).toRotationMatrix();
  InertialParameters p;
  p.mass = m;
  p.inertia_com = InertiaTensor::FromMatrix(R * d.asDiagonal() * R.transpose());
  Vec3 moments;
  Eigen::Matrix3d axes;
  PrincipalAxes(p.inertia_com, &moments, &axes);
  EXPECT_NEAR(moments(0), d(0), 1e-14);
  EXPECT_NEAR(moments(2), d(2), 1e-14);
  EXPECT_NEAR(axes.determinant(), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(axes.col(0).dot(R.col(0))), 1.0, 1e-10);
  EXPECT_NEAR(EquivalentBoxSize(p), 0.3, 1e-12);
}

TEST(InertiaTruth, ParsesTheSharedFormat) {
  const std::string text = R"({
 "mass": 0.6897,
 "com": [ -8.3e-17, 0.15628, -0.00094 ],
 "inertia_com": [0.0068616296, 0.0005532019, 0.0063604132, 9.15e-08, -1.34e-07, -5.52629e-05],
 "gravity_world": [0.0, 0.0, -9.81],
 "source": "utiasSTARS/..., MIT license",
 "extra": {"nested": [1, "x"]}
})";
  absl::StatusOr<InertiaTruth> t = ParseTruthJson(text, "Hammer.truth.json");
  ASSERT_TRUE(t.ok()) << t.status();
  EXPECT_DOUBLE_EQ(t->params.mass, 0.6897);
  EXPECT_DOUBLE_EQ(t->params.com.y(), 0.15628);
  EXPECT_DOUBLE_EQ(t->params.inertia_com.iyz, -5.52629e-05);
  ASSERT_TRUE(t->gravity_world.has_value());
  EXPECT_DOUBLE_EQ(t->gravity_world->z(), -9.81);
  // Round trip through the writer.
  absl::StatusOr<InertiaTruth> back = ParseTruthJson(TruthToJson(*t), "x");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_DOUBLE_EQ(back->params.inertia_com.ixy, 9.15e-08);
}

TEST(InertiaTruth, ErrorsNameTheKey) {
  auto err = [](const std::string& text) {
    return std::string(ParseTruthJson(text, "t.json").status().message());
  };
  EXPECT_NE(err(R"({"mass": 1, "inertia_com": [1,1,1,0,0,0]})").find("missing key 'com'"),
            std::string::npos);
  EXPECT_NE(err(R"({"mass": 1, "com": [0,0], "inertia_com": [1,1,1,0,0,0]})")
                .find("key 'com': expected an array of 3"),
            std::string::npos);
  EXPECT_NE(err(R"({"mass": -1, "com": [0,0,0], "inertia_com": [1,1,1,0,0,0]})")
                .find("key 'mass': must be > 0"),
            std::string::npos);
  // Syntax errors name the file and line (the shared JSON reader of io/json.h).
  EXPECT_EQ(err("{\n\"mass\": 1,\n\"com\": [0,0,0] \"inertia_com\": []}").rfind("t.json:3:", 0), 0u)
      << err("{\n\"mass\": 1,\n\"com\": [0,0,0] \"inertia_com\": []}");
  EXPECT_EQ(err("").rfind("t.json", 0), 0u) << err("");
  EXPECT_NE(err("[1, 2]").find("expected a JSON object"), std::string::npos);
}

TEST(InertiaHull, CubeContainsAndRejectsFlatSets) {
  std::vector<Vec3> cube;
  for (int x : {0, 1})
    for (int y : {0, 1})
      for (int z : {0, 1}) cube.push_back(Vec3(x, y, z) * 0.1);
  cube.push_back(Vec3(0.05, 0.05, 0.05));  // interior point
  absl::StatusOr<ConvexHull> h = ComputeConvexHull(cube);
  ASSERT_TRUE(h.ok()) << h.status();
  EXPECT_EQ(h->vertices.size(), 8u);
  EXPECT_TRUE(h->Contains(Vec3(0.05, 0.02, 0.09)));
  EXPECT_TRUE(h->Contains(Vec3(0.1, 0.1, 0.1)));
  EXPECT_FALSE(h->Contains(Vec3(0.05, 0.05, 0.11)));
  EXPECT_NEAR(h->SignedDistanceBound(Vec3(0.05, 0.05, 0.13)), 0.03, 1e-12);
  std::vector<Vec3> flat = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
  absl::StatusOr<ConvexHull> f = ComputeConvexHull(flat);
  ASSERT_FALSE(f.ok());
  EXPECT_NE(f.status().message().find("coplanar"), std::string::npos);
  EXPECT_FALSE(ComputeConvexHull({Vec3(0, 0, 0), Vec3(1, 0, 0)}).ok());
}

}  // namespace
}  // namespace tactforce::inertia
