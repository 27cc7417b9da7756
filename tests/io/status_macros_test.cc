#include "tactforce/io/status_macros.h"

#include <random>
#include <string>

#include <gtest/gtest.h>

namespace tactforce::io {
namespace {

int g_evaluations = 0;

absl::Status Counted(absl::Status s) {
  ++g_evaluations;
  return s;
}

absl::StatusOr<int> CountedValue(absl::StatusOr<int> v) {
  ++g_evaluations;
  return v;
}

absl::Status ReturnsFirstError(bool fail_first, bool fail_second, int* reached) {
  TF_RETURN_IF_ERROR(Counted(fail_first ? absl::InvalidArgumentError("first") : absl::OkStatus()));
  *reached = 1;
  TF_RETURN_IF_ERROR(Counted(fail_second ? absl::NotFoundError("second") : absl::OkStatus()));
  *reached = 2;
  return absl::OkStatus();
}

absl::StatusOr<int> SumOfTwo(absl::StatusOr<int> a, absl::StatusOr<int> b) {
  TF_ASSIGN_OR_RETURN(int x, CountedValue(std::move(a)));
  TF_ASSIGN_OR_RETURN(const int y, CountedValue(std::move(b)));
  return x + y;
}

TEST(StatusMacros, ReturnIfErrorReturnsTheFirstErrorAndEvaluatesOnce) {
  for (int mask = 0; mask < 4; ++mask) {
    g_evaluations = 0;
    int reached = 0;
    const absl::Status s = ReturnsFirstError(mask & 1, mask & 2, &reached);
    if (mask & 1) {
      EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
      EXPECT_EQ(reached, 0);
      EXPECT_EQ(g_evaluations, 1);
    } else if (mask & 2) {
      EXPECT_EQ(s.code(), absl::StatusCode::kNotFound);
      EXPECT_EQ(reached, 1);
      EXPECT_EQ(g_evaluations, 2);
    } else {
      EXPECT_TRUE(s.ok());
      EXPECT_EQ(reached, 2);
      EXPECT_EQ(g_evaluations, 2);
    }
  }
}

TEST(StatusMacros, AssignOrReturnMovesValuesAndStopsAtTheFirstError) {
  std::mt19937 rng(20261127);
  std::uniform_int_distribution<int> value(-1000, 1000);
  for (int i = 0; i < 50; ++i) {
    const int a = value(rng), b = value(rng);
    g_evaluations = 0;
    absl::StatusOr<int> sum = SumOfTwo(a, b);
    ASSERT_TRUE(sum.ok());
    EXPECT_EQ(*sum, a + b);
    EXPECT_EQ(g_evaluations, 2);
  }
  g_evaluations = 0;
  absl::StatusOr<int> failed = SumOfTwo(absl::OutOfRangeError("a"), 3);
  EXPECT_EQ(failed.status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(g_evaluations, 1);
}

TEST(PrependPath, NestsOutermostFirstAndKeepsCodeAndPayload) {
  absl::Status inner = absl::InvalidArgumentError("must be > 0, got -1");
  inner.SetPayload("tactforce/field", absl::Cord("mass"));
  const absl::Status s = PrependPath(PrependPath(inner, "mass"), "object");
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(s.message(), "object: mass: must be > 0, got -1");
  ASSERT_TRUE(s.GetPayload("tactforce/field").has_value());
  EXPECT_EQ(std::string(*s.GetPayload("tactforce/field")), "mass");
}

TEST(PrependPath, DotSeparatorContinuesAFieldPath) {
  const absl::Status inner = absl::OutOfRangeError("contacts[1].normal: zero length");
  const absl::Status s = PrependPath(PrependPath(inner, "plan", "."), "request");
  EXPECT_EQ(s.code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(s.message(), "request: plan.contacts[1].normal: zero length");
  EXPECT_TRUE(PrependPath(absl::OkStatus(), "plan", ".").ok());
  EXPECT_EQ(PrependPath(inner, "", "."), inner);
}

TEST(PrependPath, LeavesOkAndEmptyPathAlone) {
  EXPECT_TRUE(PrependPath(absl::OkStatus(), "x").ok());
  const absl::Status e = absl::NotFoundError("gone");
  EXPECT_EQ(PrependPath(e, ""), e);
}

}  // namespace
}  // namespace tactforce::io
