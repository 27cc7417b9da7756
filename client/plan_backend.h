// Where `tactforce plan` (and `demo`) send a request: in-process planning
// (--local) or tactforce-server over gRPC (--server ADDR), behind one
// interface.
#pragma once

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "connection.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::cli {

class PlanBackend {
 public:
  virtual ~PlanBackend() = default;
  // !ok(): the request was rejected (InvalidArgument names the field) or the
  // backend could not answer (remote: Unavailable "cannot reach ADDR: ...",
  // DeadlineExceeded, ...; see RpcError in connection.h). ok(): a computed
  // plan, whatever its status.
  virtual absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) = 0;
  // For messages: "local", "localhost:50051", ...
  virtual std::string Describe() const = 0;
};

// Plans in this process through tactforce::api::HandlePlan.
std::unique_ptr<PlanBackend> MakeLocalBackend();

// Plans on tactforce-server at `args.server` (unary tactforce.v1.Planner/Plan,
// one call per Plan(), each with `args.deadline_ms`). Fails only when the
// channel cannot be built (unreadable TLS files); connecting happens on the
// first call.
absl::StatusOr<std::unique_ptr<PlanBackend>> MakeRemoteBackend(const ConnectionArgs& args);

}  // namespace tactforce::cli
