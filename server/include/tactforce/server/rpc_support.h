// Small pieces shared by every service of tactforce-server: status mapping,
// deadline / cancellation checks, and the per-request log line.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include <grpcpp/grpcpp.h>

#include "absl/status/status.h"

namespace tactforce::server {

// "OK", "INVALID_ARGUMENT", ...
const char* StatusCodeName(grpc::StatusCode code);

// Same code (absl and gRPC share the numbering), same message.
grpc::Status ToGrpcStatus(const absl::Status& status);

// Deadline and cancellation of one RPC, safe to poll from any thread while
// the RPC is not finished. The deadline is converted to the steady clock
// when the guard is made, so wall-clock jumps do not matter.
class RpcGuard {
 public:
  // `cancelled`: an extra flag set by a reactor's OnCancel (may be null).
  explicit RpcGuard(const grpc::CallbackServerContext* context,
                    const std::atomic<bool>* cancelled = nullptr);

  bool Expired() const;
  bool Cancelled() const;
  bool ShouldStop() const { return Expired() || Cancelled(); }
  // DEADLINE_EXCEEDED if expired, else CANCELLED; `what` says where.
  grpc::Status StopStatus(std::string_view what) const;

  // For PlanOptions::interrupt: true once the RPC should stop.
  std::function<bool()> Interrupt() const;

  bool has_deadline() const { return has_deadline_; }

 private:
  const grpc::CallbackServerContext* context_;
  const std::atomic<bool>* cancelled_;
  bool has_deadline_ = false;
  std::chrono::steady_clock::time_point deadline_{};
};

// logfmt value: bare when safe, else double-quoted with escapes.
std::string LogValue(std::string_view text);

}  // namespace tactforce::server
