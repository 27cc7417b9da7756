// The --rpc and --engine spellings.
#include "load_spec.h"

namespace tactforce::cli {

const char* ToString(LoadRpc rpc) {
  switch (rpc) {
    case LoadRpc::kPlan:
      return "plan";
    case LoadRpc::kStream:
      return "stream";
    case LoadRpc::kHealth:
      return "health";
    case LoadRpc::kEstimate:
      return "estimate";
    case LoadRpc::kFitInertia:
      return "fit-inertia";
    case LoadRpc::kAudit:
      return "audit";
  }
  return "?";
}

const char* ToString(LoadEngine engine) {
  return engine == LoadEngine::kSync ? "sync" : "callback";
}

}  // namespace tactforce::cli
