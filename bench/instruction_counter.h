// User-space instructions retired by this thread, from the kernel's
// perf_event_open counter (Linux; needs perf_event_paranoid <= 2, the
// default). When the counter is unavailable (containers, other kernels)
// available() is false and benches print "n/a"; then count with callgrind:
// scripts/count_instructions.sh [CONTACTS] [SOLVES] runs
//   planner_bench --callgrind-run=SOLVES,CONTACTS
// under valgrind --toggle-collect='*TimedWorkspaceSolve*' and divides.
#pragma once

#include <cstdint>

namespace tactforce::bench {

class InstructionCounter {
 public:
  InstructionCounter();
  ~InstructionCounter();
  InstructionCounter(const InstructionCounter&) = delete;
  InstructionCounter& operator=(const InstructionCounter&) = delete;

  bool available() const { return fd_ >= 0; }
  // Instructions since construction (0 when unavailable).
  uint64_t Read() const;

 private:
  int fd_ = -1;
};

}  // namespace tactforce::bench
