#include "absl/status/status.h"
#include "audit_internal.h"

namespace tactforce::audit::internal {

absl::StatusOr<DownstreamGain> MeasureDownstreamGain(const sim::SensorModel& nominal,
                                                     const sim::SensorModel& extended, int grasps,
                                                     uint64_t seed) {
  return absl::UnimplementedError("downstream gain: not implemented yet");
}

}  // namespace tactforce::audit::internal
