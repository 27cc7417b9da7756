// Counts the heap allocations of a test binary: allocation_counter.cc
// replaces the global operator new (all forms), so link it into the test
// executable as a SOURCE (an object file, not a library member, so that the
// replacement is always taken).
//
//   const long before = tactforce::testing::AllocationCount();
//   ... code under test ...
//   EXPECT_EQ(tactforce::testing::AllocationCount() - before, 0);
//
// TACTFORCE_TRAP_ALLOCATION=1 in the environment makes ArmAllocationTrap()
// effective: the next allocation traps, so `gdb -ex run -ex bt` shows who
// allocated.
#pragma once

namespace tactforce::testing {

long AllocationCount();
// While armed (and TACTFORCE_TRAP_ALLOCATION is set) an allocation traps.
void ArmAllocationTrap(bool armed);

}  // namespace tactforce::testing
