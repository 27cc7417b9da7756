// plan_grasp: plans the fingertip forces of a three-finger grasp with an
// installed tactforce (examples/cpp/CMakeLists.txt), twice:
//   1. through the library, tactforce::planner (CROSS_CHECK: the geometric
//      plan checked against Ipopt), printing the force of each finger;
//   2. through the wire API, tactforce::api (a tactforce.v1.PlanRequest
//      handled in process, exactly as tactforce-server would), printing the
//      response as JSON.
// Exit code 0 when both plans are optimal, agree and hold the object.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/api/services.h"
#include "tactforce/api/version.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/types.h"

namespace {

namespace planner = tactforce::planner;

// A 0.1 kg sphere (radius 3 cm) held at its equator by three fingers 120
// degrees apart; normals point into the object, gravity is -z.
planner::PlanProblem TripodGrasp() {
  planner::PlanProblem problem;
  problem.object.mass = 0.1;
  const char* names[] = {"thumb", "index", "middle"};
  for (int i = 0; i < 3; ++i) {
    const double angle = std::numbers::pi / 2 + i * 2 * std::numbers::pi / 3;
    planner::Contact c;
    c.name = names[i];
    c.position = 0.03 * planner::Vec3(std::cos(angle), std::sin(angle), 0);
    c.normal = -c.position.normalized();
    c.friction = 0.8;
    c.sigma = 0.2;
    c.min_normal_force = 0.2;
    problem.contacts.push_back(c);
  }
  return problem;
}

}  // namespace

int main() {
  std::printf("tactforce %s (%s build)\n", tactforce::api::kVersion, tactforce::api::kBuildType);
  const planner::PlanProblem problem = TripodGrasp();
  const planner::PlanOptions options;  // kappa 1, 12-sided pyramids

  // 1. The library.
  absl::StatusOr<planner::PlanResult> plan =
      planner::Plan(problem, options, planner::SolverKind::kCrossCheck);
  if (!plan.ok()) {
    std::fprintf(stderr, "plan: %s\n", plan.status().ToString().c_str());
    return 1;
  }
  std::printf("status: %s\n", planner::ToString(plan->status));
  planner::Vec3 total = problem.object.mass * problem.object.gravity;
  for (size_t i = 0; i < plan->forces.size(); ++i) {
    const planner::Vec3& f = plan->forces[i];
    total += f;
    std::printf("%-6s f = (%+.4f, %+.4f, %+.4f) N  normal %.4f N\n",
                problem.contacts[i].name.c_str(), f.x(), f.y(), f.z(), plan->normal_forces[i]);
  }
  const bool agree = plan->cross_check.has_value() && plan->cross_check->agree;
  std::printf("ipopt agrees: %s\n", agree ? "yes" : "no");
  std::printf("force balance residual: %.1e N\n", total.norm());

  // 2. The wire API, as the server runs it.
  const tactforce::v1::PlanRequest request =
      tactforce::api::ToRequest(problem, options, planner::SolverKind::kGeometric);
  absl::StatusOr<tactforce::v1::PlanResponse> response = tactforce::api::HandlePlan(request);
  if (!response.ok()) {
    std::fprintf(stderr, "api: %s\n", response.status().ToString().c_str());
    return 1;
  }
  std::printf("api response: %s\n", tactforce::api::ToJson(*response, /*compact=*/true).c_str());

  const bool ok = plan->status == planner::PlanStatus::kOptimal && agree && total.norm() < 1e-6 &&
                  response->status() == tactforce::v1::PLAN_STATUS_OPTIMAL;
  return ok ? 0 : 1;
}
