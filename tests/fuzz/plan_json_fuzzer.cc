// proto3-JSON requests (api::ParseJson, the CLI's and load tester's reader):
// the first byte picks the message, even = PlanRequest (then the Plan path,
// plan_runner.h), odd = EstimateRequest (then api::HandleEstimate, what the
// Estimator.EstimateForces handler calls). Corpus files start with 'P' or 'E'.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "plan_runner.h"
#include "tactforce/api/json.h"
#include "tactforce/api/services.h"
#include "tactforce/v1/estimator.pb.h"

namespace {

void FuzzEstimate(std::string_view json) {
  tactforce::v1::EstimateRequest request;
  if (!tactforce::api::ParseJson(json, &request).ok()) return;
  absl::StatusOr<tactforce::v1::EstimateResponse> response =
      tactforce::api::HandleEstimate(request);
  if (!response.ok()) return;
  (void)tactforce::api::ToJson(*response, /*compact=*/true);
}

void FuzzPlan(std::string_view json) {
  absl::StatusOr<tactforce::v1::PlanRequest> request = tactforce::api::ParsePlanRequestJson(json);
  if (!request.ok()) return;
  tactforce::fuzz::RunPlanRequest(*request);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > tactforce::fuzz::kMaxInputBytes) return 0;
  const std::string_view json = tactforce::fuzz::Bytes(data + 1, size - 1);
  if (data[0] % 2 == 0) {
    FuzzPlan(json);
  } else {
    FuzzEstimate(json);
  }
  return 0;
}
