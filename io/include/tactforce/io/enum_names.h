// The one convention for an enum's names in CLI flags, JSON and proto
// spellings: a table of {value, name} rows and a parse with one
// normalisation rule and one error message.
//
//   Normalisation: ASCII case ignored and '_' equal to '-', so "Fg_C",
//   "fg-c" and "FG_C" are one name.
//   Wire spelling: a parse given a prefix (e.g. "INERTIA_METHOD_") also
//   accepts prefix + a row's `wire` name (its `name` when `wire` is empty),
//   so the proto enum's names parse too.
//   Aliases: rows with `listed = false` parse but are neither printed by
//   EnumName nor listed in errors (e.g. "colours" beside "colors").
//   Error: InvalidArgument "<field>: unknown '<text>' (expected a, b or c)"
//   listing the listed names in table order.
//
// Usage:
//   constexpr io::EnumNameRow<Color> kColorNames[] = {{Color::kRed, "red"}, {Color::kBlue,
//   "blue"}}; io::EnumName(kColorNames, Color::kRed)                       -> "red"
//   io::ParseEnumName(kColorNames, "BLUE", "color")              -> Color::kBlue
//   io::ParseEnumName(kColorNames, "COLOR_RED", "color", "color_") -> Color::kRed
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace tactforce::io {

template <typename Enum>
struct EnumNameRow {
  Enum value;
  const char* name;
  const char* wire = "";  // after the wire prefix; empty: `name`
  bool listed = true;     // false: an alias (parsed, never printed)
};

// The name under the normalisation rule: ASCII lower case, '_' -> '-'.
std::string NormalizeEnumName(std::string_view text);

// "<field>: unknown '<text>' (expected a, b or c)".
absl::Status UnknownEnumName(std::string_view field, std::string_view text,
                             const std::vector<std::string>& names);

// The name of the first row holding `value` ("?" when none does).
template <typename Enum>
const char* EnumName(std::span<const EnumNameRow<Enum>> rows, Enum value) {
  for (const EnumNameRow<Enum>& r : rows)
    if (r.value == value) return r.name;
  return "?";
}
template <typename Enum, size_t N>
const char* EnumName(const EnumNameRow<Enum> (&rows)[N], Enum value) {
  return EnumName(std::span<const EnumNameRow<Enum>>(rows), value);
}

template <typename Enum>
absl::StatusOr<Enum> ParseEnumName(std::span<const EnumNameRow<Enum>> rows, std::string_view text,
                                   std::string_view field, std::string_view wire_prefix = "") {
  const std::string key = NormalizeEnumName(text);
  const std::string prefix = NormalizeEnumName(wire_prefix);
  const bool wire = !prefix.empty() && key.rfind(prefix, 0) == 0;
  for (const EnumNameRow<Enum>& r : rows) {
    if (key == NormalizeEnumName(r.name)) return r.value;
    if (wire && key.substr(prefix.size()) == NormalizeEnumName(*r.wire ? r.wire : r.name))
      return r.value;
  }
  std::vector<std::string> names;
  for (const EnumNameRow<Enum>& r : rows)
    if (r.listed) names.emplace_back(r.name);
  return UnknownEnumName(field, text, names);
}
template <typename Enum, size_t N>
absl::StatusOr<Enum> ParseEnumName(const EnumNameRow<Enum> (&rows)[N], std::string_view text,
                                   std::string_view field, std::string_view wire_prefix = "") {
  return ParseEnumName(std::span<const EnumNameRow<Enum>>(rows), text, field, wire_prefix);
}

}  // namespace tactforce::io
