// The load generator's callback engine: closed-loop slots of one call at a
// time (UnarySlot: the unary RPCs and FitInertia, load_rpcs.h), closed-loop
// PlanStream slots (StreamCall, a bidi reactor, and StreamSlot, which
// restarts a failed stream) and the open-loop dispatcher, all on gRPC's
// callback API and its threads; the driving thread runs Driver.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "connection.h"
#include "load_rpcs.h"

namespace tactforce::cli::load_engine {
namespace {

template <class Rpc>
struct UnaryCall {
  grpc::ClientContext context;
  typename Rpc::Response response;
  int64_t started_ns = 0;
};

// Completions that gRPC runs inline (on the thread that started the call,
// e.g. a call failing at once) would otherwise recurse without bound.
thread_local int inline_depth = 0;
constexpr int kMaxInlineDepth = 4;

// ------------------------------------------------- callback engine, unary

template <class Rpc>
class UnarySlot {
 public:
  UnarySlot(Run* run, int channel) : run_(run), channel_(channel) {}

  void Next() {
    int64_t ticket = 0;
    if (!run_->ClaimOrFinishSlot(&ticket)) return;
    auto* call = new UnaryCall<Rpc>;
    SetDeadline(&call->context, run_->spec.deadline_ms);
    call->started_ns = NowNs();
    Rpc::Start(*run_, channel_, &call->context, ticket, &call->response,
               [this, call](grpc::Status status) {
                 run_->Record(status.error_code(), call->started_ns);
                 delete call;
                 if (inline_depth >= kMaxInlineDepth) {
                   run_->Defer([this] { Next(); });
                   return;
                 }
                 ++inline_depth;
                 Next();
                 --inline_depth;
               });
  }

 private:
  Run* run_;
  int channel_;
};

// ------------------------------------------------ callback engine, stream

class StreamSlot;

// One PlanStream. Lives from Begin() to OnDone (which deletes it). A hold
// taken before StartCall keeps it alive until the driving thread releases
// it, so the watcher may TryCancel() it safely.
class StreamCall final : public grpc::ClientBidiReactor<v1::PlanRequest, v1::PlanResponse> {
 public:
  StreamCall(Run* run, StreamSlot* slot, int channel) : run_(run), slot_(slot) {
    run_->planners[channel]->async()->PlanStream(&context_, this);
  }

  // Starts the stream with `ticket`'s request.
  void Begin(int64_t ticket) {
    sent_ns_.store(NowNs(), std::memory_order_relaxed);
    outstanding_ = true;
    writing_ = true;
    AddHold();  // released by the driving thread (ReleaseIfFinishing)
    StartWrite(&run_->PlanRequestFor(ticket));
    StartRead(&response_);
    StartCall();
  }

  void OnWriteDone(bool ok) override {
    const v1::PlanRequest* next = nullptr;
    bool close = false;
    {
      std::lock_guard<std::mutex> lock(mu_);
      writing_ = false;
      if (!ok) return;  // the stream is broken; OnReadDone(false) / OnDone follow
      if (pending_ != nullptr) {
        next = std::exchange(pending_, nullptr);
        writing_ = true;
      } else if (close_pending_) {
        close_pending_ = false;
        close = true;
      }
    }
    if (next != nullptr) StartWrite(next);
    if (close) StartWritesDone();
  }

  void OnReadDone(bool ok) override {
    if (!ok) {
      MarkFinishing();
      return;
    }
    run_->RecordStreamResponse(sent_ns_.load(std::memory_order_relaxed));
    int64_t ticket = 0;
    const bool more = run_->Claim(&ticket);
    const v1::PlanRequest* write = nullptr;
    bool close = false;
    {
      std::lock_guard<std::mutex> lock(mu_);
      outstanding_ = more;
      if (more) {
        sent_ns_.store(NowNs(), std::memory_order_relaxed);
        const v1::PlanRequest* request = &run_->PlanRequestFor(ticket);
        if (writing_) {
          pending_ = request;
        } else {
          writing_ = true;
          write = request;
        }
      } else if (writing_) {
        close_pending_ = true;
      } else {
        close = true;
      }
    }
    if (write != nullptr) StartWrite(write);
    if (more) {
      StartRead(&response_);
    } else {
      if (close) StartWritesDone();
      MarkFinishing();  // no more reads: the server's status ends the stream
    }
  }

