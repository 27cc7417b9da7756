#include "tactforce/server/estimator_service.h"

#include <atomic>
#include <chrono>

#include "tactforce/api/inertia.h"
#include "tactforce/api/services.h"
#include "tactforce/server/pooled_unary.h"

namespace tactforce::server {
namespace {

// Reads the FitInertia stream message by message into an api::InertiaStream;
// a bad message ends the call at once with INVALID_ARGUMENT; at the
// half-close the fit runs on the pool. Deletes itself in OnDone.
class FitInertiaReactor final : public grpc::ServerReadReactor<v1::FitInertiaRequest> {
 public:
  FitInertiaReactor(grpc::CallbackServerContext* context, v1::FitInertiaResponse* response,
                    WorkerPool* pool, int64_t max_samples)
      : context_(context), response_(response), pool_(pool), stream_(max_samples),
        peer_(spdlog::should_log(spdlog::level::info) ? context->peer() : "") {
    StartRead(&message_);
  }

  void OnReadDone(bool ok) override {
    if (!ok) return StartFit();  // half-close (or a broken call: the guard sees it)
    if (absl::Status s = stream_.Add(message_); !s.ok()) return Done(ToGrpcStatus(s));
    message_.Clear();
    StartRead(&message_);
  }
  void OnCancel() override { cancelled_.store(true); }
  void OnDone() override { delete this; }

 private:
  void StartFit() {
    const bool queued = pool_->TrySubmit([this] {
      RpcGuard guard(context_, &cancelled_);
      if (guard.ShouldStop()) return Done(guard.StopStatus("before the fit started"));
      api::CallLimits limits;
      limits.interrupt = guard.Interrupt();
      absl::StatusOr<v1::FitInertiaResponse> result = stream_.Fit(limits);
      if (!result.ok()) return Done(ToGrpcStatus(result.status()));
      *response_ = *std::move(result);
      Done(grpc::Status::OK);
    });
    if (!queued) Done(PoolBusyStatus(*pool_));
  }

  void Done(const grpc::Status& status) {
    LogPoolRpc("FitInertia", status, start_, peer_,
               absl::StrCat("messages=", stream_.messages_received(), " samples=", stream_.samples_received()));
    Finish(status);
  }

  grpc::CallbackServerContext* context_;
  v1::FitInertiaResponse* response_;
  WorkerPool* pool_;
  api::InertiaStream stream_;
  v1::FitInertiaRequest message_;
  std::atomic<bool> cancelled_{false};
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  const std::string peer_;
};

}  // namespace

grpc::ServerReadReactor<v1::FitInertiaRequest>* EstimatorService::FitInertia(
    grpc::CallbackServerContext* context, v1::FitInertiaResponse* response) {
  return new FitInertiaReactor(context, response, pool_, options_.max_inertia_samples);
}

grpc::ServerUnaryReactor* EstimatorService::EstimateForces(grpc::CallbackServerContext* context,
                                                           const v1::EstimateRequest* request,
                                                           v1::EstimateResponse* response) {
  api::CallLimits limits;
  limits.max_contacts = options_.max_contacts;
  return ServeOnPool<v1::EstimateRequest, v1::EstimateResponse>(
      "EstimateForces", context, request, response, pool_, limits, &api::HandleEstimate);
}

grpc::ServerUnaryReactor* EstimatorService::EstimateFriction(grpc::CallbackServerContext* context,
                                                             const v1::FrictionRequest* request,
                                                             v1::FrictionResponse* response) {
  return ServeOnPool<v1::FrictionRequest, v1::FrictionResponse>(
      "EstimateFriction", context, request, response, pool_, api::CallLimits{},
      [](const v1::FrictionRequest& r, const api::CallLimits&) { return api::HandleFriction(r); });
}

grpc::ServerUnaryReactor* AuditService::AuditModel(grpc::CallbackServerContext* context,
                                                   const v1::AuditRequest* request,
                                                   v1::AuditResponse* response) {
  return ServeOnPool<v1::AuditRequest, v1::AuditResponse>(
      "AuditModel", context, request, response, pool_, api::CallLimits{},
      [](const v1::AuditRequest& r, const api::CallLimits&) { return api::HandleAudit(r); });
}

}  // namespace tactforce::server
