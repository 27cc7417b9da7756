// Short enum names from the generated descriptors (names.h): the same
// spellings the hand-written tables gave, and "UNKNOWN(n)" off the enum.
#include "tactforce/api/names.h"

#include <gtest/gtest.h>

#include "tactforce/v1/estimator.pb.h"
#include "tactforce/v1/inertia.pb.h"

namespace tactforce::api {
namespace {

TEST(ApiNamesTest, PlanStatus) {
  EXPECT_EQ(StatusName(v1::PLAN_STATUS_OPTIMAL), "OPTIMAL");
  EXPECT_EQ(StatusName(v1::PLAN_STATUS_INFEASIBLE), "INFEASIBLE");
  EXPECT_EQ(StatusName(v1::PLAN_STATUS_SOLVER_FAILURE), "SOLVER_FAILURE");
  EXPECT_EQ(StatusName(v1::PLAN_STATUS_UNSPECIFIED), "UNSPECIFIED");
  EXPECT_EQ(StatusName(static_cast<v1::PlanStatus>(7)), "UNKNOWN(7)");
}

TEST(ApiNamesTest, Solver) {
  EXPECT_EQ(SolverName(v1::SOLVER_GEOMETRIC), "GEOMETRIC");
  EXPECT_EQ(SolverName(v1::SOLVER_IPOPT), "IPOPT");
  EXPECT_EQ(SolverName(v1::SOLVER_CROSS_CHECK), "CROSS_CHECK");
  EXPECT_EQ(SolverName(v1::SOLVER_UNSPECIFIED), "UNSPECIFIED");
  EXPECT_EQ(SolverName(static_cast<v1::Solver>(-2)), "UNKNOWN(-2)");
}

TEST(ApiNamesTest, AnyApiEnum) {
  EXPECT_EQ(ShortEnumName(v1::ESTIMATE_METHOD_NORMAL_LSQ), "NORMAL_LSQ");
  EXPECT_EQ(ShortEnumName(v1::INERTIA_METHOD_FACTOR_GRAPH), "FACTOR_GRAPH");
  EXPECT_EQ(ShortEnumName(v1::CONE_MODEL_EXACT), "EXACT");
}

}  // namespace
}  // namespace tactforce::api
