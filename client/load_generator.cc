#include "load_generator.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <limits>
#include <mutex>
#include <random>
#include <thread>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "connection.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "latency_histogram.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/planner/random_grasps.h"
#include "tactforce/v1/planner.grpc.pb.h"
#include "tactforce/io/json.h"

namespace tactforce::cli {
namespace {

using Clock = std::chrono::steady_clock;
using HealthStub = grpc::health::v1::Health::Stub;

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

constexpr int kCodeSlots = 17;  // gRPC's canonical codes 0..16; others share the last slot

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
  Run(const LoadSpec& spec, const std::vector<std::shared_ptr<grpc::Channel>>& channels)
      : spec(spec) {
    for (const auto& channel : channels) {
      planners.push_back(v1::Planner::NewStub(channel));
      health.push_back(grpc::health::v1::Health::NewStub(channel));
    }
    health_request.set_service(spec.health_service);
    start_ns = NowNs();
    end_ns = spec.duration_s > 0 ? start_ns + static_cast<int64_t>(spec.duration_s * 1e9)
                                 : std::numeric_limits<int64_t>::max();
  }

  // Claims the next call; false once a bound is reached or the run stops.
  bool Claim(int64_t* ticket) {
    if (stop.load(std::memory_order_relaxed) || NowNs() >= end_ns) return false;
    const int64_t t = tickets.fetch_add(1, std::memory_order_relaxed);
    if (spec.max_requests > 0 && t >= spec.max_requests) return false;
    *ticket = t;
    return true;
  }

  const v1::PlanRequest& PlanRequestFor(int64_t ticket) const {
    return spec.requests[static_cast<size_t>(ticket) % spec.requests.size()];
  }

  void Record(grpc::StatusCode code, int64_t started_ns) {
    const int64_t now = NowNs();
    if (code == grpc::StatusCode::OK) {
      histogram.Record(now - started_ns);
      ok.fetch_add(1, std::memory_order_relaxed);
    } else {
      const int slot = std::clamp(static_cast<int>(code), 0, kCodeSlots - 1);
      errors[slot].fetch_add(1, std::memory_order_relaxed);
    }
    completed.fetch_add(1, std::memory_order_relaxed);
    int64_t seen = last_done_ns.load(std::memory_order_relaxed);
    while (now > seen &&
           !last_done_ns.compare_exchange_weak(seen, now, std::memory_order_relaxed)) {
    }
  }

  // A stream response to the request sent at `sent_ns`: a late one counts
  // as DEADLINE_EXCEEDED, like a unary call (the watcher cancels a stream
  // whose response is overdue, within a few milliseconds).
  void RecordStreamResponse(int64_t sent_ns) {
    const bool late = spec.deadline_ms > 0 &&
                      NowNs() - sent_ns > int64_t{spec.deadline_ms} * 1'000'000;
    Record(late ? grpc::StatusCode::DEADLINE_EXCEEDED : grpc::StatusCode::OK, sent_ns);
  }

  void SlotFinished() {
    std::lock_guard<std::mutex> lock(mu);
    --active;
    wake.notify_all();
  }

  // Runs `fn` on the driving thread (used instead of deep recursion when
  // gRPC runs a completion inline, and to restart failed streams).
  void Defer(std::function<void()> fn) {
    std::lock_guard<std::mutex> lock(mu);
    deferred.push_back(std::move(fn));
    wake.notify_all();
  }

  void Wake() {
    std::lock_guard<std::mutex> lock(mu);
    poke = true;
    wake.notify_all();
  }

  const LoadSpec& spec;
  std::vector<std::unique_ptr<v1::Planner::Stub>> planners;
  std::vector<std::unique_ptr<HealthStub>> health;
  grpc::health::v1::HealthCheckRequest health_request;

