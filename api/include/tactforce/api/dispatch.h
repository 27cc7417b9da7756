// How a service runs one call: where (inline on the caller's thread or on a
// bounded worker pool), under which limits, checked against the caller's
// deadline and cancellation, and logged in one line. The front end (the
// gRPC server) supplies the pool (Executor) and the caller's state
// (CallControl) and turns the final absl::Status into its own; everything
// else is decided here, so every RPC takes the same path:
//
//   PlanDispatcher::Dispatch   Planner.Plan and each PlanStream request:
//                              convert + limits, validation before queueing,
//                              inline or pool, solve, log.
//   DispatchOnPool             every other unary RPC (an api::Handle*
//                              function) and the FitInertia fit, on the pool.
//   RunCall                    the step both end in: run inline or on the
//                              pool, refuse when the pool is full, log,
//                              done(status).
//
// Threads: `done` runs exactly once, on the dispatching thread (inline work,
// invalid request, full pool) or on a worker thread. Nothing the caller
// passed by reference (request, response, control) is touched after `done`
// has run, so the caller may free them in `done`.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "tactforce/api/services.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {

// Where heavy work runs: a fixed set of threads with a bounded queue
// (tactforce-server's WorkerPool).
class Executor {
 public:
  virtual ~Executor() = default;
  // Queues `task`; false (task dropped) when the queue is full. Never
  // blocks; thread-safe.
  virtual bool TrySubmit(std::function<void()> task) = 0;
  virtual int workers() const = 0;
  virtual int max_queued() const = 0;
};

// The caller's side of one call: its deadline, cancellation and address.
// Must stay valid until the call's `done` has run; polled from any thread.
class CallControl {
 public:
  virtual ~CallControl() = default;
  // True once the deadline has passed or the caller cancelled.
  virtual bool ShouldStop() const = 0;
  // Only once ShouldStop(): DEADLINE_EXCEEDED "deadline exceeded <when>" or
  // CANCELLED "cancelled <when>" (`when`: "before the solve started", ...).
  virtual absl::Status StopReason(std::string_view when) const = 0;
  // Who is calling, for the log ("ipv4:127.0.0.1:40512"); may be empty.
  virtual std::string Peer() const = 0;
  // For CallState::interrupt: true once ShouldStop(). Valid
  // while this object is (an implementation may return a self-contained copy).
  virtual std::function<bool()> Interrupt() const {
    return [this] { return ShouldStop(); };
  }
};

// One structured line per call at info level (logfmt):
//   rpc=Plan [index=3] code=OK [details] where=inline|pool [results]
//   total_us=160790 peer=ipv4:127.0.0.1:40512 [message="..."]
// e.g. details "solver=IPOPT contacts=60", results "plan_status=OPTIMAL
// solve_us=160512". The clock starts when the CallLog is made; the peer is
// asked for only when info is logged.
class CallLog {
 public:
  // `index` >= 0: the request's position in a stream.
  CallLog(std::string_view rpc, const CallControl& control, int64_t index = -1);

  void set_details(std::string details) { details_ = std::move(details); }
  void set_results(std::string results) { results_ = std::move(results); }
  void set_pooled() { pooled_ = true; }
  const std::string& rpc() const { return rpc_; }

  void Emit(const absl::Status& status) const;

 private:
  std::string rpc_;
  int64_t index_;
  std::string peer_;
  std::string details_;
  std::string results_;
  bool pooled_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// logfmt value: bare when safe, else double-quoted with \" \\ \n \t escapes
// (other control characters become spaces).
std::string LogValue(std::string_view text);

// The words a full pool's message uses for its threads and queued items.
struct PoolWords {
  const char* workers;
  const char* queued;
};
inline constexpr PoolWords kRequestWords{"workers", "requests"};
inline constexpr PoolWords kSolveWords{"solver workers", "solves"};

// RESOURCE_EXHAUSTED "server busy: all 4 workers busy and 64 requests
// queued; retry later".
absl::Status BusyStatus(const Executor& pool, const PoolWords& words = kRequestWords);

// The end of a call: exactly once, with the call's status.
using CallDone = std::function<void(const absl::Status& status)>;
// The work of a call: returns its status (filling the response on OK) and
// may add results to the log line.
using CallWork = std::function<absl::Status(CallLog& log)>;

// Runs `work` inline (pool == nullptr) or on `pool` (the worker runs the
// call as an inline one), emits `log` with its status and calls
// done(status). A full pool drops `work` and ends the call
// with BusyStatus(*pool, words). Returns false only then. An exception out
// of `work` becomes the call's status (std::bad_alloc RESOURCE_EXHAUSTED
// "out of memory while serving this request", any other INTERNAL), never
// an abort.
bool RunCall(CallLog log, Executor* pool, CallWork work, CallDone done,
             const PoolWords& words = kRequestWords);

// Settings of the Plan path (tactforce-server's flags).
struct PlanSettings {
  CallLimits limits;            // each call polls its own CallControl
  int inline_max_contacts = 8;  // GEOMETRIC solves this small run inline; 0 = never
};

// Planner.Plan and each PlanStream request. A request runs
//   * inline, on the dispatching (gRPC) thread: SOLVER_GEOMETRIC with at
//     most inline_max_contacts contacts (default 8). Solver time, measured
//     on the 2-core dev box (Release): sphere-pinch 6.5 us, wrench-3f 61 us,
//     8 random contacts p50 160 us / p90 230 us, i.e. no worse than the
//     gRPC work around it. A pool hand-off costs more than it saves: one
//     client, 2,000 sequential Plans, 3 alternating runs each,
//       wrench-3f   p50 104-123 us inline vs 129-141 us pooled
//       8 contacts  p50 181-210 us inline vs 213-297 us pooled
//     and with 8 clients x 2,000 plans throughput was the same within the
//     noise of the shared box (median 5,400 vs 5,100 plans/s).
//   * on the pool otherwise: SOLVER_IPOPT and SOLVER_CROSS_CHECK (~20-200
//     ms) and larger geometric problems (cost grows ~n^3: 16 contacts p50
//     2 ms, 64 contacts ~66 ms). Validated first (ValidatePlan, a few
//     microseconds) so that a bad request is INVALID_ARGUMENT even under
//     overload and never takes a queue slot, and the worker solves that
//     validated plan without checking it again; a full pool is
//     RESOURCE_EXHAUSTED ("... solver workers busy and N solves queued;
//     retry later").
// Either way a request is validated once. The solve checks the CallControl
// before it starts ("before the solve started") and after it ends ("after
// N us of solving"), and polls it in between (CallState::interrupt). Log details:
// "solver=<SOLVER|-> contacts=N"; results on OK: "plan_status=<STATUS> solve_us=N". A queued
// request also logs "rpc=<rpc> event=queued solver=... contacts=N" at debug.
class PlanDispatcher {
 public:
  // `pool` (and `ipopt_lane`) must outlive the dispatcher. `ipopt_lane`:
  // where SOLVER_IPOPT and SOLVER_CROSS_CHECK requests run, so that
  // geometric work never waits behind Ipopt solves (which a process runs
  // one at a time); nullptr = on `pool` with everything else.
  PlanDispatcher(Executor* pool, PlanSettings settings, Executor* ipopt_lane = nullptr)
      : pool_(pool),
        ipopt_lane_(ipopt_lane != nullptr ? ipopt_lane : pool),
        settings_(std::move(settings)) {}