  void OnDone(const grpc::Status& status) override;

  // Driving thread: per-response deadline.
  void CheckDeadline(int64_t now_ns, int64_t deadline_ns) {
    bool cancel = false;
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (outstanding_ && !timed_out_ &&
          now_ns - sent_ns_.load(std::memory_order_relaxed) > deadline_ns) {
        timed_out_ = true;
        cancel = true;
      }
    }
    if (cancel) context_.TryCancel();  // safe: our hold keeps the call alive
  }

  // Driving thread: drops the hold once the stream needs no more watching;
  // OnDone may run (inline) and delete this. True when released.
  bool ReleaseIfFinishing() {
    if (!finishing_.load(std::memory_order_acquire)) return false;
    RemoveHold();
    return true;
  }

 private:
  void MarkFinishing() {
    finishing_.store(true, std::memory_order_release);
    run_->Wake();
  }

  Run* run_;
  StreamSlot* slot_;
  grpc::ClientContext context_;
  v1::PlanResponse response_;
  std::atomic<int64_t> sent_ns_{0};
  std::atomic<bool> finishing_{false};
  std::mutex mu_;
  bool outstanding_ = false;  // a request waits for its response
  bool writing_ = false;      // a write is in flight
  bool close_pending_ = false;
  bool timed_out_ = false;
  const v1::PlanRequest* pending_ = nullptr;  // next write, once the current one is done
};

// One closed-loop stream slot: restarts a failed stream while tickets last.
class StreamSlot final : public StreamWatch {
 public:
  StreamSlot(Run* run, int channel) : run_(run), channel_(channel) {}

  // Driving thread only.
  void Begin() {
    int64_t ticket = 0;
    if (!run_->ClaimOrFinishSlot(&ticket)) return;
    call_ = new StreamCall(run_, this, channel_);
    call_->Begin(ticket);
  }

  void Check(int64_t now_ns, int64_t deadline_ns) override {
    if (call_ == nullptr) return;
    if (deadline_ns > 0) call_->CheckDeadline(now_ns, deadline_ns);
    StreamCall* call = call_;
    // Cleared first: OnDone (maybe inline in RemoveHold) may restart the slot.
    call_ = nullptr;
    if (!call->ReleaseIfFinishing()) call_ = call;
  }

  // From StreamCall::OnDone (any thread).
  void Ended(bool failed) {
    if (failed) {
      run_->Defer([this] { Begin(); });
    } else {
      run_->SlotFinished();
    }
  }

 private:
  Run* run_;
  int channel_;
  StreamCall* call_ = nullptr;  // touched by the driving thread only
};

void StreamCall::OnDone(const grpc::Status& status) {
  bool outstanding = false;
  bool timed_out = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    outstanding = outstanding_;
    timed_out = timed_out_;
  }
  if (outstanding) {
    grpc::StatusCode code = status.error_code();
    if (timed_out) code = grpc::StatusCode::DEADLINE_EXCEEDED;
    if (code == grpc::StatusCode::OK) code = grpc::StatusCode::UNKNOWN;  // ended unanswered
    run_->Record(code, sent_ns_.load(std::memory_order_relaxed));
  }
  StreamSlot* slot = slot_;
  const bool failed = !status.ok() || outstanding;
  delete this;
  slot->Ended(failed);
}

// ------------------------------------------------ callback engine, open loop

constexpr auto kRoundWait = std::chrono::milliseconds(50);

// Starts call i at start + i / rate whatever the server does, with at most
// spec.concurrency in flight; latency counts from the scheduled start.
template <class Rpc>
class OpenLoop {
 public:
  OpenLoop(Run& run, int channels)
      : run_(run), channels_(channels), driver_(&run), interval_ns_(1e9 / run.spec.rate) {}

