#include "tactforce/server/planner_service.h"

#include "tactforce/server/pooled_unary.h"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "spdlog/spdlog.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/validation.h"

namespace tactforce::server {
namespace {

using Clock = std::chrono::steady_clock;

int64_t MicrosSince(Clock::time_point start) {
  return std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start).count();
}

// One structured log line per request, at info:
//   rpc=Plan code=OK solver=IPOPT contacts=60 plan_status=OPTIMAL
//   solve_us=160512 total_us=160790 peer=ipv4:127.0.0.1:40512
class CallLog {
 public:
  CallLog(const char* rpc, const grpc::CallbackServerContext* context, int contacts,
          int64_t index = -1)
      : rpc_(rpc), index_(index), contacts_(contacts) {
    if (spdlog::should_log(spdlog::level::info)) peer_ = context->peer();
  }

  void set_solver(planner::SolverKind solver) { solver_ = planner::ToString(solver); }
  void set_pooled() { pooled_ = true; }

  void Emit(const grpc::Status& status, const v1::PlanResponse* response) const {
    if (!spdlog::should_log(spdlog::level::info)) return;
    std::string line = absl::StrCat("rpc=", rpc_);
    if (index_ >= 0) absl::StrAppend(&line, " index=", index_);
    absl::StrAppend(&line, " code=", StatusCodeName(status.error_code()), " solver=", solver_,
                    " contacts=", contacts_, " where=", pooled_ ? "pool" : "inline");
    if (status.ok() && response != nullptr) {
      absl::StrAppend(&line, " plan_status=", api_status(response->status()),
                      " solve_us=", response->solve_time_us());
    }
    absl::StrAppend(&line, " total_us=", MicrosSince(start_), " peer=", LogValue(peer_));
    if (!status.ok()) absl::StrAppend(&line, " message=", LogValue(status.error_message()));
    spdlog::info("{}", line);
  }

 private:
  static const char* api_status(v1::PlanStatus status) {
    switch (status) {
      case v1::PLAN_STATUS_OPTIMAL: return "OPTIMAL";
      case v1::PLAN_STATUS_INFEASIBLE: return "INFEASIBLE";
      case v1::PLAN_STATUS_SOLVER_FAILURE: return "SOLVER_FAILURE";
      default: return "UNSPECIFIED";
    }
  }

  const char* rpc_;
  int64_t index_;
  int contacts_;
  const char* solver_ = "-";
  bool pooled_ = false;
  std::string peer_;
  Clock::time_point start_ = Clock::now();
};

grpc::Status QueueFull(const WorkerPool& pool) {
  return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                      absl::StrCat("server busy: all ", pool.workers(), " solver workers busy and ",
                                   pool.max_queued(), " solves queued; retry later"));
}

// ---------------------------------------------------------------- PlanStream

class PlanStreamReactor final
    : public grpc::ServerBidiReactor<v1::PlanRequest, v1::PlanResponse> {
 public:
  PlanStreamReactor(const PlannerService* service, grpc::CallbackServerContext* context)
      : service_(service), context_(context), guard_(context, &cancelled_) {
    if (spdlog::should_log(spdlog::level::info)) peer_ = context->peer();
    StartRead(&request_);
  }

  void OnReadDone(bool ok) override {
    if (!ok) {
      // Half-close by the client (normal end), or a broken / cancelled call.
      FinishOnce(guard_.ShouldStop() ? guard_.StopStatus("while reading") : grpc::Status::OK);
      return;
    }
    Dispatch();
  }

  void OnWriteDone(bool ok) override {
    if (!ok) {
      FinishOnce(guard_.ShouldStop() ? guard_.StopStatus("while writing")
                                     : grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                                    "stream broken while writing"));
      return;
    }
    ++index_;
    request_.Clear();
    StartRead(&request_);
  }

  void OnCancel() override { cancelled_.store(true, std::memory_order_relaxed); }

  void OnDone() override { Unref(); }

 private:
  // Exactly one of: a read pending, a solve running, a write pending, or
  // finished. So no lock is needed around request_/response_.
  void Dispatch() {
    CallLog log("PlanStream", context_, request_.contacts_size(), index_);
    absl::StatusOr<api::PlanCall> call = service_->Prepare(request_);
    if (call.ok()) log.set_solver(call->solver);
    if (call.ok() && !service_->RunsInline(*call)) {
      if (absl::Status valid = service_->Validate(*call); !valid.ok()) call = valid;
    }
    if (!call.ok()) {
      grpc::Status status = ToGrpcStatus(call.status());
      log.Emit(status, nullptr);
      FinishOnce(Indexed(status));
      return;
    }
    if (service_->RunsInline(*call)) {
      grpc::Status status = service_->Execute(*call, guard_, &response_);
      log.Emit(status, &response_);
      Complete(status);
      return;
    }
    log.set_pooled();
    refs_.fetch_add(1, std::memory_order_relaxed);  // held by the task
    auto job = std::make_shared<std::pair<api::PlanCall, CallLog>>(*std::move(call), log);
    const bool queued = service_->pool()->TrySubmit([this, job] {
      grpc::Status status = service_->Execute(job->first, guard_, &response_);
      job->second.Emit(status, &response_);
      Complete(status);
      Unref();
    });
    if (!queued) {
      refs_.fetch_sub(1, std::memory_order_relaxed);
      grpc::Status status = QueueFull(*service_->pool());
      log.Emit(status, nullptr);
      FinishOnce(Indexed(status));
    }
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
    } else {
      StartWrite(&response_);
    }
  }

  void FinishOnce(const grpc::Status& status) {
    {
      std::lock_guard<std::mutex> lock(finish_mu_);
      if (finished_) return;
      finished_ = true;
    }
    // One line per stream besides the per-request ones.
    spdlog::info("rpc=PlanStream event=end code={} responses={} total_us={} peer={}",
                 StatusCodeName(status.error_code()), index_, MicrosSince(start_),
                 LogValue(peer_));
    Finish(status);
  }

  // gRPC holds one reference until OnDone; a queued or running solve holds
  // another, because OnDone may run before the task has returned.
  void Unref() {
    if (refs_.fetch_sub(1, std::memory_order_acq_rel) == 1) delete this;
  }

  const PlannerService* service_;
  grpc::CallbackServerContext* context_;
  std::atomic<bool> cancelled_{false};
  RpcGuard guard_;
  std::atomic<int> refs_{1};
  std::mutex finish_mu_;
  bool finished_ = false;
  int64_t index_ = 0;  // requests answered so far = index of the current one
  std::string peer_;
  const Clock::time_point start_ = Clock::now();
  v1::PlanRequest request_;
  v1::PlanResponse response_;
};

}  // namespace