  LatencyHistogram histogram;
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

// ------------------------------------------------------------------ RPCs

struct PlanRpc {
  using Response = v1::PlanResponse;
  static void Start(Run& run, int channel, grpc::ClientContext* context, int64_t ticket,
                    Response* response, std::function<void(grpc::Status)> done) {
    run.planners[channel]->async()->Plan(context, &run.PlanRequestFor(ticket), response,
                                          std::move(done));
  }
  static grpc::Status Call(Run& run, int channel, grpc::ClientContext* context, int64_t ticket,
                           Response* response) {
    return run.planners[channel]->Plan(context, run.PlanRequestFor(ticket), response);
  }
};

struct HealthRpc {
  using Response = grpc::health::v1::HealthCheckResponse;
  static void Start(Run& run, int channel, grpc::ClientContext* context, int64_t /*ticket*/,
                    Response* response, std::function<void(grpc::Status)> done) {
    run.health[channel]->async()->Check(context, &run.health_request, response,
                                        std::move(done));
  }
  static grpc::Status Call(Run& run, int channel, grpc::ClientContext* context,
                           int64_t /*ticket*/, Response* response) {
    return run.health[channel]->Check(context, run.health_request, response);
  }
};

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
    if (!run_->Claim(&ticket)) {
      run_->SlotFinished();
      return;
    }
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
    if (!run_->Claim(&ticket)) {
      run_->SlotFinished();
      return;
    }
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

// ------------------------------------------------------------ sync engine

// The context of the stream a sync thread is running, for the watcher.
class SyncStreamWatch final : public StreamWatch {
 public:
  void Attach(grpc::ClientContext* context) {
    std::lock_guard<std::mutex> lock(mu_);
    context_ = context;
    sent_ns_ = 0;
    timed_out_ = false;
  }
  void Detach() {
    std::lock_guard<std::mutex> lock(mu_);
    context_ = nullptr;
  }
  void Sent(int64_t ns) {
    std::lock_guard<std::mutex> lock(mu_);
    sent_ns_ = ns;
  }
  void Answered() { Sent(0); }
  bool timed_out() {
    std::lock_guard<std::mutex> lock(mu_);
    return timed_out_;
  }
  void Check(int64_t now_ns, int64_t deadline_ns) override {
    std::lock_guard<std::mutex> lock(mu_);  // sync TryCancel runs no callbacks
    if (context_ != nullptr && deadline_ns > 0 && sent_ns_ > 0 && !timed_out_ &&
        now_ns - sent_ns_ > deadline_ns) {
      timed_out_ = true;
      context_->TryCancel();
    }
  }

