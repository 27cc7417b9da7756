// Inside the load generator (load_generator.h): the state one run shares
// between its slots (Run: tickets, counters, latency histogram, completions
// over time, stubs), the driving thread's loop (Driver: deferred work,
// stream deadlines, progress, Ctrl-C), and the engines' entry points
// (callback engine in load_callback_engine.cc, sync engine in
// load_sync_engine.cc). How each RPC is issued: load_rpcs.h. Only load_*.cc
// include this.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "grpc/health/v1/health.grpc.pb.h"
#include "latency_histogram.h"
#include "load_spec.h"
#include "load_timeline.h"
#include "tactforce/v1/audit.grpc.pb.h"
#include "tactforce/v1/estimator.grpc.pb.h"
#include "tactforce/v1/planner.grpc.pb.h"

namespace tactforce::cli::load_engine {

using Clock = std::chrono::steady_clock;

// Nanoseconds on the steady clock.
int64_t NowNs();

inline constexpr int kCodeSlots = 17;  // gRPC's canonical codes 0..16; others share the last slot

// A stream whose progress the driving thread watches: per-response deadline
// (TryCancel) and, for callback streams, the hold that keeps the reactor
// alive while it may be cancelled.
class StreamWatch {
 public:
  virtual ~StreamWatch() = default;
  // The driving thread's periodic look: cancels the stream when its
  // outstanding request is older than `deadline_ns`.
  virtual void Check(int64_t now_ns, int64_t deadline_ns) = 0;
};

// State shared by every slot of one run.
class Run {
 public:
  Run(const LoadSpec& spec, const std::vector<std::shared_ptr<grpc::Channel>>& channels);

  // Claims the next call; false once a bound is reached or the run stops.
  bool Claim(int64_t* ticket);
  // Claim, and when there is nothing left the slot asking has finished.
  bool ClaimOrFinishSlot(int64_t* ticket);

  const v1::PlanRequest& PlanRequestFor(int64_t ticket) const {
    return spec.requests[static_cast<size_t>(ticket) % spec.requests.size()];
  }

  // A finished call started at `started_ns`: latency when OK, else an error
  // count under `code`; either way its latency in `all_histogram` and a
  // completion in the timeline.
  void Record(grpc::StatusCode code, int64_t started_ns);

  // A stream response to the request sent at `sent_ns`: a late one counts
  // as DEADLINE_EXCEEDED, like a unary call (the watcher cancels a stream
  // whose response is overdue, within a few milliseconds).
  void RecordStreamResponse(int64_t sent_ns);

  void SlotFinished();

  // Runs `fn` on the driving thread (used instead of deep recursion when
  // gRPC runs a completion inline, and to restart failed streams).
  void Defer(std::function<void()> fn);

  void Wake();

  const LoadSpec& spec;
  // One of each per channel.
  std::vector<std::unique_ptr<v1::Planner::Stub>> planners;
  std::vector<std::unique_ptr<grpc::health::v1::Health::Stub>> health;
  std::vector<std::unique_ptr<v1::Estimator::Stub>> estimators;
  std::vector<std::unique_ptr<v1::Audit::Stub>> audits;
  grpc::health::v1::HealthCheckRequest health_request;

  LatencyHistogram histogram;      // successful calls
  LatencyHistogram all_histogram;  // every call, whatever its status
  CompletionTimeline timeline;
  std::atomic<int64_t> tickets{0};
  std::atomic<int64_t> completed{0};
  std::atomic<int64_t> ok{0};
  std::array<std::atomic<int64_t>, kCodeSlots> errors{};
  std::atomic<int64_t> last_done_ns{0};
  std::atomic<bool> stop{false};
  int64_t start_ns = 0;
  int64_t end_ns = 0;

  std::mutex mu;
  std::condition_variable wake;
  int active = 0;  // slots not finished
  bool poke = false;
  std::vector<std::function<void()>> deferred;
  std::vector<StreamWatch*> watches;  // stable for the run
};

// ------------------------------------------------------------ the driver

// The driving thread's loop: Round() until every slot has finished, running
// deferred work, the stream watchers, progress and interruption checks. The
// open-loop dispatcher calls Housekeeping() between the calls it starts.
class Driver {
 public:
  explicit Driver(Run* run) : run_(run), next_progress_ns_(run->start_ns + 1'000'000'000) {}

  // How long Round() may sleep: short enough for the stream watchers to
  // cancel an overdue stream soon after its deadline.
  std::chrono::nanoseconds RoundWait() const;

  // One round of housekeeping; waits up to `wait` for something to do.
  // Returns false once every slot has finished and nothing is pending.
  bool Round(std::chrono::nanoseconds wait);

  // Stream deadlines, Ctrl-C, and the progress callback when one is due.
  void Housekeeping();

  // Runs Round() until every slot has finished; true when interrupted.
  bool RunUntilSlotsFinish();

  bool interrupted() const { return interrupted_; }

 private:
  void ReportProgress(int64_t now);

  Run* run_;
  int64_t next_progress_ns_;
  int64_t last_progress_ns_ = 0;
  int64_t last_completed_ = 0;
  bool interrupted_ = false;
};

// ------------------------------------------------------------ the engines
// Each returns true when the run was interrupted (Ctrl-C).

// Callback API, closed loop: `spec.concurrency` slots of unary calls or
// streams (load_callback_engine.cc).
bool RunClosedLoopCallback(Run& run, int channels);
// Callback API, open loop: calls on a fixed schedule (unary RPCs only).
bool RunOpenLoop(Run& run, int channels);
// Sync API: one thread per slot with blocking calls (load_sync_engine.cc).
bool RunSync(Run& run, int channels);

}  // namespace tactforce::cli::load_engine
