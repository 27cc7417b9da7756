// WorkerPool (worker_pool.h): threads that take tasks from one bounded FIFO
// queue under a mutex; Shutdown runs what is queued, then joins.
#include "tactforce/server/worker_pool.h"

#include <algorithm>
#include <utility>

namespace tactforce::server {

WorkerPool::WorkerPool(int workers, int max_queued)
    : workers_(std::max(1, workers)), max_queued_(std::max(0, max_queued)) {
  threads_.reserve(workers_);
  for (int i = 0; i < workers_; ++i) threads_.emplace_back([this] { Run(); });
}

WorkerPool::~WorkerPool() { Shutdown(); }

bool WorkerPool::TrySubmit(std::function<void()> task) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    // Capacity: one running task per worker plus max_queued_ waiting ones.
    // (Counted from tasks, not from idle threads, so it does not depend on
    // how far the worker threads have got.)
    const int accepted = static_cast<int>(queue_.size()) + busy_;
    if (stopping_ || accepted >= workers_ + max_queued_) {
      ++rejected_;
      return false;
    }
    queue_.push_back(std::move(task));
  }
  ready_.notify_one();
  return true;
}

void WorkerPool::Run() {
  std::unique_lock<std::mutex> lock(mu_);
  for (;;) {
    ready_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stopping and drained
    std::function<void()> task = std::move(queue_.front());
    queue_.pop_front();
    ++busy_;
    lock.unlock();
    task();
    task = nullptr;  // destroy captures outside the lock
    lock.lock();
    --busy_;
    ++completed_;
  }
}

void WorkerPool::Shutdown() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stopping_ && threads_.empty()) return;
    stopping_ = true;
  }
  ready_.notify_all();
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
  std::lock_guard<std::mutex> lock(mu_);
  threads_.clear();
}

WorkerPool::Stats WorkerPool::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  Stats s;
  s.queued = std::max(0, static_cast<int>(queue_.size()) + busy_ - workers_);
  s.busy = busy_;
  s.completed = completed_;
  s.rejected = rejected_;
  return s;
}

}  // namespace tactforce::server
