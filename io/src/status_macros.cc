#include "tactforce/io/status_macros.h"

#include "absl/strings/str_cat.h"

namespace tactforce::io {

absl::Status PrependPath(const absl::Status& status, absl::string_view path,
                         absl::string_view separator) {
  if (status.ok() || path.empty()) return status;
  absl::Status out(status.code(), absl::StrCat(path, separator, status.message()));
  status.ForEachPayload(
      [&out](absl::string_view url, const absl::Cord& payload) { out.SetPayload(url, payload); });
  return out;
}

}  // namespace tactforce::io