 private:
  std::mutex mu_;
  grpc::ClientContext* context_ = nullptr;
  int64_t sent_ns_ = 0;
  bool timed_out_ = false;
};

template <class Rpc>
void SyncUnaryLoop(Run* run, int channel) {
  int64_t ticket = 0;
  while (run->Claim(&ticket)) {
    grpc::ClientContext context;
    SetDeadline(&context, run->spec.deadline_ms);
    typename Rpc::Response response;
    const int64_t started = NowNs();
    const grpc::Status status = Rpc::Call(*run, channel, &context, ticket, &response);
    run->Record(status.error_code(), started);
  }
  run->SlotFinished();
}

void SyncStreamLoop(Run* run, int channel, SyncStreamWatch* watch) {
  int64_t ticket = 0;
  bool have_ticket = run->Claim(&ticket);
  while (have_ticket) {
    grpc::ClientContext context;
    watch->Attach(&context);
    auto stream = run->planners[channel]->PlanStream(&context);
    v1::PlanResponse response;
    bool broken = false;
    while (have_ticket) {
      const int64_t sent = NowNs();
      watch->Sent(sent);
      if (!stream->Write(run->PlanRequestFor(ticket)) || !stream->Read(&response)) {
        broken = true;
        break;
      }
      watch->Answered();
      run->RecordStreamResponse(sent);
      have_ticket = run->Claim(&ticket);
    }
    if (!broken) stream->WritesDone();
    const grpc::Status status = stream->Finish();
    const bool timed_out = watch->timed_out();
    watch->Detach();
    if (broken) {
      grpc::StatusCode code = timed_out ? grpc::StatusCode::DEADLINE_EXCEEDED
                                        : status.error_code();
      if (code == grpc::StatusCode::OK) code = grpc::StatusCode::UNKNOWN;
      run->Record(code, NowNs());
      have_ticket = run->Claim(&ticket);  // a new stream for the next request
    }
  }
  run->SlotFinished();
}

// ------------------------------------------------------------ the driver

// The driving thread's loop: Round() until every slot has finished, running
// deferred work, the stream watchers, progress and interruption checks. The
// open-loop dispatcher calls Housekeeping() between the calls it starts.
class Driver {
 public:
  explicit Driver(Run* run) : run_(run), next_progress_ns_(run->start_ns + 1'000'000'000) {}

  // How long Round() may sleep: short enough for the stream watchers to
  // cancel an overdue stream soon after its deadline.
  std::chrono::nanoseconds RoundWait() const {
    const int64_t base_ns = 50'000'000;
    if (run_->watches.empty() || run_->spec.deadline_ms <= 0) {
      return std::chrono::nanoseconds(base_ns);
    }
    const int64_t quarter_ns = int64_t{run_->spec.deadline_ms} * 250'000;
    return std::chrono::nanoseconds(std::clamp<int64_t>(quarter_ns, 2'000'000, base_ns));
  }

  // One round of housekeeping; waits up to `wait` for something to do.
  // Returns false once every slot has finished and nothing is pending.
  bool Round(std::chrono::nanoseconds wait) {
    std::vector<std::function<void()>> work;
    {
      std::unique_lock<std::mutex> lock(run_->mu);
      run_->wake.wait_for(lock, wait, [this] {
        return run_->active == 0 || !run_->deferred.empty() || run_->poke;
      });
      run_->poke = false;
      work.swap(run_->deferred);
      if (run_->active == 0 && work.empty()) return false;
    }
    for (auto& fn : work) fn();
    Housekeeping();
    return true;
  }

  void Housekeeping() {
    const int64_t now = NowNs();
    const int64_t deadline_ns = int64_t{run_->spec.deadline_ms} * 1'000'000;
    for (StreamWatch* watch : run_->watches) watch->Check(now, deadline_ns);
    if (run_->spec.interrupted && run_->spec.interrupted()) {
      run_->stop.store(true, std::memory_order_relaxed);
      interrupted_ = true;
    }
    if (run_->spec.progress && now >= next_progress_ns_) {
      const int64_t completed = run_->completed.load(std::memory_order_relaxed);
      LoadProgress progress;
      progress.elapsed_s = (now - run_->start_ns) * 1e-9;
      progress.completed = completed;
      progress.failed = completed - run_->ok.load(std::memory_order_relaxed);
      const double window_s = (now - last_progress_ns_) * 1e-9;
      progress.recent_qps =
          (completed - last_completed_) / std::max(window_s, 1e-9);
      if (last_progress_ns_ == 0) progress.recent_qps = completed / progress.elapsed_s;
      last_progress_ns_ = now;
      last_completed_ = completed;
      next_progress_ns_ = now + 1'000'000'000;
      run_->spec.progress(progress);
    }
  }

  bool interrupted() const { return interrupted_; }

 private:
  Run* run_;
  int64_t next_progress_ns_;
  int64_t last_progress_ns_ = 0;
  int64_t last_completed_ = 0;
  bool interrupted_ = false;
};

constexpr auto kRoundWait = std::chrono::milliseconds(50);
constexpr int kMaxSyncThreads = 1024;

template <class Rpc>
bool RunOpenLoop(Run& run, int channels) {
  Driver driver(&run);
  const LoadSpec& spec = run.spec;
  const double interval_ns = 1e9 / spec.rate;
  std::atomic<int> in_flight{0};
  std::mutex mu;
  std::condition_variable slot_free;
  int64_t issued = 0;
  for (;;) {
    const int64_t scheduled = run.start_ns + static_cast<int64_t>(issued * interval_ns);
    if (run.stop.load() || scheduled >= run.end_ns ||
        (spec.max_requests > 0 && issued >= spec.max_requests)) {
      break;
    }
    // Until the call is due (housekeeping meanwhile).
    for (int64_t now = NowNs(); now < scheduled; now = NowNs()) {
      const int64_t left = scheduled - now;
      if (left > 2'000'000) {
        std::this_thread::sleep_for(std::chrono::nanoseconds(std::min<int64_t>(left, 50'000'000) -
                                                             1'000'000));
        driver.Housekeeping();
      } else {
        std::this_thread::sleep_until(Clock::time_point(std::chrono::nanoseconds(scheduled)));
      }
    }
    {
      std::unique_lock<std::mutex> lock(mu);
      while (in_flight.load() >= spec.concurrency) {
        slot_free.wait_for(lock, kRoundWait);
        driver.Housekeeping();
        if (run.stop.load()) break;
      }
    }
    if (run.stop.load()) break;
    if (issued % 64 == 0) driver.Housekeeping();
    auto* call = new UnaryCall<Rpc>;
    SetDeadline(&call->context, spec.deadline_ms);
    call->started_ns = scheduled;  // latency from the scheduled start
    in_flight.fetch_add(1);
    run.tickets.fetch_add(1, std::memory_order_relaxed);
    Rpc::Start(run, static_cast<int>(issued % channels), &call->context, issued, &call->response,
               [&run, &in_flight, &mu, &slot_free, call](grpc::Status status) {
                 run.Record(status.error_code(), call->started_ns);
                 delete call;
                 std::lock_guard<std::mutex> lock(mu);
                 in_flight.fetch_sub(1);
                 slot_free.notify_all();
               });
    ++issued;
  }
  std::unique_lock<std::mutex> lock(mu);
  while (in_flight.load() > 0) {
    slot_free.wait_for(lock, kRoundWait);
    lock.unlock();
    driver.Housekeeping();
    lock.lock();
  }
  return driver.interrupted();
}

template <class Rpc>
bool RunClosedLoopCallback(Run& run, int channels) {
  std::vector<std::unique_ptr<UnarySlot<Rpc>>> slots;
  for (int i = 0; i < run.spec.concurrency; ++i) {
    slots.push_back(std::make_unique<UnarySlot<Rpc>>(&run, i % channels));
  }
  run.active = run.spec.concurrency;
  Driver driver(&run);
  for (auto& slot : slots) slot->Next();
  while (driver.Round(driver.RoundWait())) {
  }
  return driver.interrupted();
}

bool RunStreamsCallback(Run& run, int channels) {
  std::vector<std::unique_ptr<StreamSlot>> slots;
  for (int i = 0; i < run.spec.concurrency; ++i) {
    slots.push_back(std::make_unique<StreamSlot>(&run, i % channels));
    run.watches.push_back(slots.back().get());
  }
  run.active = run.spec.concurrency;
  Driver driver(&run);
  for (auto& slot : slots) slot->Begin();
  while (driver.Round(driver.RoundWait())) {
  }
  return driver.interrupted();
}

bool RunSync(Run& run, int channels) {
  std::vector<std::unique_ptr<SyncStreamWatch>> watches;
  std::vector<std::thread> threads;
  run.active = run.spec.concurrency;
  if (run.spec.rpc == LoadRpc::kStream) {
    for (int i = 0; i < run.spec.concurrency; ++i) {
      watches.push_back(std::make_unique<SyncStreamWatch>());
      run.watches.push_back(watches.back().get());
    }
  }
  Driver driver(&run);
  for (int i = 0; i < run.spec.concurrency; ++i) {
    const int channel = i % channels;
    switch (run.spec.rpc) {
      case LoadRpc::kPlan:
        threads.emplace_back(SyncUnaryLoop<PlanRpc>, &run, channel);
        break;
      case LoadRpc::kHealth:
        threads.emplace_back(SyncUnaryLoop<HealthRpc>, &run, channel);
        break;
      case LoadRpc::kStream:
        threads.emplace_back(SyncStreamLoop, &run, channel, watches[i].get());
        break;
    }
  }
  while (driver.Round(driver.RoundWait())) {
  }
  for (std::thread& thread : threads) thread.join();
  return driver.interrupted();
}

std::string Number(double value) {
  // Latencies and rates: one decimal is plenty and keeps JSON readable.
  return absl::StrFormat("%.1f", value);
}

}  // namespace

const char* ToString(LoadRpc rpc) {
  switch (rpc) {
    case LoadRpc::kPlan:
      return "plan";
    case LoadRpc::kStream:
      return "stream";
    case LoadRpc::kHealth:
      return "health";
  }
  return "?";
}

const char* ToString(LoadEngine engine) {
  return engine == LoadEngine::kSync ? "sync" : "callback";
}

absl::StatusOr<LoadReport> RunLoad(const LoadSpec& spec,
                                   const std::vector<std::shared_ptr<grpc::Channel>>& channels) {
  if (channels.empty()) return absl::InvalidArgumentError("load: no target");
  if (spec.concurrency < 1) return absl::InvalidArgumentError("--concurrency: must be >= 1");
  if (spec.max_requests <= 0 && spec.duration_s <= 0) {
    return absl::InvalidArgumentError("load: give --requests and/or --duration");
  }
  if (spec.rpc != LoadRpc::kHealth && spec.requests.empty()) {
    return absl::InvalidArgumentError("load: no request to send");
  }
  const bool open_loop = spec.rate > 0;
  if (open_loop && spec.rpc == LoadRpc::kStream) {
    return absl::InvalidArgumentError(
        "--rate: open loop is for unary RPCs (plan, health); streams run closed loop");
  }
  if (open_loop && spec.engine == LoadEngine::kSync) {
    return absl::InvalidArgumentError("--rate: open loop needs --engine callback");
  }
  if (spec.engine == LoadEngine::kSync && spec.concurrency > kMaxSyncThreads) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--concurrency: at most ", kMaxSyncThreads, " with --engine sync (one thread each)"));
  }

