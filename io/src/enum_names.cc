// The enum-name convention (enum_names.h): normalisation and the error.
#include "tactforce/io/enum_names.h"

#include "absl/strings/str_cat.h"

namespace tactforce::io {

std::string NormalizeEnumName(std::string_view text) {
  std::string s;
  s.reserve(text.size());
  for (char c : text)
    s += c == '_' ? '-' : (c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c);
  return s;
}

absl::Status UnknownEnumName(std::string_view field, std::string_view text,
                             const std::vector<std::string>& names) {
  std::string list;
  for (size_t i = 0; i < names.size(); ++i) {
    if (i > 0) list += i + 1 == names.size() ? " or " : ", ";
    list += names[i];
  }
  return absl::InvalidArgumentError(absl::StrCat(std::string(field), ": unknown '",
                                                 std::string(text), "' (expected ", list, ")"));
}

}  // namespace tactforce::io
