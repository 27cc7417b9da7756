// tactforce.v1.Estimator and tactforce.v1.Audit (estimator_service.h):
// unary RPCs through ServeOnPool; FitInertia's read reactor converts each
// message as it arrives and fits on the pool (api::RunCall) at the
// half-close.
#include "tactforce/server/estimator_service.h"

#include <atomic>
#include <chrono>
#include <mutex>
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
// half-close the fit runs on the pool. Messages are read raw and parsed
// here, so that one that cannot be parsed ends the call with "message <i>:
// cannot be parsed ..." (gRPC's typed reader would report it as the
// half-close, and a partial stream would be fitted). Admitted, timed out and
// held to the in-flight sample and byte budgets by the StreamRegistry.
// Deletes itself once gRPC (OnDone) and the registry have let go.
class FitInertiaReactor final : public grpc::ServerReadReactor<grpc::ByteBuffer>,
                                public IdleEndable {
 public:
  FitInertiaReactor(grpc::CallbackServerContext* context, grpc::ByteBuffer* response,
                    WorkerPool* pool, StreamRegistry* streams, const EstimatorServiceOptions& options)
      : response_(response), pool_(pool), streams_(streams), stream_(options.max_inertia_samples),
        max_call_seconds_(options.solve_timeout_ms / 1000.0), max_fit_bytes_(options.max_fit_bytes),
        guard_(context, &cancelled_),
        log_("FitInertia", guard_) {
    log_.set_pooled();  // also for a call that ends before the fit
    if (absl::Status admitted = streams_->Open(this, "FitInertia"); !admitted.ok()) {
      EndWith(admitted);
      return;
    }
    registered_.store(true);
    ReadNext();
  }

  void OnReadDone(bool ok) override {
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (finished_) return;  // ended for idling while this read was pending
      waiting_ = false;
    }
    if (!ok) return StartFit();  // half-close (or a broken call: the guard sees it)
    if (absl::Status s = AddMessage(); !s.ok()) return EndWith(s);
    ReadNext();
  }
  void OnCancel() override { cancelled_.store(true); }
  void OnDone() override {
    ReleaseBudgets();
    Unregister();
    Unref();
  }

  void Ref() override { refs_.fetch_add(1, std::memory_order_relaxed); }
  void Unref() override {
    if (refs_.fetch_sub(1, std::memory_order_acq_rel) == 1) delete this;
  }
  void EndIfIdleSince(std::chrono::steady_clock::time_point cutoff, const absl::Status& status) override {
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (finished_ || !waiting_ || waiting_since_ >= cutoff) return;
    }
    EndWith(status);
  }

 private:
  void ReadNext() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      waiting_ = true;
      waiting_since_ = std::chrono::steady_clock::now();
    }
    StartRead(&buffer_);
  }

  // Parses the message just read and adds it to the stream, its samples
  // and bytes taken from the server's budgets before anything is kept.
  absl::Status AddMessage() {
    const int index = stream_.messages_received();
    if (absl::Status parsed = ParseMessage(&buffer_, &message_); !parsed.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("message ", index, ": ", parsed.message()));
    }
    absl::Status s = streams_->ReserveSamples(message_.samples_size());
    if (!s.ok()) return s;
    reserved_samples_.fetch_add(message_.samples_size());
    const int64_t more_bytes = stream_.held_bytes_after(message_) - reserved_bytes_.load();
    if (more_bytes > 0) {
      if (s = streams_->ReserveBytes(more_bytes); !s.ok()) return s;
      reserved_bytes_.fetch_add(more_bytes);
    }
    s = stream_.Add(message_);
    message_.Clear();
    return s;
  }

  // Logs and finishes once, whichever of reader, reaper and fit comes first.
  void EndWith(const absl::Status& status) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (finished_) return;
      finished_ = true;
    }
    Log().Emit(status);
    ReleaseBudgets();
    Unregister();
    Finish(ToGrpcStatus(status));
  }

  // Back to the budgets, and the stream's slot freed, before the client
  // hears the end: a client that opens its next stream at once finds both.
  void ReleaseBudgets() {
    streams_->ReleaseSamples(reserved_samples_.exchange(0));
    streams_->ReleaseBytes(reserved_bytes_.exchange(0));
  }
  void Unregister() {
    if (registered_.exchange(false)) streams_->Close(this);
  }

  void StartFit() {
    auto fit = [this](api::CallLog&) -> absl::Status {
      if (guard_.ShouldStop()) return guard_.StopReason("before the fit started");
      const api::WorkBudget budget(max_call_seconds_, guard_.Interrupt());
      api::CallLimits limits;
      limits.max_fit_bytes = max_fit_bytes_;
      absl::StatusOr<v1::FitInertiaResponse> result =
          stream_.Fit(limits, {}, api::CallState{budget.Interrupt()});
      if (!result.ok()) return guard_.ShouldStop() ? result.status() : budget.Explain(result.status());
      return SerializeMessage(*result, response_);
    };
    {
      std::lock_guard<std::mutex> lock(mu_);
      finished_ = true;  // from here the fit's `done` finishes the call
    }
    api::RunCall(Log(), pool_, std::move(fit),
                 [this](const absl::Status& status) {
                   ReleaseBudgets();
                   Unregister();
                   Finish(ToGrpcStatus(status));
                 });
  }

  // The call's log line with what the stream has delivered so far.
  api::CallLog Log() const {
    api::CallLog log = log_;
    log.set_details(absl::StrCat("messages=", stream_.messages_received(),
                                 " samples=", stream_.samples_received()));
    return log;
  }

  grpc::ByteBuffer* response_;
  WorkerPool* pool_;
  StreamRegistry* streams_;
  std::atomic<bool> registered_{false};  // admitted and not yet closed
  std::atomic<int64_t> reserved_samples_{0};  // taken from the registry's budgets
  std::atomic<int64_t> reserved_bytes_{0};
  api::InertiaStream stream_;
  double max_call_seconds_;
  int64_t max_fit_bytes_;
  grpc::ByteBuffer buffer_;
  v1::FitInertiaRequest message_;
  std::atomic<bool> cancelled_{false};
  std::atomic<int> refs_{1};  // gRPC's until OnDone; the reaper's while it looks
  std::mutex mu_;             // guards finished_, waiting_, waiting_since_
  bool finished_ = false;
  bool waiting_ = false;
  std::chrono::steady_clock::time_point waiting_since_{};
  const RpcGuard guard_;
  api::CallLog log_;  // clock and peer from the start of the call
};

}  // namespace