  Run run(spec, channels);
  const int n = static_cast<int>(channels.size());
  bool interrupted = false;
  if (open_loop) {
    interrupted = spec.rpc == LoadRpc::kHealth ? RunOpenLoop<HealthRpc>(run, n)
                                               : RunOpenLoop<PlanRpc>(run, n);
  } else if (spec.engine == LoadEngine::kSync) {
    interrupted = RunSync(run, n);
  } else if (spec.rpc == LoadRpc::kStream) {
    interrupted = RunStreamsCallback(run, n);
  } else if (spec.rpc == LoadRpc::kHealth) {
    interrupted = RunClosedLoopCallback<HealthRpc>(run, n);
  } else {
    interrupted = RunClosedLoopCallback<PlanRpc>(run, n);
  }

  LoadReport report;
  report.rpc = ToString(spec.rpc);
  report.mode = open_loop ? "open" : "closed";
  report.engine = ToString(spec.engine);
  report.concurrency = spec.concurrency;
  report.rate = spec.rate;
  report.channels = n;
  report.requests = run.completed.load();
  report.ok = run.ok.load();
  const int64_t last = run.last_done_ns.load();
  report.duration_s = ((last > 0 ? last : NowNs()) - run.start_ns) * 1e-9;
  report.qps = report.duration_s > 0 ? report.ok / report.duration_s : 0.0;
  const LatencyHistogram& h = run.histogram;
  report.p50_us = h.Quantile(0.50) * 1e-3;
  report.p90_us = h.Quantile(0.90) * 1e-3;
  report.p99_us = h.Quantile(0.99) * 1e-3;
  report.p999_us = h.Quantile(0.999) * 1e-3;
  report.max_us = h.max() * 1e-3;
  for (int code = 0; code < kCodeSlots; ++code) {
    const int64_t count = run.errors[code].load();
    if (count > 0) {
      report.errors[StatusCodeName(static_cast<grpc::StatusCode>(code))] += count;
    }
  }
  report.interrupted = interrupted;
  return report;
}

absl::StatusOr<std::vector<std::shared_ptr<grpc::Channel>>> ConnectLoadChannels(
    const ConnectionArgs& connection, const std::string& target_list, int per_target,
    const LoadSpec& spec) {
  absl::StatusOr<std::vector<std::string>> targets = SplitTargets(target_list);
  if (!targets.ok()) return targets.status();
  if (per_target < 1) return absl::InvalidArgumentError("--channels: must be >= 1");
  const int deadline_ms = connection.deadline_ms > 0 ? connection.deadline_ms : 10'000;
  std::vector<std::shared_ptr<grpc::Channel>> channels;
  for (const std::string& target : *targets) {
    // Addresses behind one target: the entries of an ipv4:/ipv6: list.
    const int addresses =
        HasUriScheme(target) ? static_cast<int>(std::count(target.begin(), target.end(), ',')) + 1
                             : 1;
    for (int k = 0; k < per_target; ++k) {
      grpc::ChannelArguments args;
      // Without this, channels with equal arguments share one connection.
      args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
      if (HasUriScheme(target)) args.SetLoadBalancingPolicyName("round_robin");
      absl::StatusOr<std::shared_ptr<grpc::Channel>> channel =
          MakeChannel(connection, target, args);
      if (!channel.ok()) return channel.status();
      // Warm-up, which also connects: the first call fails fast with the
      // reason (connection refused, TLS handshake) when the target cannot be
      // reached. round_robin connects to every address; a few calls make
      // sure each is used (and the request accepted) before measuring.
      for (int i = 0; i < 2 * addresses; ++i) {
        grpc::ClientContext context;
        SetDeadline(&context, deadline_ms);
        grpc::Status status;
        if (spec.rpc == LoadRpc::kHealth) {
          grpc::health::v1::HealthCheckRequest request;
          request.set_service(spec.health_service);
          grpc::health::v1::HealthCheckResponse response;
          status = grpc::health::v1::Health::NewStub(*channel)->Check(&context, request, &response);
          if (status.error_code() == grpc::StatusCode::NOT_FOUND) {
            return absl::InvalidArgumentError(absl::StrCat(
                target, " does not know service '", spec.health_service, "' (--service)"));
          }
        } else {
          if (spec.requests.empty()) return absl::InvalidArgumentError("load: no request to send");
          v1::PlanResponse response;
          status = v1::Planner::NewStub(*channel)->Plan(&context, spec.requests.front(), &response);
        }
        if (!status.ok()) return RpcError(status, target, deadline_ms, channel->get());
      }
      channels.push_back(*std::move(channel));
    }
  }
  return channels;
}

std::vector<v1::PlanRequest> RandomRequestMix(uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  std::vector<v1::PlanRequest> requests;
  requests.reserve(static_cast<size_t>(std::max(count, 0)));
  for (int i = 0; i < count; ++i) {
    const planner::RandomGrasp grasp = planner::MakeRandomGrasp(rng);
    requests.push_back(
        api::ToRequest(grasp.problem, planner::PlanOptions(), planner::SolverKind::kGeometric));
  }
  return requests;
}

std::string FormatLoadText(const LoadReport& r, const std::string& target) {
  std::string out = absl::StrFormat("tactforce load: %s -> %s, %s loop, %s %d", r.rpc, target,
                                    r.mode, r.mode == "open" ? "at most" : "concurrency",
                                    r.concurrency);
  if (r.mode == "open") absl::StrAppendFormat(&out, " in flight, rate %g/s", r.rate);
  absl::StrAppendFormat(&out, ", %s API, %d channel%s%s\n", r.engine, r.channels,
                        r.channels == 1 ? "" : "s", r.interrupted ? " (interrupted)" : "");
  absl::StrAppendFormat(&out, "  calls       %d (%d ok, %d failed) in %.3f s\n", r.requests,
                        r.ok, r.requests - r.ok, r.duration_s);
  absl::StrAppendFormat(&out, "  throughput  %.1f calls/s\n", r.qps);
  absl::StrAppendFormat(&out, "  latency [us] %9s %9s %9s %9s %9s\n", "p50", "p90", "p99",
                        "p99.9", "max");
  absl::StrAppendFormat(&out, "               %9.1f %9.1f %9.1f %9.1f %9.1f\n", r.p50_us,
                        r.p90_us, r.p99_us, r.p999_us, r.max_us);
  if (r.errors.empty()) {
    out += "  errors      none\n";
  } else {
    out += "  errors     ";
    for (const auto& [code, count] : r.errors) absl::StrAppendFormat(&out, " %s=%d", code, count);
    out += "\n";
  }
  return out;
}

std::string FormatLoadJson(const LoadReport& r, const std::string& target) {
  std::string errors = "{";
  bool first = true;
  for (const auto& [code, count] : r.errors) {
    absl::StrAppendFormat(&errors, "%s%s: %d", first ? "" : ", ", io::JsonEscape(code), count);
    first = false;
  }
  errors += "}";
  std::string out = absl::StrFormat(
      "{\"rpc\": %s, \"target\": %s, \"mode\": %s, \"engine\": %s, \"concurrency\": %d, ",
      io::JsonEscape(r.rpc), io::JsonEscape(target), io::JsonEscape(r.mode),
      io::JsonEscape(r.engine), r.concurrency);
  if (r.mode == "open") absl::StrAppendFormat(&out, "\"rate\": %g, ", r.rate);
  absl::StrAppendFormat(&out,
                        "\"channels\": %d, \"requests\": %d, \"ok\": %d, \"duration_s\": %.4f, "
                        "\"qps\": %s, \"latency_us\": {\"p50\": %s, \"p90\": %s, \"p99\": %s, "
                        "\"p999\": %s, \"max\": %s}, \"errors\": %s",
                        r.channels, r.requests, r.ok, r.duration_s, Number(r.qps),
                        Number(r.p50_us), Number(r.p90_us), Number(r.p99_us), Number(r.p999_us),
                        Number(r.max_us), errors);
  if (r.interrupted) out += ", \"interrupted\": true";
  out += "}\n";
  return out;
}

}  // namespace tactforce::cli
