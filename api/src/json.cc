// JSON of API messages (json.h). Before protobuf's parser sees the text, the
// io/ reader checks its syntax and the fields are walked against the message
// descriptors, so both kinds of error name file:line:column (and suggest the
// nearest valid names); what protobuf still rejects (a value of the wrong
// type) is reduced to one line that names the field.
#include "tactforce/api/json.h"

#include "tactforce/io/json.h"
#include "tactforce/io/suggest.h"

#include <cmath>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/match.h"
#include "google/protobuf/descriptor.h"
#include "google/protobuf/util/json_util.h"
#include "tactforce/io/status_macros.h"

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

using google::protobuf::Descriptor;
using google::protobuf::EnumDescriptor;
using google::protobuf::FieldDescriptor;

// Checks field names, containers and enum names of a parsed JSON document
// against a message's descriptor; errors are "source:line:column: path:
// what" with the nearest valid names.
class FieldChecker {
 public:
  explicit FieldChecker(std::string source) : source_(std::move(source)) {}

  absl::Status Message(const io::JsonValue& value, const Descriptor* type,
                       const std::string& path) {
    if (!value.is_object())
      return Error(value.line(), value.column(), path, "expected a JSON object");
    for (size_t i = 0; i < value.members().size(); ++i) {
      const auto& [key, member] = value.members()[i];
      const FieldDescriptor* field = FindField(type, key);
      if (field == nullptr) {
        const io::JsonValue::Position at = value.KeyPosition(i);
        return Error(at.line, at.column, path,
                     absl::StrCat("unknown field '", key, "' in ", type->name(),
                                  io::DidYouMean(key, FieldNames(type))));
      }
      if (member.is_null()) continue;
      const std::string where =
          path.empty() ? field->name() : absl::StrCat(path, ".", field->name());
      TF_RETURN_IF_ERROR(Field(member, field, where));
    }
    return absl::OkStatus();
  }

 private:
  absl::Status Field(const io::JsonValue& value, const FieldDescriptor* field,
                     const std::string& path) {
    if (field->is_map()) {
      if (!value.is_object())
        return Error(value.line(), value.column(), path, "expected a JSON object (a map)");
      const FieldDescriptor* mapped = field->message_type()->map_value();
      for (const auto& [key, entry] : value.members()) {
        if (entry.is_null()) continue;
        TF_RETURN_IF_ERROR(Element(entry, mapped, absl::StrCat(path, "[\"", key, "\"]")));
      }
      return absl::OkStatus();
    }
    if (!field->is_repeated()) return Element(value, field, path);
    if (!value.is_array())
      return Error(value.line(), value.column(), path, "expected a JSON array");
    for (size_t k = 0; k < value.array().size(); ++k) {
      TF_RETURN_IF_ERROR(Element(value.array()[k], field, absl::StrCat(path, "[", k, "]")));
    }
    return absl::OkStatus();
  }

  // One value of `field` (an element when it is repeated).
  absl::Status Element(const io::JsonValue& value, const FieldDescriptor* field,
                       const std::string& path) {
    if (field->type() == FieldDescriptor::TYPE_MESSAGE &&
        !absl::StartsWith(field->message_type()->full_name(), "google.protobuf.")) {
      return Message(value, field->message_type(), path);
    }
    if (field->type() != FieldDescriptor::TYPE_ENUM) return Scalar(value, field, path);
    if (value.is_number()) return absl::OkStatus();  // numeric enum values
    if (!value.is_string())
      return Error(value.line(), value.column(), path, "expected an enum name (a string)");
    const EnumDescriptor* type = field->enum_type();
    if (type->FindValueByName(value.string()) != nullptr) return absl::OkStatus();
    std::vector<std::string> names;
    for (int k = 0; k < type->value_count(); ++k) names.push_back(type->value(k)->name());
    return Error(value.line(), value.column(), path,
                 absl::StrCat("unknown ", type->name(), " value '", value.string(), "'",
                              io::DidYouMean(value.string(), names)));
  }

