// A fixed-size pool of worker threads with a bounded FIFO queue, for the
// CPU-heavy solves that must not run on gRPC's callback threads.
//
// Overload policy: TrySubmit() never blocks; it accepts a task while fewer
// than `workers + max_queued` accepted tasks are unfinished (one running per
// worker, up to `max_queued` waiting) and returns false otherwise; the
// caller turns that into RESOURCE_EXHAUSTED (api::RunCall does).
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "tactforce/api/dispatch.h"

namespace tactforce::server {

class WorkerPool final : public api::Executor {
 public:
  // workers >= 1 (smaller values mean 1), max_queued >= 0 (0: a task is
  // accepted only while a worker is free for it).
  WorkerPool(int workers, int max_queued);
  ~WorkerPool() override;  // Shutdown()

  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Queues `task`; false (task dropped) when the queue is full or the pool
  // is shut down. Thread-safe.
  bool TrySubmit(std::function<void()> task) override;

  // Stops accepting tasks, runs every task already queued, joins the
  // threads. Idempotent; must not be called from a worker.
  void Shutdown();

  int workers() const override { return workers_; }
  int max_queued() const override { return max_queued_; }

  struct Stats {
    int queued = 0;  // accepted tasks beyond one per worker (waiting)
    int busy = 0;    // workers running a task
    long long completed = 0;
    long long rejected = 0;
  };
  Stats stats() const;

 private:
  void Run();

  const int workers_;
  const int max_queued_;
  mutable std::mutex mu_;
  std::condition_variable ready_;
  std::deque<std::function<void()>> queue_;
  int busy_ = 0;  // tasks running
  long long completed_ = 0;
  long long rejected_ = 0;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace tactforce::server
