// User-space instructions retired by this thread, from the kernel's
// perf_event_open counter (Linux; needs perf_event_paranoid <= 2, the
// default). When the counter is unavailable (containers, other kernels)
// available() is false and benches print "n/a"; then count with callgrind:
//   valgrind --tool=callgrind --toggle-collect='*TimedWorkspaceSolve*' \
//     build/bin/planner_bench --benchmark_filter='BM_Workspace/4$' --benchmark_min_time=0.01
// and divide the total Ir by the calls of TimedWorkspaceSolve
// (scripts/count_instructions.sh does both).
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
