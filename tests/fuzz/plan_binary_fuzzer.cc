// Binary PlanRequest (what a gRPC Plan call carries): ParseFromArray, then
// the Plan path of plan_runner.h.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "plan_runner.h"
#include "tactforce/v1/planner.pb.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > tactforce::fuzz::kMaxInputBytes) return 0;
  tactforce::v1::PlanRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return 0;
  tactforce::fuzz::RunPlanRequest(request);
  return 0;
}
