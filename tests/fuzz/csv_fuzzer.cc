// The CSV readers. The first byte picks one (byte % 3):
//   0 ('0'): io::ParseCsv (bit 3 of the byte: skip_nan_rows) +
//            estimator::FrictionTrialFromCsv, then EstimateFriction on the
//            trial with a fixed normal (the CLI's `estimate friction`);
//   1 ('1'): audit::ParseMeasuredCsv (t, reference, reading[, shear, trial]);
//   2 ('2'): inertia::ParseInertiaCsv (poses + contact forces or a wrench).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "tactforce/audit/measured_data.h"
#include "tactforce/estimator/friction.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/io/csv.h"

namespace {

void FuzzFriction(const std::string& text, bool skip_nan_rows) {
  tactforce::io::CsvOptions options;
  options.skip_nan_rows = skip_nan_rows;
  absl::StatusOr<tactforce::io::CsvTable> table =
      tactforce::io::ParseCsv(text, "fuzz.csv", options);
  if (!table.ok()) return;
  for (const std::string& column : table->columns) (void)table->Column(column);
  absl::StatusOr<tactforce::estimator::FrictionTrial> trial =
      tactforce::estimator::FrictionTrialFromCsv(*table);
  if (!trial.ok()) return;
  trial->normal = tactforce::estimator::Vec3(0, 0, 1);
  (void)tactforce::estimator::EstimateFriction({*trial});
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > tactforce::fuzz::kMaxInputBytes) return 0;
  const std::string text(tactforce::fuzz::Bytes(data + 1, size - 1));
  switch (data[0] % 3) {
    case 0:
      FuzzFriction(text, (data[0] & 8) != 0);
      break;
    case 1:
      (void)tactforce::audit::ParseMeasuredCsv(text, "fuzz.csv");
      break;
    default:
      (void)tactforce::inertia::ParseInertiaCsv(text, "fuzz.csv");
      break;
  }
  return 0;
}
