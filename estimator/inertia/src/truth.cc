// Truth / prior JSON (truth.h) read with the io JSON reader (unknown keys
// ignored, missing ones named) and written back.
#include "tactforce/inertia/truth.h"

#include <cmath>
#include <vector>

#include "absl/strings/str_cat.h"
#include "tactforce/io/json.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::inertia {

absl::StatusOr<InertiaTruth> ParseTruthJson(const std::string& text, const std::string& source) {
  TF_ASSIGN_OR_RETURN(io::JsonValue root, io::ParseJson(text, source));
  if (!root.is_object())
    return absl::InvalidArgumentError(absl::StrCat(source, ": expected a JSON object"));
  auto key_error = [&](const std::string& key, const std::string& what) {
    return absl::InvalidArgumentError(absl::StrCat(source, ": key '", key, "': ", what));
  };
  auto array = [&](const std::string& key, size_t n, bool required,
                   std::vector<double>* out) -> absl::Status {
    const io::JsonValue* v = root.Find(key);
    if (v == nullptr) {
      return required
                 ? absl::InvalidArgumentError(absl::StrCat(source, ": missing key '", key, "'"))
                 : absl::OkStatus();
    }
    if (!v->is_array() || v->array().size() != n)
      return key_error(key, absl::StrCat("expected an array of ", n, " numbers"));
    for (const io::JsonValue& x : v->array()) {
      if (!x.is_number())
        return key_error(key, absl::StrCat("expected an array of ", n, " numbers"));
      if (!std::isfinite(x.number())) return key_error(key, "not finite");
      out->push_back(x.number());
    }
    return absl::OkStatus();
  };
  InertiaTruth truth;
  const io::JsonValue* m = root.Find("mass");
  if (m == nullptr) return absl::InvalidArgumentError(absl::StrCat(source, ": missing key 'mass'"));
  if (!m->is_number() || !std::isfinite(m->number())) return key_error("mass", "expected a number");
  if (!(m->number() > 0)) return key_error("mass", "must be > 0");
  truth.params.mass = m->number();
  std::vector<double> com, inertia, g;
  TF_RETURN_IF_ERROR(array("com", 3, true, &com));
  TF_RETURN_IF_ERROR(array("inertia_com", 6, true, &inertia));
  TF_RETURN_IF_ERROR(array("gravity_world", 3, false, &g));
  truth.params.com = Vec3(com[0], com[1], com[2]);
  truth.params.inertia_com = InertiaTensor::FromArray(
      {inertia[0], inertia[1], inertia[2], inertia[3], inertia[4], inertia[5]});
  if (!g.empty()) truth.gravity_world = Vec3(g[0], g[1], g[2]);
  return truth;
}

absl::StatusOr<InertiaTruth> ReadTruthJsonFile(const std::string& path) {
  TF_ASSIGN_OR_RETURN(std::string text, io::ReadTextFile(path));
  return ParseTruthJson(text, io::SourceName(path));
}

std::string TruthToJson(const InertiaTruth& t) {
  const InertialParameters& p = t.params;
  const auto inertia = p.inertia_com.ToArray();
  io::JsonWriter w;
  w.BeginObject();
  w.Field("mass", p.mass);
  w.NumberArray("com", {p.com.x(), p.com.y(), p.com.z()});
  w.NumberArray("inertia_com", std::vector<double>(inertia.begin(), inertia.end()));
  if (t.gravity_world) {
    const Vec3& g = *t.gravity_world;
    w.NumberArray("gravity_world", {g.x(), g.y(), g.z()});
  }
  w.EndObject();
  return w.str() + "\n";
}

absl::Status WriteTruthJsonFile(const InertiaTruth& truth, const std::string& path) {
  return io::WriteTextFile(path, TruthToJson(truth));
}

}  // namespace tactforce::inertia
