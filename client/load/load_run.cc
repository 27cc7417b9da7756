// The shared state of one load run (tickets, outcome counters, latency,
// completions over time) and the driving thread's loop (Driver): deferred
// work, stream deadlines, progress once a second, Ctrl-C.
#include "load_run.h"

#include <limits>
#include <utility>

namespace tactforce::cli::load_engine {

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

Run::Run(const LoadSpec& spec, const std::vector<std::shared_ptr<grpc::Channel>>& channels)
    : spec(spec) {
  for (const auto& channel : channels) {
    planners.push_back(v1::Planner::NewStub(channel));
    health.push_back(grpc::health::v1::Health::NewStub(channel));
    estimators.push_back(v1::Estimator::NewStub(channel));
    audits.push_back(v1::Audit::NewStub(channel));
  }
  health_request.set_service(spec.health_service);
  start_ns = NowNs();
  end_ns = spec.duration_s > 0 ? start_ns + static_cast<int64_t>(spec.duration_s * 1e9)
                               : std::numeric_limits<int64_t>::max();
}

bool Run::Claim(int64_t* ticket) {
  if (stop.load(std::memory_order_relaxed) || NowNs() >= end_ns) return false;
  const int64_t t = tickets.fetch_add(1, std::memory_order_relaxed);
  if (spec.max_requests > 0 && t >= spec.max_requests) return false;
  *ticket = t;
  return true;
}

bool Run::ClaimOrFinishSlot(int64_t* ticket) {
  if (Claim(ticket)) return true;
  SlotFinished();
  return false;
}

void Run::Record(grpc::StatusCode code, int64_t started_ns) {
  const int64_t now = NowNs();
  all_histogram.Record(now - started_ns);
  if (code == grpc::StatusCode::OK) {
    histogram.Record(now - started_ns);
    ok.fetch_add(1, std::memory_order_relaxed);
  } else {
    const int slot = std::clamp(static_cast<int>(code), 0, kCodeSlots - 1);
    errors[slot].fetch_add(1, std::memory_order_relaxed);
  }
  timeline.Record(now - start_ns, code == grpc::StatusCode::OK);
  completed.fetch_add(1, std::memory_order_relaxed);
  int64_t seen = last_done_ns.load(std::memory_order_relaxed);
  while (now > seen && !last_done_ns.compare_exchange_weak(seen, now, std::memory_order_relaxed)) {
  }
}

void Run::RecordStreamResponse(int64_t sent_ns) {
  const bool late =
      spec.deadline_ms > 0 && NowNs() - sent_ns > int64_t{spec.deadline_ms} * 1'000'000;
  Record(late ? grpc::StatusCode::DEADLINE_EXCEEDED : grpc::StatusCode::OK, sent_ns);
}

void Run::SlotFinished() {
  std::lock_guard<std::mutex> lock(mu);
  --active;
  wake.notify_all();
}

void Run::Defer(std::function<void()> fn) {
  std::lock_guard<std::mutex> lock(mu);
  deferred.push_back(std::move(fn));
  wake.notify_all();
}

void Run::Wake() {
  std::lock_guard<std::mutex> lock(mu);
  poke = true;
  wake.notify_all();
}

std::chrono::nanoseconds Driver::RoundWait() const {
  const int64_t base_ns = 50'000'000;
  if (run_->watches.empty() || run_->spec.deadline_ms <= 0) {
    return std::chrono::nanoseconds(base_ns);
  }
  const int64_t quarter_ns = int64_t{run_->spec.deadline_ms} * 250'000;
  return std::chrono::nanoseconds(std::clamp<int64_t>(quarter_ns, 2'000'000, base_ns));
}

bool Driver::Round(std::chrono::nanoseconds wait) {
  std::vector<std::function<void()>> work;
  {
    std::unique_lock<std::mutex> lock(run_->mu);
    run_->wake.wait_for(
        lock, wait, [this] { return run_->active == 0 || !run_->deferred.empty() || run_->poke; });
    run_->poke = false;
    work.swap(run_->deferred);
    if (run_->active == 0 && work.empty()) return false;
  }
  for (auto& fn : work) fn();
  Housekeeping();
  return true;
}

void Driver::Housekeeping() {
  const int64_t now = NowNs();
  const int64_t deadline_ns = int64_t{run_->spec.deadline_ms} * 1'000'000;
  for (StreamWatch* watch : run_->watches) watch->Check(now, deadline_ns);
  if (run_->spec.interrupted && run_->spec.interrupted()) {
    run_->stop.store(true, std::memory_order_relaxed);
    interrupted_ = true;
  }
  if (run_->spec.progress && now >= next_progress_ns_) ReportProgress(now);
}

bool Driver::RunUntilSlotsFinish() {
  while (Round(RoundWait())) {
  }
  return interrupted_;
}

void Driver::ReportProgress(int64_t now) {
  const int64_t completed = run_->completed.load(std::memory_order_relaxed);
  LoadProgress progress;
  progress.elapsed_s = (now - run_->start_ns) * 1e-9;
  progress.completed = completed;
  progress.failed = completed - run_->ok.load(std::memory_order_relaxed);
  const double window_s = (now - last_progress_ns_) * 1e-9;
  progress.recent_qps = (completed - last_completed_) / std::max(window_s, 1e-9);
  if (last_progress_ns_ == 0) progress.recent_qps = completed / progress.elapsed_s;
  last_progress_ns_ = now;
  last_completed_ = completed;
  next_progress_ns_ = now + 1'000'000'000;
  run_->spec.progress(progress);
}

}  // namespace tactforce::cli::load_engine
