// tactforce.v1.Planner (planner_service.h): every RPC hands its request to
// api:: dispatch with its RpcGuard and finishes the gRPC call in `done`.
// PlanStream's reactor keeps a stream's order (read, dispatch, write, read
// the next) and its lifetime (a solve on the pool may outlive OnDone).
#include "tactforce/server/planner_service.h"

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "spdlog/spdlog.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/server/admitted_stream.h"
#include "tactforce/server/pooled_unary.h"
#include "tactforce/server/rpc_support.h"

namespace tactforce::server {
namespace {

// One response per request, in order: read, dispatch (inline or on the
// pool), write, read the next, so at most one solve per stream is in flight
// and request_/response_ need no lock. A bad request ends the stream with
// "request <i>: ..." (i counts from 0).
class PlanStreamReactor final
    : public AdmittedStream<grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>> {
 public:
  PlanStreamReactor(const api::PlanDispatcher* plans, StreamRegistry* streams,
                    grpc::CallbackServerContext* context)
      : AdmittedStream(context, streams, "PlanStream"), plans_(plans) {
    if (spdlog::should_log(spdlog::level::info)) peer_ = context->peer();
    Start();
  }

  void OnReadDone(bool ok) override {
    if (!ReadArrived()) return;
    if (!ok) {
      // Half-close by the client (normal end), or a broken / cancelled call.
      End(guard().ShouldStop() ? guard().StopReason("while reading") : absl::OkStatus());
      return;
    }
    if (absl::Status parsed = ParseMessage(read_buffer(), &request_); !parsed.ok()) {
      End(Indexed(parsed));
      return;
    }
    Dispatch();
  }

  void OnWriteDone(bool ok) override {
    WriteTaken();
    if (!ok) {
      End(guard().ShouldStop() ? guard().StopReason("while writing")
                               : absl::UnavailableError("stream broken while writing"));
      return;
    }
    ++index_;
    request_.Clear();
    ReadNext();
  }

 private:
  void Dispatch() {
    Ref();  // held until `done` has run: OnDone may come first
    plans_->Dispatch(
        request_, &response_, api::CallLog("PlanStream", guard(), index_), guard(),
        [this](const absl::Status& status) {
          Complete(status);
          Unref();
        },
        &buffers_);
  }

  void Complete(const absl::Status& status) {
    if (!status.ok()) return End(Indexed(status));
    if (guard().ShouldStop()) return End(Indexed(guard().StopReason("after the solve")));
    if (absl::Status s = SerializeMessage(response_, write_buffer()); !s.ok())
      return End(Indexed(s));
    WriteNext();
  }

  absl::Status Indexed(const absl::Status& status) const {
    return io::PrependPath(status, absl::StrCat("request ", index_));
  }
  absl::Status Idled(const absl::Status& status) const override { return Indexed(status); }

  // One line per stream besides the per-request ones.
  void OnEnd(const absl::Status& status) override {
    const auto total_us =
        std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start_).count();
    spdlog::info("rpc=PlanStream event=end code={} responses={} total_us={} peer={}",
                 absl::StatusCodeToString(status.code()), index_, total_us, LogValue(peer_));
  }

  const api::PlanDispatcher* plans_;
  int64_t index_ = 0;  // requests answered so far = index of the current one
  std::string peer_;
  const Clock::time_point start_ = Clock::now();
  v1::PlanRequest request_;
  v1::PlanResponse response_;
  api::PlanBuffers buffers_;  // the stream's workspace: one solve at a time
};

}  // namespace

PlannerService::PlannerService(WorkerPool* pool, WorkerPool* ipopt_lane, StreamRegistry* streams,
                               api::PlanSettings settings)
    : pool_(pool),
      ipopt_lane_(ipopt_lane),
      streams_(streams),
      plans_(pool, std::move(settings), ipopt_lane) {
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
  // The guard lives on the call's arena (plan_messages_), as long as the
  // request, which api:: may read until `done` has run: no allocation of
  // its own and no shared count on the hot path.
  if (google::protobuf::Arena* arena = request->GetArena(); arena != nullptr) {
    const RpcGuard* guard = google::protobuf::Arena::Create<RpcGuard>(arena, context);
    plans_.Dispatch(*request, response, api::CallLog("Plan", *guard), *guard, FinishUnary(reactor));
    return reactor;
  }
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
      plans_.settings().limits, &api::HandleTrajectory);
}

grpc::ServerUnaryReactor* PlannerService::PlanFrictionProbe(grpc::CallbackServerContext* context,
                                                            const v1::FrictionProbeRequest* request,
                                                            v1::FrictionProbeResponse* response) {
  return ServeOnPool<v1::FrictionProbeRequest, v1::FrictionProbeResponse>(
      "PlanFrictionProbe", context, request, response, PoolFor(request->plan().solver()),
      plans_.settings().limits, &api::HandleFrictionProbe);
}

}  // namespace tactforce::server
