// tactforce.v1.Planner (planner_service.h): every RPC hands its request to
// api:: dispatch with its RpcGuard and finishes the gRPC call in `done`.
// PlanStream's reactor keeps a stream's order (read, dispatch, write, read
// the next) and its lifetime (a solve on the pool may outlive OnDone).
#include "tactforce/server/planner_service.h"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "spdlog/spdlog.h"
#include "tactforce/server/pooled_unary.h"
#include "tactforce/server/rpc_support.h"

namespace tactforce::server {
namespace {

using Clock = std::chrono::steady_clock;

api::PlanSettings ToPlanSettings(const PlannerServiceOptions& options) {
  api::PlanSettings settings;
  settings.limits.max_contacts = options.max_contacts;
  settings.limits.solve_timeout_ms = options.solve_timeout_ms;
  settings.inline_max_contacts = options.inline_max_contacts;
  settings.limits.max_trajectory_work = options.max_trajectory_work;
  settings.limits.max_response_bytes = options.max_response_bytes;
  return settings;
}

// Reads and writes raw messages and parses each itself: gRPC's typed
// reader reports a message it cannot parse exactly like the end of the
// stream, which would end a stream with a corrupt request OK.
class PlanStreamReactor final
    : public grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>, public IdleEndable {
 public:
  PlanStreamReactor(const api::PlanDispatcher* plans, StreamRegistry* streams,
                    grpc::CallbackServerContext* context)
      : plans_(plans), streams_(streams), context_(context), guard_(context, &cancelled_) {
    if (spdlog::should_log(spdlog::level::info)) peer_ = context->peer();
    if (absl::Status admitted = streams_->Open(this, "PlanStream"); !admitted.ok()) {
      FinishOnce(ToGrpcStatus(admitted));
      return;
    }
    registered_.store(true);
    ReadNext();
  }

  void OnReadDone(bool ok) override {
    {
      std::lock_guard<std::mutex> lock(finish_mu_);
      if (finished_) return;  // ended for idling while this read was pending
      waiting_ = false;
    }
    if (!ok) {
      // Half-close by the client (normal end), or a broken / cancelled call.
      FinishOnce(guard_.ShouldStop() ? guard_.StopStatus("while reading") : grpc::Status::OK);
      return;
    }
    if (absl::Status parsed = ParseMessage(&read_buffer_, &request_); !parsed.ok()) {
      FinishOnce(Indexed(ToGrpcStatus(parsed)));
      return;
    }
    Dispatch();
  }

  void OnWriteDone(bool ok) override {
    {
      std::lock_guard<std::mutex> lock(finish_mu_);
      writing_ = false;
    }
    if (!ok) {
      FinishOnce(guard_.ShouldStop() ? guard_.StopStatus("while writing")
                                     : grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                                    "stream broken while writing"));
      return;
    }
    ++index_;
    request_.Clear();
    ReadNext();
  }

  void OnCancel() override { cancelled_.store(true, std::memory_order_relaxed); }

  void OnDone() override {
    Unregister();
    Unref();
  }

  void Ref() override { refs_.fetch_add(1, std::memory_order_relaxed); }
  // gRPC holds one reference until OnDone; a dispatched request holds
  // another until its `done` has run, because OnDone may come first; the
  // registry one while it looks at the stream.
  void Unref() override {
    if (refs_.fetch_sub(1, std::memory_order_acq_rel) == 1) delete this;
  }

  // Idle: waiting for the client's next request, or for the client to
  // take a response (a client that never reads blocks the write forever;
  // the call is then cancelled, which fails the pending write).
  void EndIfIdleSince(Clock::time_point cutoff, const absl::Status& status) override {
    bool write_blocked = false;
    {
      std::lock_guard<std::mutex> lock(finish_mu_);
      if (finished_) return;
      write_blocked = writing_ && writing_since_ < cutoff;
      if (!write_blocked && (!waiting_ || waiting_since_ >= cutoff)) return;
    }
    FinishOnce(Indexed(ToGrpcStatus(status)));
    if (write_blocked) context_->TryCancel();
  }

 private:
  // Exactly one of: a read pending, a solve running, a write pending, or
  // finished. So no lock is needed around request_/response_.
  void ReadNext() {
    {
      std::lock_guard<std::mutex> lock(finish_mu_);
      waiting_ = true;
      waiting_since_ = Clock::now();
    }
    StartRead(&read_buffer_);
  }

  void Dispatch() {
    Ref();  // held until `done` has run
    plans_->Dispatch(
        request_, &response_, api::CallLog("PlanStream", guard_, index_), guard_,
        [this](const absl::Status& status) {
          Complete(ToGrpcStatus(status));
          Unref();
        },
        &buffers_);
  }

