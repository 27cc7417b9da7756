// StreamRegistry (stream_registry.h): admission, the sample budget and the
// idle reaper.
#include "tactforce/server/stream_registry.h"

#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"

namespace tactforce::server {

StreamRegistry::StreamRegistry(StreamLimits limits) : limits_(limits) {
  if (limits_.idle_timeout.count() > 0) reaper_ = std::thread([this] { ReapLoop(); });
}

StreamRegistry::~StreamRegistry() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
  }
  stop_cv_.notify_all();
  if (reaper_.joinable()) reaper_.join();
}

absl::Status StreamRegistry::Open(IdleEndable* stream, const char* rpc) {
  std::lock_guard<std::mutex> lock(mu_);
  if (limits_.max_streams > 0 && static_cast<int>(streams_.size()) >= limits_.max_streams) {
    return absl::ResourceExhaustedError(
        absl::StrCat(rpc, ": ", streams_.size(),
                     " streams already open (the server's --max-streams); retry later"));
  }
  streams_.insert(stream);
  return absl::OkStatus();
}

void StreamRegistry::Close(IdleEndable* stream) {
  std::lock_guard<std::mutex> lock(mu_);
  streams_.erase(stream);
}

namespace {

// Takes `n` from `held` unless that passes `limit` (> 0); RESOURCE_EXHAUSTED
// naming what is counted and the flag otherwise.
absl::Status Reserve(std::atomic<int64_t>& held, int64_t n, int64_t limit, const char* what,
                     const char* flag) {
  const int64_t before = held.fetch_add(n);
  if (limit > 0 && before + n > limit) {
    held.fetch_sub(n);
    return absl::ResourceExhaustedError(absl::StrCat(
        "samples: open FitInertia streams hold ", before, " ", what, " and this message brings ", n,
        ", over the server's budget of ", limit, " (", flag, "); retry later"));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status StreamRegistry::ReserveSamples(int64_t n) {
  return Reserve(samples_, n, limits_.max_inflight_samples, "samples", "--max-inflight-samples");
}

void StreamRegistry::ReleaseSamples(int64_t n) { samples_.fetch_sub(n); }

absl::Status StreamRegistry::ReserveBytes(int64_t n) {
  return Reserve(bytes_, n, limits_.max_inflight_bytes, "bytes", "--max-inflight-bytes");
}

void StreamRegistry::ReleaseBytes(int64_t n) { bytes_.fetch_sub(n); }

int StreamRegistry::open_streams() const {
  std::lock_guard<std::mutex> lock(mu_);
  return static_cast<int>(streams_.size());
}

void StreamRegistry::ReapLoop() {
  const absl::Status idle = absl::UnavailableError(
      absl::StrCat("stream idle for more than ", limits_.idle_timeout.count(),
                   " ms (the server's --stream-idle-timeout-ms); open a new stream"));
  std::unique_lock<std::mutex> lock(mu_);
  while (!stop_cv_.wait_for(lock, std::chrono::seconds(1), [this] { return stopping_; })) {
    // Referenced under the lock (a stream closes under it), ended outside
    // it: ending a stream may run its OnDone, which closes it here.
    std::vector<IdleEndable*> all(streams_.begin(), streams_.end());
    for (IdleEndable* s : all) s->Ref();
    const auto cutoff = std::chrono::steady_clock::now() - limits_.idle_timeout;
    lock.unlock();
    for (IdleEndable* s : all) {
      s->EndIfIdleSince(cutoff, idle);
      s->Unref();
    }
    lock.lock();
  }
}

}  // namespace tactforce::server
