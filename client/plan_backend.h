// Where `tactforce plan` sends a request. Today only in-process planning;
// the gRPC service adds a remote backend (`--server ADDR`) behind the same
// interface.
#pragma once

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::cli {

class PlanBackend {
 public:
  virtual ~PlanBackend() = default;
  // !ok(): the request was rejected (InvalidArgument names the field) or the
  // backend could not answer. ok(): a computed plan, whatever its status.
  virtual absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) = 0;
  // For messages: "local", "localhost:50051", ...
  virtual std::string Describe() const = 0;
};

// Plans in this process through tactforce::api::HandlePlan.
std::unique_ptr<PlanBackend> MakeLocalBackend();

}  // namespace tactforce::cli
