// JSON form of the API messages (protobuf's canonical proto3 JSON mapping).
//
// Parsing accepts both the proto field names (snake_case) and their
// lowerCamelCase JSON names; unknown fields are errors so that a typo is
// reported instead of silently ignored. Printing keeps the proto field names
// and prints every scalar field, zeros included.
#pragma once

#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "google/protobuf/message.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {

// InvalidArgument on bad input, naming `source` (a file name; defaults to
// "<MessageName> JSON", "request JSON" for PlanRequest) and, for syntax
// errors, unknown fields and enum names, the position and the nearest valid
// names:
//   "grasp.json:4:7: object: unknown field 'mas' in ObjectProperties; did you mean 'mass'?"
// Values of the wrong type: "<source>: <what protobuf reports>".
absl::Status ParseJson(std::string_view json, google::protobuf::Message* message,
                       std::string_view source = {});
absl::StatusOr<v1::PlanRequest> ParsePlanRequestJson(std::string_view json,
                                                     std::string_view source = {});

// Pretty-printed (two-space indent) unless `compact`; ends with a newline
// when pretty-printed.
std::string ToJson(const google::protobuf::Message& message, bool compact = false);

}  // namespace tactforce::api