PlannerService::PlannerService(WorkerPool* pool, PlannerServiceOptions options)
    : pool_(pool), options_(options) {}

std::string PlannerService::service_name() const {
  return std::string(v1::Planner::service_full_name());
}

absl::StatusOr<api::PlanCall> PlannerService::Prepare(const v1::PlanRequest& request) const {
  absl::StatusOr<api::PlanCall> call = api::FromProto(request);
  if (!call.ok()) return call.status();
  call->options.max_contacts = options_.max_contacts;
  call->options.ipopt_max_cpu_seconds = options_.solve_timeout_ms / 1000.0;
  return call;
}

bool PlannerService::RunsInline(const api::PlanCall& call) const {
  return call.solver == planner::SolverKind::kGeometric &&
         static_cast<int>(call.problem.contacts.size()) <= options_.inline_max_contacts;
}

absl::Status PlannerService::Validate(const api::PlanCall& call) const {
  return planner::ValidateProblem(call.problem, call.options).status();
}

grpc::Status PlannerService::Execute(api::PlanCall& call, const RpcGuard& guard,
                                     v1::PlanResponse* response) const {
  if (guard.ShouldStop()) return guard.StopStatus("before the solve started");
  call.options.interrupt = guard.Interrupt();
  absl::StatusOr<planner::PlanResult> result =
      planner::Plan(call.problem, call.options, call.solver);
  if (!result.ok()) return ToGrpcStatus(result.status());
  if (guard.ShouldStop()) {
    return guard.StopStatus(absl::StrCat("after ", result->solve_time_us, " us of solving"));
  }
  *response = api::ToProto(*result);
  return grpc::Status::OK;
}

grpc::ServerUnaryReactor* PlannerService::Plan(grpc::CallbackServerContext* context,
                                               const v1::PlanRequest* request,
                                               v1::PlanResponse* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  CallLog log("Plan", context, request->contacts_size());
  absl::StatusOr<api::PlanCall> call = Prepare(*request);
  if (call.ok()) log.set_solver(call->solver);
  if (call.ok() && !RunsInline(*call)) {
    if (absl::Status valid = Validate(*call); !valid.ok()) call = valid;
  }
  if (!call.ok()) {
    grpc::Status status = ToGrpcStatus(call.status());
    log.Emit(status, nullptr);
    reactor->Finish(status);
    return reactor;
  }

  if (RunsInline(*call)) {
    grpc::Status status = Execute(*call, RpcGuard(context), response);
    log.Emit(status, response);
    reactor->Finish(status);
    return reactor;
  }

  log.set_pooled();
  const int contacts = request->contacts_size();
  const planner::SolverKind solver = call->solver;
  // context, request and response stay valid until Finish() is called, which
  // the task may do before TrySubmit() even returns: do not touch them below.
  struct Job {
    api::PlanCall call;
    CallLog log;
  };
  auto job = std::make_shared<Job>(Job{*std::move(call), log});
  const bool queued = pool_->TrySubmit([this, context, reactor, response, job] {
    grpc::Status status = Execute(job->call, RpcGuard(context), response);
    job->log.Emit(status, response);
    reactor->Finish(status);
  });
  if (!queued) {
    grpc::Status status = QueueFull(*pool_);
    log.Emit(status, nullptr);
    reactor->Finish(status);
  } else {
    spdlog::debug("rpc=Plan event=queued solver={} contacts={}", planner::ToString(solver),
                  contacts);
  }
  return reactor;
}

grpc::ServerBidiReactor<v1::PlanRequest, v1::PlanResponse>* PlannerService::PlanStream(
    grpc::CallbackServerContext* context) {
  return new PlanStreamReactor(this, context);
}

api::CallLimits PlannerService::Limits() const {
  api::CallLimits limits;
  limits.max_contacts = options_.max_contacts;
  limits.ipopt_max_cpu_seconds = options_.solve_timeout_ms / 1000.0;
  return limits;
}

grpc::ServerUnaryReactor* PlannerService::PlanTrajectory(grpc::CallbackServerContext* context,
                                                         const v1::TrajectoryRequest* request,
                                                         v1::TrajectoryResponse* response) {
  return ServeOnPool<v1::TrajectoryRequest, v1::TrajectoryResponse>(
      "PlanTrajectory", context, request, response, pool_, Limits(), &api::HandleTrajectory);
}

grpc::ServerUnaryReactor* PlannerService::PlanFrictionProbe(grpc::CallbackServerContext* context,
                                                            const v1::FrictionProbeRequest* request,
                                                            v1::FrictionProbeResponse* response) {
  return ServeOnPool<v1::FrictionProbeRequest, v1::FrictionProbeResponse>(
      "PlanFrictionProbe", context, request, response, pool_, Limits(), &api::HandleFrictionProbe);
}

}  // namespace tactforce::server
