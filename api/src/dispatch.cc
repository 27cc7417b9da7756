// The one path of a service call (dispatch.h): RunCall places the work
// (inline, or on the pool where the worker runs it as an inline call;
// refused when the pool is full), runs it guarded against exceptions, logs
// one line and ends the call; PlanDispatcher adds the Plan-specific steps in front of it
// (conversion with limits, the inline-or-pool choice, validation before
// queueing) and the solve with its deadline and cancellation checks.
#include "tactforce/api/dispatch.h"

#include <cmath>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "spdlog/spdlog.h"
#include "tactforce/api/names.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::api {
namespace {

int64_t MicrosSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() -
                                                               start)
      .count();
}

// Solves a request (the inline call: validated by the solve itself; the
// pool task: validated before it was queued) with the stream's buffers, or
// the running thread's when `buffers` is null.
template <class Call>
absl::Status ExecutePlan(const Call& call, const CallControl& control, PlanBuffers* buffers,
                         v1::PlanResponse* response, CallLog& log) {
  if (control.ShouldStop()) return control.StopReason("before the solve started");
  // Into the caller's response (a unary Plan's lives on the call's arena).
  TF_RETURN_IF_ERROR(SolvePlan(call, CallState{control.Interrupt()}, buffers, response));
  if (control.ShouldStop()) {
    return control.StopReason(absl::StrCat("after ", response->solve_time_us(), " us of solving"));
  }
  if (spdlog::should_log(spdlog::level::info)) {
    log.set_results(absl::StrCat("plan_status=", StatusName(response->status()),
                                 " solve_us=", response->solve_time_us()));
  }
  return absl::OkStatus();
}

}  // namespace

CallLog::CallLog(std::string_view rpc, const CallControl& control, int64_t index)
    : rpc_(rpc), index_(index) {
  if (spdlog::should_log(spdlog::level::info)) peer_ = control.Peer();
}

void CallLog::Emit(const absl::Status& status) const {
  if (!spdlog::should_log(spdlog::level::info)) return;
  std::string line = absl::StrCat("rpc=", rpc_);
  if (index_ >= 0) absl::StrAppend(&line, " index=", index_);
  absl::StrAppend(&line, " code=", absl::StatusCodeToString(status.code()));
  if (!details_.empty()) absl::StrAppend(&line, " ", details_);
  absl::StrAppend(&line, " where=", pooled_ ? "pool" : "inline");
  if (status.ok() && !results_.empty()) absl::StrAppend(&line, " ", results_);
  absl::StrAppend(&line, " total_us=", MicrosSince(start_), " peer=", LogValue(peer_));
  if (!status.ok()) absl::StrAppend(&line, " message=", LogValue(std::string(status.message())));
  spdlog::info("{}", line);
}

std::string LogValue(std::string_view text) {
  bool bare = !text.empty();
  for (char c : text) {
    if (c == ' ' || c == '"' || c == '=' || c == '\\' || static_cast<unsigned char>(c) < 0x20) {
      bare = false;
      break;
    }
  }
  if (bare) return std::string(text);
  std::string out = "\"";
  for (char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        out += static_cast<unsigned char>(c) < 0x20 ? ' ' : c;
    }
  }
  out += '"';
  return out;
}

absl::Status BusyStatus(const Executor& pool, const PoolWords& words) {
  return absl::ResourceExhaustedError(absl::StrCat("server busy: all ", pool.workers(), " ",
                                                   words.workers, " busy and ", pool.max_queued(),
                                                   " ", words.queued, " queued; retry later"));
}

WorkBudget::WorkBudget(double seconds, std::function<bool()> interrupt)
    : seconds_(seconds > 0 ? seconds : 0.0), interrupt_(std::move(interrupt)) {
  if (seconds_ > 0) {
    end_ = std::chrono::steady_clock::now() +
           std::chrono::duration_cast<std::chrono::steady_clock::duration>(
               std::chrono::duration<double>(seconds_));
  }
}

std::function<bool()> WorkBudget::Interrupt() const {
  if (seconds_ == 0) return interrupt_;
  return [end = end_, inner = interrupt_] {
    return (inner && inner()) || std::chrono::steady_clock::now() >= end;
  };
}

bool WorkBudget::Spent() const { return seconds_ > 0 && std::chrono::steady_clock::now() >= end_; }