  // Until a bound or Ctrl-C, then until every call has ended; true when
  // interrupted.
  bool Dispatch() {
    const LoadSpec& spec = run_.spec;
    for (int64_t issued = 0;; ++issued) {
      const int64_t scheduled = run_.start_ns + static_cast<int64_t>(issued * interval_ns_);
      if (run_.stop.load() || scheduled >= run_.end_ns ||
          (spec.max_requests > 0 && issued >= spec.max_requests)) {
        break;
      }
      SleepUntil(scheduled);
      WaitForFreeSlot();
      if (run_.stop.load()) break;
      if (issued % 64 == 0) driver_.Housekeeping();
      Start(issued, scheduled);
    }
    WaitForAll();
    return driver_.interrupted();
  }

 private:
  // Until the call is due (housekeeping meanwhile).
  void SleepUntil(int64_t scheduled) {
    for (int64_t now = NowNs(); now < scheduled; now = NowNs()) {
      const int64_t left = scheduled - now;
      if (left > 2'000'000) {
        std::this_thread::sleep_for(
            std::chrono::nanoseconds(std::min<int64_t>(left, 50'000'000) - 1'000'000));
        driver_.Housekeeping();
      } else {
        std::this_thread::sleep_until(Clock::time_point(std::chrono::nanoseconds(scheduled)));
      }
    }
  }

  // Until fewer than spec.concurrency calls are in flight or the run stops.
  void WaitForFreeSlot() {
    std::unique_lock<std::mutex> lock(mu_);
    while (in_flight_.load() >= run_.spec.concurrency) {
      slot_free_.wait_for(lock, kRoundWait);
      driver_.Housekeeping();
      if (run_.stop.load()) break;
    }
  }

  void Start(int64_t issued, int64_t scheduled) {
    auto* call = new UnaryCall<Rpc>;
    SetDeadline(&call->context, run_.spec.deadline_ms);
    call->started_ns = scheduled;  // latency from the scheduled start
    in_flight_.fetch_add(1);
    run_.tickets.fetch_add(1, std::memory_order_relaxed);
    Rpc::Start(run_, static_cast<int>(issued % channels_), &call->context, issued, &call->response,
               [this, call](grpc::Status status) {
                 run_.Record(status.error_code(), call->started_ns);
                 delete call;
                 std::lock_guard<std::mutex> lock(mu_);
                 in_flight_.fetch_sub(1);
                 slot_free_.notify_all();
               });
  }

  void WaitForAll() {
    std::unique_lock<std::mutex> lock(mu_);
    while (in_flight_.load() > 0) {
      slot_free_.wait_for(lock, kRoundWait);
      lock.unlock();
      driver_.Housekeeping();
      lock.lock();
    }
  }

  Run& run_;
  const int channels_;
  Driver driver_;
  const double interval_ns_;
  std::atomic<int> in_flight_{0};
  std::mutex mu_;
  std::condition_variable slot_free_;
};

// ---------------------------------------------- callback engine, closed loop

template <class Rpc>
bool RunUnarySlots(Run& run, int channels) {
  std::vector<std::unique_ptr<UnarySlot<Rpc>>> slots;
  for (int i = 0; i < run.spec.concurrency; ++i) {
    slots.push_back(std::make_unique<UnarySlot<Rpc>>(&run, i % channels));
  }
  run.active = run.spec.concurrency;
  Driver driver(&run);
  for (auto& slot : slots) slot->Next();
  return driver.RunUntilSlotsFinish();
}

bool RunStreamSlots(Run& run, int channels) {
  std::vector<std::unique_ptr<StreamSlot>> slots;
  for (int i = 0; i < run.spec.concurrency; ++i) {
    slots.push_back(std::make_unique<StreamSlot>(&run, i % channels));
    run.watches.push_back(slots.back().get());
  }
  run.active = run.spec.concurrency;
  Driver driver(&run);
  for (auto& slot : slots) slot->Begin();
  return driver.RunUntilSlotsFinish();
}

}  // namespace

bool RunClosedLoopCallback(Run& run, int channels) {
  if (run.spec.rpc == LoadRpc::kStream) return RunStreamSlots(run, channels);
  return VisitRpc(run.spec.rpc,
                  [&](auto rpc) { return RunUnarySlots<decltype(rpc)>(run, channels); });
}

bool RunOpenLoop(Run& run, int channels) {
  return VisitRpc(run.spec.rpc,
                  [&](auto rpc) { return OpenLoop<decltype(rpc)>(run, channels).Dispatch(); });
}

}  // namespace tactforce::cli::load_engine
