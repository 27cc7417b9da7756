// The RPCs of the load generator (load_rpcs.h): the FitInertia stream on
// the callback API (FitInertiaCall, a ClientWriteReactor) and blocking, and
// every RPC's warm-up call.
#include "load_rpcs.h"

#include <memory>
#include <string>
#include <utility>

#include "health_check.h"

namespace tactforce::cli::load_engine {
namespace {

// One FitInertia call: writes the messages in order (the last with
// StartWriteLast, which half-closes) and hands the status to `done`. Lives
// from Begin() to OnDone, which deletes it.
class FitInertiaCall final : public grpc::ClientWriteReactor<v1::FitInertiaRequest> {
 public:
  FitInertiaCall(const std::vector<v1::FitInertiaRequest>* messages, DoneCallback done)
      : messages_(messages), done_(std::move(done)) {}

  void Begin(v1::Estimator::Stub* stub, grpc::ClientContext* context,
             v1::FitInertiaResponse* response) {
    stub->async()->FitInertia(context, response, this);
    WriteNext();
    StartCall();
  }

  void OnWriteDone(bool ok) override {
    if (ok) WriteNext();  // else the call is broken: OnDone follows
  }

  void OnDone(const grpc::Status& status) override {
    DoneCallback done = std::move(done_);
    delete this;
    done(status);
  }

 private:
  void WriteNext() {
    if (messages_->empty()) {
      StartWritesDone();
      return;
    }
    if (next_ >= messages_->size()) return;  // the last write has half-closed
    const v1::FitInertiaRequest* message = &(*messages_)[next_++];
    if (next_ == messages_->size()) {
      StartWriteLast(message, grpc::WriteOptions());
    } else {
      StartWrite(message);
    }
  }

  const std::vector<v1::FitInertiaRequest>* messages_;
  DoneCallback done_;
  size_t next_ = 0;
};

// One blocking FitInertia call writing `messages`.
grpc::Status FitInertiaBlocking(v1::Estimator::Stub& stub, grpc::ClientContext* context,
                                const std::vector<v1::FitInertiaRequest>& messages,
                                v1::FitInertiaResponse* response) {
  std::unique_ptr<grpc::ClientWriter<v1::FitInertiaRequest>> writer =
      stub.FitInertia(context, response);
  for (const v1::FitInertiaRequest& message : messages) {
    if (!writer->Write(message)) break;  // the server ended the call: Finish says why
  }
  writer->WritesDone();
  return writer->Finish();
}

absl::Status NothingToSend() { return absl::InvalidArgumentError("load: no request to send"); }

}  // namespace

absl::Status PlanRpc::WarmUp(const RemoteServer& server, const LoadSpec& spec) {
  if (spec.requests.empty()) return NothingToSend();
  return CallUnary(server, &v1::Planner::Stub::Plan, spec.requests.front()).status();
}

absl::Status HealthRpc::WarmUp(const RemoteServer& server, const LoadSpec& spec) {
  absl::StatusOr<std::string> state = CheckHealth(server, spec.health_service);
  if (state.ok() && *state == "SERVICE_UNKNOWN") {
    return UnknownServiceError(server.target(), spec.health_service);
  }
  return state.status();
}

absl::Status EstimateRpc::WarmUp(const RemoteServer& server, const LoadSpec& spec) {
  if (spec.estimate_requests.empty()) return NothingToSend();
  return CallUnary(server, &v1::Estimator::Stub::EstimateForces, spec.estimate_requests.front())
      .status();
}

absl::Status AuditRpc::WarmUp(const RemoteServer& server, const LoadSpec& spec) {
  if (spec.audit_requests.empty()) return NothingToSend();
  return CallUnary(server, &v1::Audit::Stub::AuditModel, spec.audit_requests.front()).status();
}

void FitInertiaRpc::Start(Run& run, int channel, grpc::ClientContext* context, int64_t /*ticket*/,
                          Response* response, DoneCallback done) {
  auto* call = new FitInertiaCall(&run.spec.fit_inertia_stream, std::move(done));
  call->Begin(run.estimators[channel].get(), context, response);
}

grpc::Status FitInertiaRpc::Call(Run& run, int channel, grpc::ClientContext* context,
                                 int64_t /*ticket*/, Response* response) {
  return FitInertiaBlocking(*run.estimators[channel], context, run.spec.fit_inertia_stream,
                            response);
}

absl::Status FitInertiaRpc::WarmUp(const RemoteServer& server, const LoadSpec& spec) {
  if (spec.fit_inertia_stream.empty()) return NothingToSend();
  v1::Estimator::Stub stub(server.channel());
  grpc::ClientContext context;
  server.SetDeadline(&context);
  v1::FitInertiaResponse response;
  const grpc::Status status =
      FitInertiaBlocking(stub, &context, spec.fit_inertia_stream, &response);
  return status.ok() ? absl::OkStatus() : server.Error(status);
}

}  // namespace tactforce::cli::load_engine
