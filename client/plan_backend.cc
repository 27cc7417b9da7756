#include "plan_backend.h"

#include "tactforce/api/handler.h"

namespace tactforce::cli {
namespace {

class LocalBackend final : public PlanBackend {
 public:
  absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) override {
    return api::HandlePlan(request);
  }
  std::string Describe() const override { return "local"; }
};

}  // namespace

std::unique_ptr<PlanBackend> MakeLocalBackend() { return std::make_unique<LocalBackend>(); }

}  // namespace tactforce::cli
