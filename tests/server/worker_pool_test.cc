#include "tactforce/server/worker_pool.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace tactforce::server {
namespace {

// A latch the test opens to let blocked tasks finish.
class Gate {
 public:
  void Wait() {
    std::unique_lock<std::mutex> lock(mu_);
    cv_.wait(lock, [this] { return open_; });
  }
  void Open() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      open_ = true;
    }
    cv_.notify_all();
  }

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  bool open_ = false;
};

void WaitUntil(const std::function<bool()>& done) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!done() && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

TEST(WorkerPoolTest, RunsEveryAcceptedTask) {
  WorkerPool pool(3, 1000);
  std::atomic<int> ran{0};
  for (int i = 0; i < 500; ++i) ASSERT_TRUE(pool.TrySubmit([&] { ran.fetch_add(1); }));
  pool.Shutdown();
  EXPECT_EQ(ran.load(), 500);
  EXPECT_EQ(pool.stats().completed, 500);
}

TEST(WorkerPoolTest, RejectsInsteadOfGrowingTheQueue) {
  WorkerPool pool(2, 3);
  Gate gate;
  std::atomic<int> started{0}, ran{0};
  auto blocked = [&] {
    started.fetch_add(1);
    gate.Wait();
    ran.fetch_add(1);
  };
  // Two run, three wait; the sixth is turned away.
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(pool.TrySubmit(blocked)) << i;
  WaitUntil([&] { return started.load() == 2; });
  EXPECT_EQ(pool.stats().busy, 2);
  EXPECT_EQ(pool.stats().queued, 3);
  EXPECT_FALSE(pool.TrySubmit(blocked));
  EXPECT_EQ(pool.stats().rejected, 1);
  gate.Open();
  pool.Shutdown();
  EXPECT_EQ(ran.load(), 5);
}

TEST(WorkerPoolTest, ZeroQueueAcceptsOnlyWhatIdleWorkersTake) {
  WorkerPool pool(1, 0);
  Gate gate;
  std::atomic<int> started{0};
  ASSERT_TRUE(pool.TrySubmit([&] {
    started.fetch_add(1);
    gate.Wait();
  }));
  WaitUntil([&] { return started.load() == 1; });
  EXPECT_FALSE(pool.TrySubmit([] {}));
  gate.Open();
  WaitUntil([&] { return pool.stats().busy == 0; });
  EXPECT_TRUE(pool.TrySubmit([] {}));
}

TEST(WorkerPoolTest, ShutdownDrainsQueuedTasksAndRefusesNewOnes) {
  auto pool = std::make_unique<WorkerPool>(1, 10);
  Gate gate;
  std::atomic<int> ran{0};
  ASSERT_TRUE(pool->TrySubmit([&] {
    gate.Wait();
    ran.fetch_add(1);
  }));
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(pool->TrySubmit([&] { ran.fetch_add(1); }));
  std::thread stopper([&] { pool->Shutdown(); });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_FALSE(pool->TrySubmit([] {}));
  gate.Open();
  stopper.join();
  EXPECT_EQ(ran.load(), 5);
  pool->Shutdown();  // idempotent
}

TEST(WorkerPoolTest, AtLeastOneWorker) {
  WorkerPool pool(0, 4);
  EXPECT_EQ(pool.workers(), 1);
  std::atomic<bool> ran{false};
  ASSERT_TRUE(pool.TrySubmit([&] { ran = true; }));
  pool.Shutdown();
  EXPECT_TRUE(ran.load());
}

}  // namespace
}  // namespace tactforce::server
