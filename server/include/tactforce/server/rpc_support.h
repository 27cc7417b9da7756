// Small pieces shared by every service of tactforce-server: status mapping,
// the RPC's side of a call for api:: dispatch (deadline, cancellation,
// peer) and the end of a unary call. The per-call log line and its logfmt
// quoting are api::CallLog's.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include <google/protobuf/arena.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/message_allocator.h>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "tactforce/api/dispatch.h"

namespace tactforce::server {

// "OK", "INVALID_ARGUMENT", ... (absl's names: absl and gRPC share the
// numbering); "UNKNOWN_CODE" for a number neither defines.
const char* StatusCodeName(grpc::StatusCode code);

// Longest status message sent (bytes). gRPC carries the message in a
// header (percent-encoded: up to 3x) and a C-core client refuses headers
// over 8 KiB with RESOURCE_EXHAUSTED, which would turn an INVALID_ARGUMENT
// that echoes a long input into a retryable code.
inline constexpr size_t kMaxStatusMessageBytes = 2048;

// `message` cut at a UTF-8 character boundary to at most
// kMaxStatusMessageBytes, ending "... [N bytes cut]" when cut.
std::string BoundedStatusMessage(std::string_view message);

// Same code (absl and gRPC share the numbering), the message bounded
// (BoundedStatusMessage).
grpc::Status ToGrpcStatus(const absl::Status& status);

// logfmt value (api::LogValue): bare when safe, else double-quoted.
using api::LogValue;

// Deadline and cancellation of one RPC, safe to poll from any thread while
// the RPC is not finished. The deadline is converted to the steady clock
// when the guard is made, so wall-clock jumps do not matter.
class RpcGuard final : public api::CallControl {
 public:
  // `cancelled`: an extra flag set by a reactor's OnCancel (may be null).
  explicit RpcGuard(const grpc::CallbackServerContext* context,
                    const std::atomic<bool>* cancelled = nullptr);

  bool Expired() const;
  bool Cancelled() const;
  bool ShouldStop() const override { return Expired() || Cancelled(); }
  // DEADLINE_EXCEEDED "deadline exceeded <what>" if expired, else CANCELLED
  // "cancelled <what>".
  absl::Status StopReason(std::string_view what) const override;
  grpc::Status StopStatus(std::string_view what) const { return ToGrpcStatus(StopReason(what)); }
  // The context's peer ("ipv4:127.0.0.1:40512"); "" without a context.
  std::string Peer() const override;

  // For PlanOptions::interrupt: true once the RPC should stop (a copy of
  // the guard, usable after this object is gone).
  std::function<bool()> Interrupt() const override;

  bool has_deadline() const { return has_deadline_; }

 private:
  const grpc::CallbackServerContext* context_;
  const std::atomic<bool>* cancelled_;
  bool has_deadline_ = false;
  std::chrono::steady_clock::time_point deadline_{};
};

// The `done` of a unary call dispatched through api::: finishes `reactor`
// with the call's status and keeps `guard` (the call's CallControl) alive
// until then.
api::CallDone FinishUnary(grpc::ServerUnaryReactor* reactor, std::shared_ptr<const RpcGuard> guard);
// The same when the guard outlives the call on its own (e.g. on the call's
// arena).
api::CallDone FinishUnary(grpc::ServerUnaryReactor* reactor);

// Request and response of a unary callback RPC on one protobuf Arena whose
// first block lives inside the holder: one heap allocation per call instead
// of one per (sub-)message; larger messages spill into blocks the arena
// allocates. Register with the generated SetMessageAllocatorFor_<Method>();
// the allocator must outlive the service.
template <class Request, class Response>
class ArenaMessageAllocator final : public grpc::MessageAllocator<Request, Response> {
 public:
  grpc::MessageHolder<Request, Response>* AllocateMessages() override { return new Holder(); }

 private:
  static constexpr size_t kInlineBytes = 4096;

  class Holder final : public grpc::MessageHolder<Request, Response> {
   public:
    Holder() : arena_(Options(block_)) {
      this->set_request(google::protobuf::Arena::CreateMessage<Request>(&arena_));
      this->set_response(google::protobuf::Arena::CreateMessage<Response>(&arena_));
    }
    void Release() override { delete this; }

   private:
    static google::protobuf::ArenaOptions Options(char* block) {
      google::protobuf::ArenaOptions options;
      options.initial_block = block;
      options.initial_block_size = kInlineBytes;
      return options;
    }
    alignas(16) char block_[kInlineBytes];
    google::protobuf::Arena arena_;  // after block_: destroyed before it
  };
};

}  // namespace tactforce::server
