// Server-wide bounds on streaming calls (PlanStream, FitInertia), so that
// no client, authenticated or not, can hold memory without limit:
//   * at most `max_streams` open at once (RESOURCE_EXHAUSTED beyond);
//   * a stream that waits longer than `idle_timeout` for its next message
//     is ended with UNAVAILABLE (a reaper thread checks once a second);
//   * FitInertia samples held by all open streams together stay within
//     `max_inflight_samples`, and the bytes they hold (converted samples,
//     contacts included, and the options with their mesh) within
//     `max_inflight_bytes` (RESOURCE_EXHAUSTED for the message that would
//     exceed either; both are released when the stream ends).
// (Per connection, HTTP/2's SETTINGS_MAX_CONCURRENT_STREAMS bounds the
// calls in flight: ServerOptions::max_streams_per_connection.)
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <unordered_set>

#include "absl/status/status.h"

namespace tactforce::server {

struct StreamLimits {
  int max_streams = 1000;                          // open streaming calls; 0 = no limit
  std::chrono::milliseconds idle_timeout{60'000};  // 0 = never
  int64_t max_inflight_samples = 2'000'000;        // FitInertia samples held; 0 = no limit
  // FitInertia bytes held by all streams (api::InertiaStream::held_bytes);
  // 0 = no limit. 256 MiB: a quarter of the shipped Kubernetes limit (1 GiB).
  int64_t max_inflight_bytes = int64_t{256} << 20;
};

// A stream the registry may end for idling. Implementations are reactors
// with a reference count: the registry holds a reference while it ends one.
class IdleEndable {
 public:
  virtual ~IdleEndable() = default;
  virtual void Ref() = 0;
  virtual void Unref() = 0;
  // Ends the stream with `status` if it has been waiting for the client's
  // next message since before `cutoff`; otherwise does nothing. Non-blocking.
  virtual void EndIfIdleSince(std::chrono::steady_clock::time_point cutoff,
                              const absl::Status& status) = 0;
};

class StreamRegistry {
 public:
  explicit StreamRegistry(StreamLimits limits);
  ~StreamRegistry();  // stops the reaper; every stream must be closed by then
  StreamRegistry(const StreamRegistry&) = delete;
  StreamRegistry& operator=(const StreamRegistry&) = delete;

  // Admits a new stream or returns RESOURCE_EXHAUSTED "<rpc>: N streams
  // already open (the server's --max-streams); retry later". An admitted
  // stream must be closed exactly once.
  absl::Status Open(IdleEndable* stream, const char* rpc);
  void Close(IdleEndable* stream);

  // Takes `n` samples from the in-flight budget, or RESOURCE_EXHAUSTED
  // naming the budget and --max-inflight-samples.
  absl::Status ReserveSamples(int64_t n);
  void ReleaseSamples(int64_t n);
  // The same for bytes (--max-inflight-bytes).
  absl::Status ReserveBytes(int64_t n);
  void ReleaseBytes(int64_t n);

  int open_streams() const;
  int64_t inflight_samples() const { return samples_.load(); }
  int64_t inflight_bytes() const { return bytes_.load(); }
  const StreamLimits& limits() const { return limits_; }

 private:
  void ReapLoop();

  const StreamLimits limits_;
  mutable std::mutex mu_;
  std::condition_variable stop_cv_;
  bool stopping_ = false;
  std::unordered_set<IdleEndable*> streams_;
  std::atomic<int64_t> samples_{0};
  std::atomic<int64_t> bytes_{0};
  std::thread reaper_;
};

}  // namespace tactforce::server
