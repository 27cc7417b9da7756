#include "tactforce/api/table.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace tactforce::api {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

v1::PlanRequest TwoContacts() {
  v1::PlanRequest request;
  request.add_contacts()->set_name("thumb");
  request.add_contacts();  // unnamed: shown by index
  return request;
}

TEST(TableTest, OptimalPlan) {
  v1::PlanResponse r;
  r.set_status(v1::PLAN_STATUS_OPTIMAL);
  for (double s : {1.0, -1.0}) {
    v1::Vec3* f = r.add_forces();
    f->set_x(-2.5 * s);
    f->set_z(0.4);
    r.add_normal_forces(2.5);
    r.add_normal_force_sigma(0.125);
  }
  r.set_objective(12.82);
  r.set_min_margin(0.75);
  r.set_solver(v1::SOLVER_GEOMETRIC);
  r.set_solve_time_us(42);
  r.set_iterations(3);

  const std::string table = FormatPlanTable(TwoContacts(), r);
  EXPECT_THAT(table, HasSubstr("status:      OPTIMAL"));
  EXPECT_THAT(table, HasSubstr("thumb"));
  EXPECT_THAT(table, HasSubstr("#1"));
  EXPECT_THAT(table, HasSubstr("-2.50000"));
  EXPECT_THAT(table, HasSubstr("0.12500"));
  EXPECT_THAT(table, HasSubstr("objective:   12.82 N^2"));
  EXPECT_THAT(table, HasSubstr("min margin:  0.75 N"));
  EXPECT_THAT(table, HasSubstr("solver:      GEOMETRIC"));
  EXPECT_THAT(table, HasSubstr("time:        42 us"));
  EXPECT_THAT(table, HasSubstr("iterations:  3"));
  EXPECT_THAT(table, Not(HasSubstr("cross-check")));
  EXPECT_THAT(table, Not(HasSubstr("message:")));
}

TEST(TableTest, InfeasiblePlanWithoutForcesAndWithCrossCheck) {
  v1::PlanResponse r;
  r.set_status(v1::PLAN_STATUS_INFEASIBLE);
  r.set_message("contact 0 max normal force too small");
  r.set_solver(v1::SOLVER_CROSS_CHECK);
  r.mutable_cross_check()->set_agree(true);
  r.mutable_cross_check()->set_ipopt_status(v1::PLAN_STATUS_INFEASIBLE);
  r.mutable_cross_check()->set_ipopt_time_us(900);

  const std::string table = FormatPlanTable(TwoContacts(), r);
  EXPECT_THAT(table, HasSubstr("status:      INFEASIBLE"));
  EXPECT_THAT(table, HasSubstr("message:     contact 0 max normal force too small"));
  EXPECT_THAT(table, HasSubstr("thumb"));  // rows still listed, values "-"
  EXPECT_THAT(table, HasSubstr(" -"));
  EXPECT_THAT(table, HasSubstr("cross-check: agree"));
  EXPECT_THAT(table, HasSubstr("ipopt 900 us"));
  EXPECT_THAT(table, HasSubstr("ipopt status INFEASIBLE"));
  // No forces, so no objective or margin (they read as "0 N^2" otherwise).
  EXPECT_THAT(table, Not(HasSubstr("objective:")));
  EXPECT_THAT(table, Not(HasSubstr("min margin:")));
}

}  // namespace
}  // namespace tactforce::api
