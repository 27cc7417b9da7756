#include "plan_runner.h"

#include "absl/strings/str_cat.h"
#include "fuzz_util.h"
#include "google/protobuf/stubs/logging.h"
#include "tactforce/api/json.h"
#include "tactforce/api/services.h"

namespace tactforce::fuzz {
namespace {

// Protobuf logs each string field with invalid UTF-8 it parses at ERROR
// level; the fuzzer would spend its time printing. (The parse still fails.)
const bool kProtobufQuiet = [] {
  google::protobuf::SetLogHandler(nullptr);
  return true;
}();

// An OPTIMAL plan is a set of finite forces, one per contact.
void CheckResponse(const v1::PlanRequest& request, const v1::PlanResponse& response) {
  if (response.status() != v1::PLAN_STATUS_OPTIMAL) return;
  if (response.forces_size() != request.contacts_size()) {
    Fail("plan", absl::StrCat(response.forces_size(), " forces for ", request.contacts_size(),
                              " contacts"));
  }
  for (const v1::Vec3& f : response.forces()) {
    if (!AllFinite({f.x(), f.y(), f.z()})) Fail("plan", "OPTIMAL with a non-finite force");
  }
  if (!AllFinite({response.objective()})) Fail("plan", "OPTIMAL with a non-finite objective");
}

}  // namespace

void RunPlanRequest(const v1::PlanRequest& request) {
  absl::StatusOr<api::PlanCall> call = api::PreparePlan(request, api::CallLimits{});
  if (!call.ok()) return;
  call->solver = planner::SolverKind::kGeometric;  // never Ipopt here (see plan_runner.h)
  absl::StatusOr<v1::PlanResponse> response = api::SolvePlan(*call);
  if (!response.ok()) return;
  CheckResponse(request, *response);
  (void)api::ToJson(*response, /*compact=*/true);  // what the CLI prints
}

}  // namespace tactforce::fuzz
