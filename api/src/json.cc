// JSON of API messages (json.h): protobuf's JSON parser and printer, with
// its error messages reduced to one line that names the field.
#include "tactforce/api/json.h"

#include "tactforce/io/json.h"

#include <string>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/match.h"
#include "google/protobuf/util/json_util.h"

namespace tactforce::api {
namespace {

// Protobuf's messages may span lines; the CLI prints errors on one.
std::string OneLine(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  }
  std::string out(absl::StripAsciiWhitespace(text));
  // Drop the position caret protobuf puts on a line of its own, and the
  // empty path prefix of errors at the root.
  if (!out.empty() && out.back() == '^') {
    out.pop_back();
    out = std::string(absl::StripTrailingAsciiWhitespace(out));
  }
  if (absl::StartsWith(out, ": ")) out.erase(0, 2);
  return out;
}

}  // namespace

absl::Status ParseJson(std::string_view json, google::protobuf::Message* message,
                       std::string_view label) {
  const std::string what =
      label.empty() ? absl::StrCat(message->GetDescriptor()->name(), " JSON") : std::string(label);
  // absl::string_view is not std::string_view in Debian 12's Abseil.
  if (absl::StripAsciiWhitespace(absl::string_view(json.data(), json.size())).empty()) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": empty input"));
  }
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;  // a misspelt field is an error
  options.case_insensitive_enum_parsing = false;
  message->Clear();
  const auto status = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(json.data(), json.size()), message, options);
  if (!status.ok()) {
    const auto text = status.message();
    return absl::InvalidArgumentError(
        absl::StrCat(what, ": ", OneLine(std::string(text.data(), text.size()))));
  }
  return absl::OkStatus();
}

absl::StatusOr<v1::PlanRequest> ParsePlanRequestJson(std::string_view json) {
  v1::PlanRequest request;
  absl::Status status = ParseJson(json, &request, "request JSON");
  if (!status.ok()) return status;
  return request;
}

std::string ToJson(const google::protobuf::Message& message, bool compact) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = !compact;
  options.always_print_primitive_fields = true;
  options.always_print_enums_as_ints = false;
  options.preserve_proto_field_names = true;
  std::string out;
  const auto status = google::protobuf::util::MessageToJsonString(message, &out, options);
  if (!status.ok()) {
    // Only possible for unresolvable Any types, which the API does not use.
    return absl::StrCat("{\"error\": ", io::JsonEscape(status.ToString()), "}\n");
  }
  // With add_whitespace protobuf already ends the text with a newline.
  if (!compact && (out.empty() || out.back() != '\n')) out.push_back('\n');
  return out;
}


}  // namespace tactforce::api