absl::Status WorkBudget::Explain(absl::Status status) const {
  if (status.ok() || !Spent()) return status;
  return absl::ResourceExhaustedError(
      absl::StrCat("stopped at the server's limit of ", std::llround(seconds_ * 1000),
                   " ms of work per call (--solve-timeout-ms): ", status.message()));
}

bool RunCall(CallLog log, Executor* pool, CallWork work, CallDone done, const PoolWords& words) {
  if (pool != nullptr) {
    log.set_pooled();
    // The pool task owns the log, the work and `done` (the caller's objects
    // may be gone once `done` has run, possibly before TrySubmit returns) and
    // runs the call as an inline one, on its worker.
    struct Call {
      CallLog log;
      CallWork work;
      CallDone done;
    };
    auto call = std::make_shared<Call>(Call{std::move(log), std::move(work), std::move(done)});
    if (pool->TrySubmit([call] {
          RunCall(std::move(call->log), nullptr, std::move(call->work), std::move(call->done));
        })) {
      return true;
    }
    // The pool dropped its copy; `call` is still ours.
    const absl::Status busy = BusyStatus(*pool, words);
    call->log.Emit(busy);
    call->done(busy);
    return false;
  }
  // Work that throws (std::bad_alloc from an allocation a request drove, an
  // exception of a third-party library) ends its call with a status; nothing
  // escapes into gRPC's threads or the worker pool, which would abort.
  absl::Status status;
  try {
    status = work(log);
  } catch (const std::bad_alloc&) {
    status = absl::ResourceExhaustedError("out of memory while serving this request");
  } catch (const std::exception& e) {
    status = absl::InternalError(absl::StrCat("internal error: ", e.what()));
  } catch (...) {
    status = absl::InternalError("internal error: an unknown exception");
  }
  log.Emit(status);
  done(status);
  return true;
}

bool UsesIpopt(v1::Solver solver) {
  return solver == v1::SOLVER_IPOPT || solver == v1::SOLVER_CROSS_CHECK;
}

bool PlanDispatcher::RunsInline(const PlanCall& call) const {
  return call.solver == planner::SolverKind::kGeometric &&
         static_cast<int>(call.problem.contacts.size()) <= settings_.inline_max_contacts;
}

void PlanDispatcher::Dispatch(const v1::PlanRequest& request, v1::PlanResponse* response,
                              CallLog log, const CallControl& control, CallDone done,
                              PlanBuffers* buffers) const {
  // Converted into the stream's or this thread's buffers: a warm thread
  // converts without allocating.
  PlanBuffers& here = buffers != nullptr ? *buffers : ThreadPlanBuffers();
  const PlanCall& call = here.call;
  const absl::Status prepared = PreparePlan(request, settings_.limits, &here.call);
  // Log text is formatted only when its level is on.
  const bool debug = spdlog::should_log(spdlog::level::debug);
  std::string details;
  if (debug || spdlog::should_log(spdlog::level::info)) {
    details = absl::StrCat("solver=", prepared.ok() ? planner::ToString(call.solver) : "-",
                           " contacts=", request.contacts_size());
    log.set_details(details);
  }
  if (!prepared.ok()) {
    log.Emit(prepared);
    done(prepared);
    return;
  }
  // From here on `log` may be logged (and `response` freed) on a worker
  // thread before RunCall returns: only locals are used after it.
  if (RunsInline(call)) {  // validated once, by the solve, in the same buffers
    auto work = [&call, &control, &here, response](CallLog& call_log) {
      return ExecutePlan(call, control, &here, response, call_log);
    };
    RunCall(std::move(log), nullptr, std::move(work), std::move(done), kSolveWords);
    return;
  }
  // Validated once, here, so that a bad request is INVALID_ARGUMENT even
  // under overload and never takes a queue slot; the worker solves the
  // validated plan (a copy: `here` is this thread's) without a second check.
  absl::StatusOr<ValidPlanCall> valid = ValidatePlan(call);
  if (!valid.ok()) {
    log.Emit(valid.status());
    done(valid.status());
    return;
  }
  std::string rpc_name;
  if (debug) rpc_name = log.rpc();
  auto work = [valid = *std::move(valid), &control, buffers, response](CallLog& call_log) {
    return ExecutePlan(valid, control, buffers, response, call_log);
  };
  Executor* where = UsesIpopt(request.solver()) ? ipopt_lane_ : pool_;
  const bool queued = RunCall(std::move(log), where, std::move(work), std::move(done), kSolveWords);
  if (debug && queued) spdlog::debug("rpc={} event=queued {}", rpc_name, details);
}

}  // namespace tactforce::api
