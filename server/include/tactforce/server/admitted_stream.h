// AdmittedStream: what every streaming reactor of the server shares
// (PlanStream, FitInertia), so that a reactor holds only what its RPC does
// with its messages:
//   * admission by the StreamRegistry (--max-streams) and its slot freed
//     exactly once, before the client hears the end;
//   * the idle clock the registry's reaper reads (--stream-idle-timeout-ms):
//     a read of the client's next message pending, or a write the client
//     does not take, for longer than the timeout ends the call;
//   * the RPC's guard (deadline, cancellation, OnCancel included);
//   * the end of the call exactly once, whichever of reader, writer, reaper
//     or pooled work comes first;
//   * a reference count: gRPC holds one until OnDone, the reaper one while
//     it looks at the stream, pooled work one while it runs (reactors are
//     made with `new` and delete themselves at the last Unref).
// Messages are read raw (grpc::ByteBuffer, ParseMessage below): gRPC's
// typed reader reports a message it cannot parse exactly like the end of
// the stream. A bidi stream writes raw too (SerializeMessage); a read
// reactor's one response is typed (gRPC serializes it at Finish).
//
// `Reactor` is grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>
// or grpc::ServerReadReactor<grpc::ByteBuffer>. A derived reactor calls
// Start() last in its constructor, ReadArrived() first in OnReadDone (and
// returns when it is false), and ends the call with End(status).
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>

#include <grpcpp/grpcpp.h>
#include <grpcpp/support/byte_buffer.h>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "tactforce/server/rpc_support.h"
#include "tactforce/server/stream_registry.h"

namespace tactforce::server {

// A stream message from its raw bytes (why raw: above). InvalidArgument "cannot be parsed as
// tactforce.v1.PlanRequest"; the buffer is emptied either way.
template <class Message>
absl::Status ParseMessage(grpc::ByteBuffer* buffer, Message* message) {
  const bool parsed = grpc::SerializationTraits<Message>::Deserialize(buffer, message).ok();
  buffer->Clear();
  if (parsed) return absl::OkStatus();
  message->Clear();
  return absl::InvalidArgumentError(
      absl::StrCat("cannot be parsed as ", Message::descriptor()->full_name()));
}
// A message into a raw buffer (a bidi stream's next write).
template <class Message>
absl::Status SerializeMessage(const Message& message, grpc::ByteBuffer* buffer) {
  buffer->Clear();  // gRPC serializes only into an empty buffer
  bool own_buffer = false;
  if (grpc::SerializationTraits<Message>::Serialize(message, buffer, &own_buffer).ok()) {
    return absl::OkStatus();
  }
  return absl::InternalError(
      absl::StrCat("cannot serialize the ", Message::descriptor()->full_name()));
}

template <class Reactor>
class AdmittedStream : public Reactor, public IdleEndable {
 public:
  using Clock = std::chrono::steady_clock;

  void OnCancel() override { cancelled_.store(true, std::memory_order_relaxed); }
  void OnDone() override {
    Release();
    Unref();
  }

  void Ref() override { refs_.fetch_add(1, std::memory_order_relaxed); }
  void Unref() override {
    if (refs_.fetch_sub(1, std::memory_order_acq_rel) == 1) delete this;
  }

  // A write blocked since before `cutoff` also cancels the call, which
  // fails the pending write (a client that never reads would hold it open).
  void EndIfIdleSince(Clock::time_point cutoff, const absl::Status& status) override {
    bool write_blocked = false;
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (ended_) return;
      write_blocked = writing_ && writing_since_ < cutoff;
      if (!write_blocked && (!reading_ || reading_since_ >= cutoff)) return;
    }
    End(Idled(status));
    if (write_blocked) context_->TryCancel();
  }

 protected:
  // `rpc` names the stream in the registry's refusal ("PlanStream: N
  // streams already open ..."). `context` and `streams` outlive the call.
  AdmittedStream(grpc::CallbackServerContext* context, StreamRegistry* streams, const char* rpc)
      : context_(context), streams_(streams), rpc_(rpc), guard_(context, &cancelled_) {}

  // Admits the stream and reads its first message, or ends the call with
  // the registry's RESOURCE_EXHAUSTED.
  void Start() {
    if (absl::Status admitted = streams_->Open(this, rpc_); !admitted.ok()) {
      End(admitted);
      return;
    }
    registered_.store(true);
    ReadNext();
  }

  // Reads the client's next message into read_buffer(); idle until it comes.
  void ReadNext() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      reading_ = true;
      reading_since_ = Clock::now();
    }
    this->StartRead(&read_buffer_);
  }
  // First thing in OnReadDone: false when the call has already ended (the
  // reaper ended it while the read was pending); then do nothing more.
  bool ReadArrived() {
    std::lock_guard<std::mutex> lock(mu_);
    reading_ = false;
    return !ended_;
  }

  // Writes write_buffer() (bidi streams); counts as idle until the client
  // takes it. OnWriteDone calls WriteTaken() first.
  void WriteNext() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      writing_ = true;
      writing_since_ = Clock::now();
    }
    this->StartWrite(&write_buffer_);
  }
  void WriteTaken() {
    std::lock_guard<std::mutex> lock(mu_);
    writing_ = false;
  }

  // Ends the call with `status` unless it has ended already: OnEnd (the
  // log line) first, then the budgets and the registry's slot are freed,
  // then gRPC finishes the call.
  void End(const absl::Status& status) {
    if (!TakeOver()) return;
    OnEnd(status);
    FinishTakenOver(status);
  }
  // For work that ends the call later (a fit on the pool): from now on
  // neither the reaper nor End() ends it; false if it has ended already.
  // The work then calls FinishTakenOver exactly once.
  bool TakeOver() {
    std::lock_guard<std::mutex> lock(mu_);
    if (ended_) return false;
    ended_ = true;
    return true;
  }
  void FinishTakenOver(const absl::Status& status) {
    Release();
    this->Finish(ToGrpcStatus(status));
  }

  // The end's log line (called once, by End).
  virtual void OnEnd(const absl::Status& status) = 0;
  // The status an idle stream ends with (the registry's, by default).
  virtual absl::Status Idled(const absl::Status& status) const { return status; }
  // Gives back what the stream took from the registry's budgets; may run
  // twice (End, then OnDone).
  virtual void ReleaseBudgets() {}

  const RpcGuard& guard() const { return guard_; }
  StreamRegistry* streams() const { return streams_; }
  grpc::CallbackServerContext* context() const { return context_; }
  grpc::ByteBuffer* read_buffer() { return &read_buffer_; }
  grpc::ByteBuffer* write_buffer() { return &write_buffer_; }

 private:
  void Release() {
    ReleaseBudgets();
    if (registered_.exchange(false)) streams_->Close(this);
  }

  grpc::CallbackServerContext* context_;
  StreamRegistry* streams_;
  const char* rpc_;
  std::atomic<bool> cancelled_{false};
  const RpcGuard guard_;                 // polls cancelled_ too
  std::atomic<bool> registered_{false};  // admitted and not yet closed
  std::atomic<int> refs_{1};
  std::mutex mu_;  // guards the flags and clocks below
  bool ended_ = false;
  bool reading_ = false;
  Clock::time_point reading_since_{};
  bool writing_ = false;
  Clock::time_point writing_since_{};
  grpc::ByteBuffer read_buffer_;
  grpc::ByteBuffer write_buffer_;
};

}  // namespace tactforce::server
