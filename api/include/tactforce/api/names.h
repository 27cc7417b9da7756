// Short wire names of the API's enums for people and logs, taken from the
// descriptors protobuf generates (<Enum>_descriptor(), as <Enum>_Name()
// does) instead of hand-written tables: PLAN_STATUS_OPTIMAL -> "OPTIMAL".
// The libraries' own enums keep their own ToString (domain spelling).
#pragma once

#include <string>

#include "google/protobuf/descriptor.h"
#include "google/protobuf/generated_enum_reflection.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {

// The value's name without the prefix its enum's values share (the name of
// value 0 minus "UNSPECIFIED", e.g. "PLAN_STATUS_"); "UNKNOWN(<number>)"
// for a number the enum does not define.
std::string ShortEnumName(const google::protobuf::EnumDescriptor& type, int number);
template <class ProtoEnum>
std::string ShortEnumName(ProtoEnum value) {
  return ShortEnumName(*google::protobuf::GetEnumDescriptor<ProtoEnum>(), static_cast<int>(value));
}

// "OPTIMAL", "INFEASIBLE", "SOLVER_FAILURE", "UNSPECIFIED", "UNKNOWN(7)".
std::string StatusName(v1::PlanStatus status);
// "GEOMETRIC", "IPOPT", "CROSS_CHECK", "UNSPECIFIED", "UNKNOWN(7)".
std::string SolverName(v1::Solver solver);

}  // namespace tactforce::api
