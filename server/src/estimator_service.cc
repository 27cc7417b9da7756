// tactforce.v1.Estimator and tactforce.v1.Audit (estimator_service.h):
// unary RPCs through ServeOnPool; FitInertia's read reactor converts each
// message as it arrives and fits on the pool (api::RunCall) at the
// half-close.
#include "tactforce/server/estimator_service.h"

#include <atomic>
#include <utility>

#include "absl/strings/str_cat.h"
#include "tactforce/api/dispatch.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/services.h"
#include "tactforce/server/pooled_unary.h"
#include "tactforce/server/rpc_support.h"

namespace tactforce::server {
namespace {

// Reads the FitInertia stream message by message into an api::InertiaStream;
// a bad message ends the call at once with INVALID_ARGUMENT; at the
// half-close the fit runs on the pool. Deletes itself in OnDone.
class FitInertiaReactor final : public grpc::ServerReadReactor<v1::FitInertiaRequest> {
 public:
  FitInertiaReactor(grpc::CallbackServerContext* context, v1::FitInertiaResponse* response,
                    WorkerPool* pool, int64_t max_samples)
      : response_(response), pool_(pool), stream_(max_samples), guard_(context, &cancelled_),
        log_("FitInertia", guard_) {
    log_.set_pooled();  // also for a call that ends before the fit
    StartRead(&message_);
  }

  void OnReadDone(bool ok) override {
    if (!ok) return StartFit();  // half-close (or a broken call: the guard sees it)
    if (absl::Status s = stream_.Add(message_); !s.ok()) {
      Log().Emit(s);
      return Finish(ToGrpcStatus(s));
    }
    message_.Clear();
    StartRead(&message_);
  }
  void OnCancel() override { cancelled_.store(true); }
  void OnDone() override { delete this; }

 private:
  void StartFit() {
    auto fit = [this](api::CallLog&) -> absl::Status {
      if (guard_.ShouldStop()) return guard_.StopReason("before the fit started");
      api::CallLimits limits;
      limits.interrupt = guard_.Interrupt();
      absl::StatusOr<v1::FitInertiaResponse> result = stream_.Fit(limits);
      if (!result.ok()) return result.status();
      *response_ = *std::move(result);
      return absl::OkStatus();
    };
    api::RunCall(Log(), pool_, std::move(fit),
                 [this](const absl::Status& status) { Finish(ToGrpcStatus(status)); });
  }

  // The call's log line with what the stream has delivered so far.
  api::CallLog Log() const {
    api::CallLog log = log_;
    log.set_details(absl::StrCat("messages=", stream_.messages_received(),
                                 " samples=", stream_.samples_received()));
    return log;
  }

  v1::FitInertiaResponse* response_;
  WorkerPool* pool_;
  api::InertiaStream stream_;
  v1::FitInertiaRequest message_;
  std::atomic<bool> cancelled_{false};
  const RpcGuard guard_;
  api::CallLog log_;  // clock and peer from the start of the call
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
