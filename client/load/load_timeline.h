// Completions over time for `tactforce load --plot`: calls that ended in
// each 100 ms interval since the start of the run, successful and failed
// apart. Lock-free Record() from any thread; memory grows with the run in
// chunks of ~100 s (16 KiB each), up to ~116 hours (later completions count
// in the last interval).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

namespace tactforce::cli {

// Calls that ended per interval: ok[i] and failed[i] in
// [i * interval_s, (i + 1) * interval_s) after the start.
struct CompletionCounts {
  double interval_s = 0;
  std::vector<int64_t> ok;
  std::vector<int64_t> failed;
};

class CompletionTimeline {
 public:
  static constexpr int64_t kIntervalNs = 100'000'000;  // 0.1 s

  CompletionTimeline() = default;
  ~CompletionTimeline();
  CompletionTimeline(const CompletionTimeline&) = delete;
  CompletionTimeline& operator=(const CompletionTimeline&) = delete;

  // A call that ended `since_start_ns` after the start (negative: 0).
  void Record(int64_t since_start_ns, bool ok);

  // The intervals from the start up to the one holding `end_ns` after the
  // start (at least one).
  CompletionCounts Counts(int64_t end_ns) const;

 private:
  static constexpr int kChunkIntervals = 1024;
  static constexpr int kMaxChunks = 4096;
  struct Chunk {
    std::array<std::atomic<int64_t>, kChunkIntervals> ok{};
    std::array<std::atomic<int64_t>, kChunkIntervals> failed{};
  };
  Chunk* ChunkAt(int64_t index);

  std::array<std::atomic<Chunk*>, kMaxChunks> chunks_{};
};

}  // namespace tactforce::cli
