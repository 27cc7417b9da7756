// The seed of the cases a test draws at run time. GoogleTest's random_seed()
// is drawn from the clock on every run unless --gtest_random_seed=N is given,
// and it is printed only when tests are shuffled; this prints it once per
// binary so that any failure can be replayed with --gtest_random_seed=N.
#pragma once

#include <cstdint>
#include <cstdio>

#include "gtest/gtest.h"

namespace tactforce::testing {

inline uint64_t GtestSeed() {
  static const uint64_t seed = [] {
    const int s = ::testing::UnitTest::GetInstance()->random_seed();
    std::printf("[ seed ] drawn cases: replay with --gtest_random_seed=%d\n", s);
    return static_cast<uint64_t>(s);
  }();
  return seed;
}

}  // namespace tactforce::testing