  grpc::Status Indexed(const grpc::Status& status) const {
    return grpc::Status(status.error_code(),
                        absl::StrCat("request ", index_, ": ", status.error_message()));
  }

  void Complete(const grpc::Status& status) {
    if (!status.ok()) {
      FinishOnce(Indexed(status));
    } else if (guard_.ShouldStop()) {
      FinishOnce(Indexed(guard_.StopStatus("after the solve")));
    } else if (absl::Status serialized = SerializeMessage(response_, &write_buffer_); !serialized.ok()) {
      FinishOnce(Indexed(ToGrpcStatus(serialized)));
    } else {
      {
        std::lock_guard<std::mutex> lock(finish_mu_);
        writing_ = true;
        writing_since_ = Clock::now();
      }
      StartWrite(&write_buffer_);
    }
  }

  void FinishOnce(const grpc::Status& status) {
    {
      std::lock_guard<std::mutex> lock(finish_mu_);
      if (finished_) return;
      finished_ = true;
    }
    // One line per stream besides the per-request ones.
    const auto total_us =
        std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start_).count();
    spdlog::info("rpc=PlanStream event=end code={} responses={} total_us={} peer={}",
                 StatusCodeName(status.error_code()), index_, total_us, LogValue(peer_));
    Unregister();  // the slot is free before the client hears the end
    Finish(status);
  }

  void Unregister() {
    if (registered_.exchange(false)) streams_->Close(this);
  }

  const api::PlanDispatcher* plans_;
  StreamRegistry* streams_;
  std::atomic<bool> registered_{false};  // admitted by streams_ and not yet closed
  grpc::CallbackServerContext* context_;
  std::atomic<bool> cancelled_{false};
  RpcGuard guard_;
  std::atomic<int> refs_{1};
  std::mutex finish_mu_;  // guards finished_, waiting_*, writing_*
  bool finished_ = false;
  bool waiting_ = false;  // a read of the client's next request is pending
  Clock::time_point waiting_since_{};
  bool writing_ = false;  // a response is being written
  Clock::time_point writing_since_{};
  int64_t index_ = 0;  // requests answered so far = index of the current one
  std::string peer_;
  const Clock::time_point start_ = Clock::now();
  grpc::ByteBuffer read_buffer_;
  grpc::ByteBuffer write_buffer_;
  v1::PlanRequest request_;
  v1::PlanResponse response_;
  api::PlanBuffers buffers_;  // the stream's workspace: one solve at a time
};

}  // namespace

PlannerService::PlannerService(WorkerPool* pool, WorkerPool* ipopt_lane, StreamRegistry* streams,
                               PlannerServiceOptions options)
    : pool_(pool), ipopt_lane_(ipopt_lane), streams_(streams),
      plans_(pool, ToPlanSettings(options), ipopt_lane) {
  SetMessageAllocatorFor_Plan(&plan_messages_);
}

WorkerPool* PlannerService::PoolFor(v1::Solver solver) const {
  return api::UsesIpopt(solver) ? ipopt_lane_ : pool_;
}

std::string PlannerService::service_name() const {
  return std::string(v1::Planner::service_full_name());
}

grpc::ServerUnaryReactor* PlannerService::Plan(grpc::CallbackServerContext* context,
                                               const v1::PlanRequest* request,
                                               v1::PlanResponse* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  auto guard = std::make_shared<const RpcGuard>(context);
  plans_.Dispatch(*request, response, api::CallLog("Plan", *guard), *guard,
                  FinishUnary(reactor, guard));
  return reactor;
}

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* PlannerService::PlanStream(
    grpc::CallbackServerContext* context) {
  return new PlanStreamReactor(&plans_, streams_, context);
}

grpc::ServerUnaryReactor* PlannerService::PlanTrajectory(grpc::CallbackServerContext* context,
                                                         const v1::TrajectoryRequest* request,
                                                         v1::TrajectoryResponse* response) {
  return ServeOnPool<v1::TrajectoryRequest, v1::TrajectoryResponse>(
      "PlanTrajectory", context, request, response, PoolFor(request->plan().solver()),
      plans_.settings().limits,
      &api::HandleTrajectory);
}

grpc::ServerUnaryReactor* PlannerService::PlanFrictionProbe(grpc::CallbackServerContext* context,
                                                            const v1::FrictionProbeRequest* request,
                                                            v1::FrictionProbeResponse* response) {
  return ServeOnPool<v1::FrictionProbeRequest, v1::FrictionProbeResponse>(
      "PlanFrictionProbe", context, request, response, PoolFor(request->plan().solver()),
      plans_.settings().limits,
      &api::HandleFrictionProbe);
}

}  // namespace tactforce::server
