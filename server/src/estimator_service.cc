// tactforce.v1.Estimator and tactforce.v1.Audit (estimator_service.h):
// unary RPCs through ServeOnPool; FitInertia's read reactor converts each
// message as it arrives and fits on the pool (api::DispatchOnPool) at the
// half-close.
#include "tactforce/server/estimator_service.h"

#include <atomic>
#include <cstdint>

#include "absl/strings/str_cat.h"
#include "tactforce/api/dispatch.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/services.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/server/admitted_stream.h"
#include "tactforce/server/pooled_unary.h"
#include "tactforce/server/rpc_support.h"

namespace tactforce::server {
namespace {

// Reads the FitInertia stream message by message into an api::InertiaStream
// (a bad message ends the call at once with INVALID_ARGUMENT "message <i>:
// ..."), each message's samples and bytes taken from the registry's
// in-flight budgets before anything is kept; at the half-close the fit
// runs on the pool through api::DispatchOnPool.
class FitInertiaReactor final : public AdmittedStream<grpc::ServerReadReactor<grpc::ByteBuffer>> {
 public:
  FitInertiaReactor(grpc::CallbackServerContext* context, v1::FitInertiaResponse* response,
                    WorkerPool* pool, StreamRegistry* streams, const api::CallLimits& limits,
                    int64_t max_samples)
      : AdmittedStream(context, streams, "FitInertia"),
        response_(response),
        pool_(pool),
        limits_(limits),
        stream_(max_samples),
        log_("FitInertia", guard()) {
    log_.set_pooled();  // also for a call that ends before the fit
    Start();
  }

  // A message: convert it and read the next. The half-close (or a broken
  // call: the guard sees it): fit on the pool; the fit's end ends the call.
  void OnReadDone(bool ok) override {
    if (!ReadArrived()) return;
    if (ok) {
      if (absl::Status s = AddMessage(); !s.ok()) return End(s);
      return ReadNext();
    }
    if (!TakeOver()) return;
    api::DispatchOnPool<api::InertiaStream, v1::FitInertiaResponse>(
        stream_, response_, Log(), pool_, guard(), limits_,
        [](const api::InertiaStream& stream, const api::CallLimits& limits,
           const api::CallState& state) {
          return api::FitInertiaSamples(stream.samples(), stream.options(), limits, {}, nullptr,
                                        state);
        },
        [this](const absl::Status& status) { FinishTakenOver(status); });
  }

 private:
  absl::Status AddMessage() {
    const int index = stream_.messages_received();
    if (absl::Status parsed = ParseMessage(read_buffer(), &message_); !parsed.ok()) {
      return io::PrependPath(parsed, absl::StrCat("message ", index));
    }
    TF_RETURN_IF_ERROR(streams()->ReserveSamples(message_.samples_size()));
    reserved_samples_.fetch_add(message_.samples_size());
    const int64_t more_bytes = stream_.held_bytes_after(message_) - reserved_bytes_.load();
    if (more_bytes > 0) {
      TF_RETURN_IF_ERROR(streams()->ReserveBytes(more_bytes));
      reserved_bytes_.fetch_add(more_bytes);
    }
    absl::Status added = stream_.Add(message_);
    message_.Clear();
    return added;
  }

  void OnEnd(const absl::Status& status) override { Log().Emit(status); }
  void ReleaseBudgets() override {
    streams()->ReleaseSamples(reserved_samples_.exchange(0));
    streams()->ReleaseBytes(reserved_bytes_.exchange(0));
  }

  // The call's log line with what the stream has delivered so far.
  api::CallLog Log() const {
    api::CallLog log = log_;
    log.set_details(absl::StrCat("messages=", stream_.messages_received(),
                                 " samples=", stream_.samples_received()));
    return log;
  }

  v1::FitInertiaResponse* response_;  // gRPC's; serialized by gRPC at Finish
  WorkerPool* pool_;
  const api::CallLimits limits_;
  std::atomic<int64_t> reserved_samples_{0};  // taken from the registry's budgets
  std::atomic<int64_t> reserved_bytes_{0};
  api::InertiaStream stream_;
  v1::FitInertiaRequest message_;
  api::CallLog log_;  // clock and peer from the start of the call
};

}  // namespace

grpc::ServerReadReactor<grpc::ByteBuffer>* EstimatorService::FitInertia(
    grpc::CallbackServerContext* context, v1::FitInertiaResponse* response) {
  return new FitInertiaReactor(context, response, pool_, streams_, limits_, max_inertia_samples_);
}

grpc::ServerUnaryReactor* EstimatorService::EstimateForces(grpc::CallbackServerContext* context,
                                                           const v1::EstimateRequest* request,
                                                           v1::EstimateResponse* response) {
  return ServeOnPool<v1::EstimateRequest, v1::EstimateResponse>(
      "EstimateForces", context, request, response, pool_, limits_, &api::HandleEstimate);
}

grpc::ServerUnaryReactor* EstimatorService::EstimateFriction(grpc::CallbackServerContext* context,
                                                             const v1::FrictionRequest* request,
                                                             v1::FrictionResponse* response) {
  return ServeOnPool<v1::FrictionRequest, v1::FrictionResponse>(
      "EstimateFriction", context, request, response, pool_, limits_, &api::HandleFriction);
}

grpc::ServerUnaryReactor* AuditService::AuditModel(grpc::CallbackServerContext* context,
                                                   const v1::AuditRequest* request,
                                                   v1::AuditResponse* response) {
  return ServeOnPool<v1::AuditRequest, v1::AuditResponse>("AuditModel", context, request, response,
                                                          pool_, limits_, &api::HandleAudit);
}

}  // namespace tactforce::server
