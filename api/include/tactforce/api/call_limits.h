// What a service allows one call (CallLimits: the server's flags, held once
// in tactforce-server's ServerConfig; the CLI takes the defaults) and, apart
// from it, the state of one call (CallState: the caller's interrupt).
#pragma once

#include <cstdint>
#include <functional>

#include "tactforce/planner/types.h"

namespace tactforce::api {

struct CallLimits {
  // Contacts per plan or estimate (the server's --max-contacts).
  int max_contacts = planner::PlanOptions{}.max_contacts;
  // Work of one call, in milliseconds (0 = none; the server's
  // --solve-timeout-ms): wall clock on the thread doing it, from when the
  // work starts (queue wait excluded), and the CPU of each Ipopt solve.
  // Long loops poll CallState::interrupt, which the dispatcher extends with
  // this budget (WorkBudget, dispatch.h); a call that runs out stops with
  // RESOURCE_EXHAUSTED naming the flag.
  int64_t solve_timeout_ms = 0;
  // PlanTrajectory / PlanFrictionProbe: at most this many steps x contacts x
  // cone sides, checked before any solve (the server's --max-trajectory-work).
  int64_t max_trajectory_work = 4'000'000;
  // Largest response the caller can receive (bytes; 0 = no limit; the
  // server's --max-message-bytes): a trajectory, probe or audit whose answer
  // cannot fit is refused before any work (InvalidArgument naming the limit).
  int64_t max_response_bytes = 0;
  // AuditModel: most samples one request may carry (--max-audit-samples).
  int64_t max_audit_samples = 1'000'000;
  // FitInertia: most working memory one fit may take (bytes, estimated
  // before it starts with inertia::FitWorkingBytes; 0 = no limit;
  // --max-fit-bytes).
  int64_t max_fit_bytes = 0;

  // solve_timeout_ms in seconds (0 = none): the one ms -> s conversion.
  double solve_timeout_seconds() const { return static_cast<double>(solve_timeout_ms) / 1000.0; }
};

// The state of one call, apart from its limits.
struct CallState {
  // True once the call should stop (the caller's deadline or cancellation,
  // the work budget); polled by long loops; may be empty.
  std::function<bool()> interrupt;
};

}  // namespace tactforce::api
