// Truth files (JSON object): "mass" (kg), "com" [x,y,z] (m, object frame),
// "inertia_com" [Ixx,Iyy,Izz,Ixy,Ixz,Iyz] (kg m^2, about the CoM), optional
// "gravity_world" [gx,gy,gz]. Other keys (e.g. "source") are ignored.
#pragma once

#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "tactforce/inertia/types.h"

namespace tactforce::inertia {

struct InertiaTruth {
  InertialParameters params;
  std::optional<Vec3> gravity_world;
};

// Errors name the source and the key ("Hammer.truth.json: key 'com': expected
// an array of 3 numbers") or the byte offset of a syntax error.
absl::StatusOr<InertiaTruth> ParseTruthJson(const std::string& text, const std::string& source);
absl::StatusOr<InertiaTruth> ReadTruthJsonFile(const std::string& path);

std::string TruthToJson(const InertiaTruth& truth);
absl::Status WriteTruthJsonFile(const InertiaTruth& truth, const std::string& path);

}  // namespace tactforce::inertia