  // `request` is read before Dispatch returns; `response`, `control` and
  // `buffers` must stay valid until done(status) has run. `buffers`: the
  // stream's own (PlanStream), or nullptr for the solving thread's
  // (ThreadPlanBuffers()). Log text is formatted only at enabled levels.
  void Dispatch(const v1::PlanRequest& request, v1::PlanResponse* response, CallLog log,
                const CallControl& control, CallDone done, PlanBuffers* buffers = nullptr) const;

  const PlanSettings& settings() const { return settings_; }

 private:
  bool RunsInline(const PlanCall& call) const;

  Executor* pool_;
  Executor* ipopt_lane_;
  PlanSettings settings_;
};

// True when `solver` runs Ipopt (SOLVER_IPOPT, SOLVER_CROSS_CHECK): such
// work belongs on the server's Ipopt lane.
bool UsesIpopt(v1::Solver solver);

// The time budget of one call's work (CallLimits::solve_timeout_ms),
// counted from construction, i.e. from when the work starts.
class WorkBudget {
 public:
  // `seconds` <= 0: no budget. `interrupt`: the caller's (may be empty).
  WorkBudget(double seconds, std::function<bool()> interrupt);
  // True once `interrupt` is or the budget is spent; self-contained (a
  // copy outliving this object stays valid), for CallState::interrupt.
  std::function<bool()> Interrupt() const;
  bool Spent() const;
  // `status` unchanged unless it failed while the budget was spent: then
  // RESOURCE_EXHAUSTED "stopped at the server's limit of N ms of work per
  // call (--solve-timeout-ms): <status message>".
  absl::Status Explain(absl::Status status) const;

 private:
  double seconds_;
  std::chrono::steady_clock::time_point end_;
  std::function<bool()> interrupt_;
};

template <class Request, class Response>
using UnaryHandler =
    std::function<absl::StatusOr<Response>(const Request&, const CallLimits&, const CallState&)>;

// A unary request on the pool (never inline): `handler` (an api::Handle*
// function) runs on a worker with `limits` and, as its CallState, the
// CallControl as interrupt extended by the WorkBudget of
// limits.solve_timeout_ms; the
// call stops with the CallControl's reason "before the work started" or
// "after the work finished", or RESOURCE_EXHAUSTED when the budget ran out. `request`, `response`
// and `control` must stay valid until done(status) has run.
template <class Request, class Response>
void DispatchOnPool(const Request& request, Response* response, CallLog log, Executor* pool,
                    const CallControl& control, CallLimits limits,
                    UnaryHandler<Request, Response> handler, CallDone done) {
  auto work = [&request, response, &control, limits = std::move(limits),
               handler = std::move(handler)](CallLog&) -> absl::Status {
    if (control.ShouldStop()) return control.StopReason("before the work started");
    const WorkBudget budget(limits.solve_timeout_seconds(), control.Interrupt());
    absl::StatusOr<Response> result = handler(request, limits, CallState{budget.Interrupt()});
    if (!result.ok())
      return control.ShouldStop() ? result.status() : budget.Explain(result.status());
    if (control.ShouldStop()) return control.StopReason("after the work finished");
    *response = *std::move(result);
    return absl::OkStatus();
  };
  RunCall(std::move(log), pool, std::move(work), std::move(done));
}

}  // namespace tactforce::api