  // The JSON kind of a scalar, so a wrong type keeps its line and column
  // (protobuf's own message has neither). Quoted numbers and "NaN" /
  // "Infinity" are proto3 JSON; their values are left to protobuf.
  absl::Status Scalar(const io::JsonValue& value, const FieldDescriptor* field,
                      const std::string& path) const {
    const std::string type = field->type_name();
    switch (field->cpp_type()) {
      case FieldDescriptor::CPPTYPE_DOUBLE:
      case FieldDescriptor::CPPTYPE_FLOAT:
        if (value.is_number() || (value.is_string() && QuotedNumber(value.string(), false)))
          return absl::OkStatus();
        return Error(value.line(), value.column(), path,
                     absl::StrCat("expected a number (", type, "), got ", Kind(value)));
      case FieldDescriptor::CPPTYPE_INT32:
      case FieldDescriptor::CPPTYPE_INT64:
      case FieldDescriptor::CPPTYPE_UINT32:
      case FieldDescriptor::CPPTYPE_UINT64:
        if (value.is_string() && QuotedNumber(value.string(), true)) return absl::OkStatus();
        if (value.is_number() && value.number() == std::floor(value.number()))
          return absl::OkStatus();
        return Error(value.line(), value.column(), path,
                     absl::StrCat("expected an integer (", type, "), got ", Kind(value)));
      case FieldDescriptor::CPPTYPE_BOOL:
        if (value.is_bool()) return absl::OkStatus();
        return Error(value.line(), value.column(), path,
                     absl::StrCat("expected true or false, got ", Kind(value)));
      case FieldDescriptor::CPPTYPE_STRING:
        if (value.is_string()) return absl::OkStatus();
        return Error(value.line(), value.column(), path,
                     absl::StrCat("expected a string, got ", Kind(value)));
      default:
        return absl::OkStatus();
    }
  }

  // A proto3 JSON number in quotes: "0.5", "-3", "NaN", "Infinity".
  static bool QuotedNumber(const std::string& text, bool integer) {
    if (!integer && (text == "NaN" || text == "Infinity" || text == "-Infinity")) return true;
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    return !text.empty() && end == text.c_str() + text.size() && (!integer || v == std::floor(v));
  }
  static std::string Kind(const io::JsonValue& value) {
    if (value.is_string()) return absl::StrCat("the string \"", value.string().substr(0, 40), "\"");
    if (value.is_number()) return absl::StrCat("the number ", value.number());
    if (value.is_bool()) return value.boolean() ? "true" : "false";
    if (value.is_object()) return "an object";
    if (value.is_array()) return "an array";
    return "null";
  }

  static const FieldDescriptor* FindField(const Descriptor* type, const std::string& key) {
    for (int k = 0; k < type->field_count(); ++k) {
      const FieldDescriptor* field = type->field(k);
      if (field->name() == key || field->json_name() == key) return field;
    }
    return nullptr;
  }
  static std::vector<std::string> FieldNames(const Descriptor* type) {
    std::vector<std::string> names;
    for (int k = 0; k < type->field_count(); ++k) names.push_back(type->field(k)->name());
    return names;
  }
  absl::Status Error(int line, int column, const std::string& path, const std::string& what) const {
    return absl::InvalidArgumentError(absl::StrCat(
        source_, ":", line, ":", column, ": ", path.empty() ? "" : absl::StrCat(path, ": "), what));
  }

  std::string source_;
};

}  // namespace

absl::Status ParseJson(std::string_view json, google::protobuf::Message* message,
                       std::string_view source) {
  const std::string what = source.empty() ? absl::StrCat(message->GetDescriptor()->name(), " JSON")
                                          : std::string(source);
  message->Clear();
  // absl::string_view is not std::string_view in Debian 12's Abseil.
  if (absl::StripAsciiWhitespace(absl::string_view(json.data(), json.size())).empty()) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": empty input"));
  }
  TF_ASSIGN_OR_RETURN(io::JsonValue tree, io::ParseJson(json, what));
  TF_RETURN_IF_ERROR(FieldChecker(what).Message(tree, message->GetDescriptor(), ""));
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;  // a misspelt field is an error
  options.case_insensitive_enum_parsing = false;
  const auto status = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(json.data(), json.size()), message, options);
  if (!status.ok()) {
    const auto text = status.message();
    return io::PrependPath(
        absl::InvalidArgumentError(OneLine(std::string(text.data(), text.size()))), what);
  }
  return absl::OkStatus();
}

absl::StatusOr<v1::PlanRequest> ParsePlanRequestJson(std::string_view json,
                                                     std::string_view source) {
  v1::PlanRequest request;
  TF_RETURN_IF_ERROR(ParseJson(json, &request, source.empty() ? "request JSON" : source));
  return request;
}

std::string ToJson(const google::protobuf::Message& message, bool compact) {
  google::protobuf::util::JsonPrintOptions options;
  // Protobuf indents by one space: the text is laid out by io::IndentJson,
  // the two-space layout of every command's JSON.
  options.add_whitespace = false;
  options.always_print_primitive_fields = true;
  options.always_print_enums_as_ints = false;
  options.preserve_proto_field_names = true;
  std::string out;
  const auto status = google::protobuf::util::MessageToJsonString(message, &out, options);
  if (!status.ok()) {
    // Only possible for unresolvable Any types, which the API does not use.
    return absl::StrCat("{\"error\": ", io::JsonEscape(status.ToString()), "}\n");
  }
  return compact ? out : io::IndentJson(out);
}

}  // namespace tactforce::api
