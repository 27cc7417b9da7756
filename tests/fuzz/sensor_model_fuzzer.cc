// The sensor-model JSON reader (sim::SensorModelFromJson, which the
// Audit.AuditModel handler and `--model` flags use), and the round trip of
// what it accepts: SensorModelToJson must give JSON that reads back to the
// same model (a model the audit writes must load again).
#include <cstddef>
#include <cstdint>
#include <string>

#include "absl/strings/str_cat.h"
#include "fuzz_util.h"
#include "tactforce/sim/sensor_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > tactforce::fuzz::kMaxInputBytes) return 0;
  const std::string text(tactforce::fuzz::Bytes(data, size));
  absl::StatusOr<tactforce::sim::SensorModel> model =
      tactforce::sim::SensorModelFromJson(text, "fuzz.json");
  if (!model.ok()) return 0;
  if (absl::Status s = tactforce::sim::ValidateSensorModel(*model); !s.ok()) {
    tactforce::fuzz::Fail("sensor model", absl::StrCat("accepted, then invalid: ", s.message()));
  }
  const std::string written = tactforce::sim::SensorModelToJson(*model);
  absl::StatusOr<tactforce::sim::SensorModel> again =
      tactforce::sim::SensorModelFromJson(written, "written.json");
  if (!again.ok()) {
    tactforce::fuzz::Fail("sensor model round trip",
                          absl::StrCat(again.status().message(), "\n", written));
  }
  if (tactforce::sim::SensorModelToJson(*again) != written) {
    tactforce::fuzz::Fail("sensor model round trip", absl::StrCat("changed:\n", written));
  }
  return 0;
}
