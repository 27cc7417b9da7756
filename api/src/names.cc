// Short enum names from protobuf's generated descriptors (names.h).
#include "tactforce/api/names.h"

#include <string_view>

#include "absl/strings/str_cat.h"

namespace tactforce::api {
namespace {

// "PLAN_STATUS_" for PlanStatus: every value of our enums starts with the
// zero value's name minus "UNSPECIFIED" (the style buf lint enforces).
std::string_view ValuePrefix(const google::protobuf::EnumDescriptor& type) {
  constexpr std::string_view kZeroSuffix = "UNSPECIFIED";
  const std::string_view zero = type.value(0)->name();
  if (!zero.ends_with(kZeroSuffix)) return {};
  return zero.substr(0, zero.size() - kZeroSuffix.size());
}

}  // namespace

std::string ShortEnumName(const google::protobuf::EnumDescriptor& type, int number) {
  const google::protobuf::EnumValueDescriptor* value = type.FindValueByNumber(number);
  if (value == nullptr) return absl::StrCat("UNKNOWN(", number, ")");
  std::string_view name = value->name();
  if (const std::string_view prefix = ValuePrefix(type); name.starts_with(prefix)) {
    name.remove_prefix(prefix.size());
  }
  return std::string(name);
}

std::string StatusName(v1::PlanStatus status) { return ShortEnumName(status); }

std::string SolverName(v1::Solver solver) { return ShortEnumName(solver); }

}  // namespace tactforce::api
