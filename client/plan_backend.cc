// The two PlanBackends: in this process through the api layer's HandlePlan,
// or one unary Planner/Plan per request through CallUnary on a stub kept for
// the backend's life.
#include "plan_backend.h"

#include <utility>

#include "remote_call.h"
#include "tactforce/api/services.h"
#include "tactforce/v1/planner.grpc.pb.h"

namespace tactforce::cli {
namespace {

class LocalBackend final : public PlanBackend {
 public:
  absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) override {
    return api::HandlePlan(request, api::CallLimits{});
  }
  std::string Describe() const override { return "local"; }
};

class RemoteBackend final : public PlanBackend {
 public:
  explicit RemoteBackend(RemoteServer server)
      : server_(std::move(server)), stub_(server_.channel()) {}

  absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) override {
    return CallUnary(server_, stub_, &v1::Planner::Stub::Plan, request);
  }

  std::string Describe() const override { return server_.target(); }

 private:
  RemoteServer server_;
  v1::Planner::Stub stub_;
};

}  // namespace

std::unique_ptr<PlanBackend> MakeLocalBackend() { return std::make_unique<LocalBackend>(); }

absl::StatusOr<std::unique_ptr<PlanBackend>> MakeRemoteBackend(const ConnectionArgs& args) {
  absl::StatusOr<RemoteServer> server = RemoteServer::Open(args);
  if (!server.ok()) return server.status();
  return std::make_unique<RemoteBackend>(*std::move(server));
}

}  // namespace tactforce::cli
