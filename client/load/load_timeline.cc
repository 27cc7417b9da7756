// CompletionTimeline (load_timeline.h): per-interval completion counters in
// lazily allocated chunks (a chunk is installed with one compare-exchange;
// the loser of a race frees its copy).
#include "load_timeline.h"

#include <algorithm>

namespace tactforce::cli {

CompletionTimeline::~CompletionTimeline() {
  for (std::atomic<Chunk*>& chunk : chunks_) delete chunk.load(std::memory_order_acquire);
}

CompletionTimeline::Chunk* CompletionTimeline::ChunkAt(int64_t index) {
  std::atomic<Chunk*>& slot = chunks_[static_cast<size_t>(index)];
  Chunk* chunk = slot.load(std::memory_order_acquire);
  if (chunk != nullptr) return chunk;
  auto* fresh = new Chunk;
  if (slot.compare_exchange_strong(chunk, fresh, std::memory_order_acq_rel)) return fresh;
  delete fresh;
  return chunk;  // installed by another thread meanwhile
}

void CompletionTimeline::Record(int64_t since_start_ns, bool ok) {
  const int64_t last = int64_t{kMaxChunks} * kChunkIntervals - 1;
  const int64_t interval = std::clamp<int64_t>(since_start_ns / kIntervalNs, 0, last);
  Chunk* chunk = ChunkAt(interval / kChunkIntervals);
  const size_t at = static_cast<size_t>(interval % kChunkIntervals);
  (ok ? chunk->ok[at] : chunk->failed[at]).fetch_add(1, std::memory_order_relaxed);
}

CompletionCounts CompletionTimeline::Counts(int64_t end_ns) const {
  const int64_t last = int64_t{kMaxChunks} * kChunkIntervals - 1;
  const int64_t intervals = std::clamp<int64_t>(end_ns / kIntervalNs, 0, last) + 1;
  CompletionCounts counts;
  counts.interval_s = kIntervalNs * 1e-9;
  counts.ok.assign(static_cast<size_t>(intervals), 0);
  counts.failed.assign(static_cast<size_t>(intervals), 0);
  for (int64_t i = 0; i < intervals; ++i) {
    const Chunk* chunk =
        chunks_[static_cast<size_t>(i / kChunkIntervals)].load(std::memory_order_acquire);
    if (chunk == nullptr) {
      i += kChunkIntervals - 1 - i % kChunkIntervals;  // the rest of this chunk is empty
      continue;
    }
    const size_t at = static_cast<size_t>(i % kChunkIntervals);
    counts.ok[static_cast<size_t>(i)] = chunk->ok[at].load(std::memory_order_relaxed);
    counts.failed[static_cast<size_t>(i)] = chunk->failed[at].load(std::memory_order_relaxed);
  }
  return counts;
}

}  // namespace tactforce::cli
