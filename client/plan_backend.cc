#include "plan_backend.h"

#include <utility>

#include <grpcpp/grpcpp.h>

#include "tactforce/api/handler.h"
#include "tactforce/v1/planner.grpc.pb.h"

namespace tactforce::cli {
namespace {

class LocalBackend final : public PlanBackend {
 public:
  absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) override {
    return api::HandlePlan(request);
  }
  std::string Describe() const override { return "local"; }
};

class RemoteBackend final : public PlanBackend {
 public:
  RemoteBackend(std::shared_ptr<grpc::Channel> channel, std::string target, int deadline_ms)
      : channel_(std::move(channel)),
        stub_(v1::Planner::NewStub(channel_)),
        target_(std::move(target)),
        deadline_ms_(deadline_ms) {}

  absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) override {
    grpc::ClientContext context;
    SetDeadline(&context, deadline_ms_);
    v1::PlanResponse response;
    const grpc::Status status = stub_->Plan(&context, request, &response);
    if (!status.ok()) return RpcError(status, target_, deadline_ms_, channel_.get());
    return response;
  }

  std::string Describe() const override { return target_; }

 private:
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Planner::Stub> stub_;
  std::string target_;
  int deadline_ms_;
};

}  // namespace

std::unique_ptr<PlanBackend> MakeLocalBackend() { return std::make_unique<LocalBackend>(); }

absl::StatusOr<std::unique_ptr<PlanBackend>> MakeRemoteBackend(const ConnectionArgs& args) {
  absl::StatusOr<std::shared_ptr<grpc::Channel>> channel = MakeChannel(args, args.server);
  if (!channel.ok()) return channel.status();
  return std::make_unique<RemoteBackend>(*std::move(channel), args.server, args.deadline_ms);
}

}  // namespace tactforce::cli