api::CallLimits EstimatorServiceOptions::Limits() const {
  api::CallLimits limits;
  limits.max_contacts = max_contacts;
  limits.max_audit_samples = max_audit_samples;
  limits.solve_timeout_ms = solve_timeout_ms;
  return limits;
}

grpc::ServerReadReactor<grpc::ByteBuffer>* EstimatorService::FitInertia(
    grpc::CallbackServerContext* context, grpc::ByteBuffer* response) {
  return new FitInertiaReactor(context, response, pool_, streams_, options_);
}

grpc::ServerUnaryReactor* EstimatorService::EstimateForces(grpc::CallbackServerContext* context,
                                                           const v1::EstimateRequest* request,
                                                           v1::EstimateResponse* response) {
  api::CallLimits limits = options_.Limits();
  return ServeOnPool<v1::EstimateRequest, v1::EstimateResponse>(
      "EstimateForces", context, request, response, pool_, limits, &api::HandleEstimate);
}

grpc::ServerUnaryReactor* EstimatorService::EstimateFriction(grpc::CallbackServerContext* context,
                                                             const v1::FrictionRequest* request,
                                                             v1::FrictionResponse* response) {
  return ServeOnPool<v1::FrictionRequest, v1::FrictionResponse>(
      "EstimateFriction", context, request, response, pool_, options_.Limits(),
      [](const v1::FrictionRequest& r, const api::CallLimits& l, const api::CallState& c) {
        return api::HandleFriction(r, l, c);
      });
}

grpc::ServerUnaryReactor* AuditService::AuditModel(grpc::CallbackServerContext* context,
                                                   const v1::AuditRequest* request,
                                                   v1::AuditResponse* response) {
  return ServeOnPool<v1::AuditRequest, v1::AuditResponse>(
      "AuditModel", context, request, response, pool_, options_.Limits(),
      [](const v1::AuditRequest& r, const api::CallLimits& l, const api::CallState& c) {
        return api::HandleAudit(r, l, c);
      });
}

}  // namespace tactforce::server
