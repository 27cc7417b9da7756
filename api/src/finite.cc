// FindNonFinite / CheckFiniteAnswer (finite.h): a reflection walk over a
// response message that builds a path only for the number it finds.
#include "tactforce/api/finite.h"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "absl/strings/str_cat.h"

namespace tactforce::api {
namespace {

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;
using google::protobuf::Reflection;

// Infinity is a documented value of these (inertia.proto).
bool MayBeInfinite(const FieldDescriptor* field) {
  constexpr std::string_view kInfinityAllowed[] = {
      "tactforce.v1.FitInertiaResponse.pseudo_inertia_min_eigenvalue",
      "tactforce.v1.InertiaErrors.riemannian"};
  return std::find(std::begin(kInfinityAllowed), std::end(kInfinityAllowed), field->full_name()) !=
         std::end(kInfinityAllowed);
}

bool IsNumber(const FieldDescriptor* field) {
  return field->cpp_type() == FieldDescriptor::CPPTYPE_DOUBLE ||
         field->cpp_type() == FieldDescriptor::CPPTYPE_FLOAT;
}

// Element `index` of a double/float field (-1: the singular value).
double NumberAt(const Message& m, const FieldDescriptor* field, int index) {
  const Reflection* r = m.GetReflection();
  const bool is_double = field->cpp_type() == FieldDescriptor::CPPTYPE_DOUBLE;
  if (index < 0) return is_double ? r->GetDouble(m, field) : r->GetFloat(m, field);
  return is_double ? r->GetRepeatedDouble(m, field, index) : r->GetRepeatedFloat(m, field, index);
}

bool Bad(double value, const FieldDescriptor* field) {
  return std::isnan(value) || (std::isinf(value) && !MayBeInfinite(field));
}

// "[3]" for a list element, "[\"key\"]" for a map entry with a string key.
std::string Subscript(const Message* map_entry, int index) {
  if (map_entry != nullptr) {
    const FieldDescriptor* key = map_entry->GetDescriptor()->map_key();
    if (key->cpp_type() == FieldDescriptor::CPPTYPE_STRING)
      return absl::StrCat("[\"", map_entry->GetReflection()->GetString(*map_entry, key), "\"]");
  }
  return absl::StrCat("[", index, "]");
}

std::optional<std::string> Find(const Message& m, double* value);

// The value of one element of a message field (a map entry's value, or the
// element itself), searched; the path below it ("", ".x", ".values[2]").
std::optional<std::string> FindInElement(const Message& element, const FieldDescriptor* field,
                                         double* value) {
  if (!field->is_map()) return Find(element, value);
  const FieldDescriptor* v = element.GetDescriptor()->map_value();
  if (IsNumber(v)) {
    *value = NumberAt(element, v, -1);
    return Bad(*value, v) ? std::optional<std::string>("") : std::nullopt;
  }
  if (v->cpp_type() != FieldDescriptor::CPPTYPE_MESSAGE) return std::nullopt;
  return Find(element.GetReflection()->GetMessage(element, v), value);
}

std::optional<std::string> FindInField(const Message& m, const FieldDescriptor* f, double* value) {
  const Reflection* r = m.GetReflection();
  if (IsNumber(f)) {
    const int n = f->is_repeated() ? r->FieldSize(m, f) : 1;
    for (int k = 0; k < n; ++k) {
      *value = NumberAt(m, f, f->is_repeated() ? k : -1);
      if (Bad(*value, f))
        return f->is_repeated() ? absl::StrCat(f->name(), "[", k, "]") : f->name();
    }
    return std::nullopt;
  }
  if (f->cpp_type() != FieldDescriptor::CPPTYPE_MESSAGE) return std::nullopt;
  if (!f->is_repeated()) {
    if (!r->HasField(m, f)) return std::nullopt;
    std::optional<std::string> below = Find(r->GetMessage(m, f), value);
    if (below) return absl::StrCat(f->name(), ".", *below);
    return std::nullopt;
  }
  for (int k = 0, n = r->FieldSize(m, f); k < n; ++k) {
    const Message& element = r->GetRepeatedMessage(m, f, k);
    std::optional<std::string> below = FindInElement(element, f, value);
    if (!below) continue;
    const std::string head =
        absl::StrCat(f->name(), Subscript(f->is_map() ? &element : nullptr, k));
    return below->empty() ? head : absl::StrCat(head, ".", *below);
  }
  return std::nullopt;
}

std::optional<std::string> Find(const Message& m, double* value) {
  const google::protobuf::Descriptor* d = m.GetDescriptor();
  for (int i = 0; i < d->field_count(); ++i) {
    if (std::optional<std::string> path = FindInField(m, d->field(i), value)) return path;
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> FindNonFinite(const Message& message) {
  double value = 0.0;
  return Find(message, &value);
}

namespace {

absl::Status NonFiniteError(const std::string& path, double value, const Message& response) {
  return absl::InternalError(absl::StrCat(
      path, ": ", value, " in the answer of ", response.GetDescriptor()->name(),
      " (a computation overflowed on input within the limits; please report it with the request)"));
}

// The first non-finite of `values` as "<field>[i]" (with `.x` etc. from
// `component` when given).
template <typename Repeated, typename Get>
std::optional<std::pair<std::string, double>> FirstNonFinite(const Repeated& values,
                                                             const char* field, Get get) {
  for (int i = 0; i < values.size(); ++i) {
    if (std::optional<std::pair<const char*, double>> bad = get(values.Get(i))) {
      return std::make_pair(absl::StrCat(field, "[", i, "]", bad->first), bad->second);
    }
  }
  return std::nullopt;
}

std::optional<std::pair<const char*, double>> NonFiniteComponent(const v1::Vec3& v) {
  if (!std::isfinite(v.x())) return std::make_pair(".x", v.x());
  if (!std::isfinite(v.y())) return std::make_pair(".y", v.y());
  if (!std::isfinite(v.z())) return std::make_pair(".z", v.z());
  return std::nullopt;
}

std::optional<std::pair<const char*, double>> NonFiniteScalar(double v) {
  if (!std::isfinite(v)) return std::make_pair("", v);
  return std::nullopt;
}

std::optional<std::pair<const char*, double>> NonFiniteMargin(const v1::RowMargin& m) {
  if (!std::isfinite(m.slack())) return std::make_pair(".slack", m.slack());
  if (!std::isfinite(m.measurement())) return std::make_pair(".measurement", m.measurement());
  if (!std::isfinite(m.parameters())) return std::make_pair(".parameters", m.parameters());
  return std::nullopt;
}

std::optional<std::pair<std::string, double>> FindInPlan(const v1::PlanResponse& r) {
  if (auto bad = FirstNonFinite(r.forces(), "forces", NonFiniteComponent)) return bad;
  if (auto bad = FirstNonFinite(r.normal_forces(), "normal_forces", NonFiniteScalar)) return bad;
  if (auto bad = FirstNonFinite(r.normal_force_sigma(), "normal_force_sigma", NonFiniteScalar))
    return bad;
  if (!std::isfinite(r.objective())) return std::make_pair(std::string("objective"), r.objective());
  if (!std::isfinite(r.min_margin()))
    return std::make_pair(std::string("min_margin"), r.min_margin());
  if (auto bad = FirstNonFinite(r.row_margins(), "row_margins", NonFiniteMargin)) return bad;
  const v1::CrossCheck& c = r.cross_check();
  if (!std::isfinite(c.max_force_diff()))
    return std::make_pair(std::string("cross_check.max_force_diff"), c.max_force_diff());
  if (!std::isfinite(c.objective_rel_diff()))
    return std::make_pair(std::string("cross_check.objective_rel_diff"), c.objective_rel_diff());
  return std::nullopt;
}

}  // namespace

absl::Status CheckFiniteAnswer(const Message& response) {
  double value = 0.0;
  std::optional<std::string> path = Find(response, &value);
  if (!path) return absl::OkStatus();
  return NonFiniteError(*path, value, response);
}

absl::Status CheckFiniteAnswer(const v1::PlanResponse& response) {
  std::optional<std::pair<std::string, double>> bad = FindInPlan(response);
  if (!bad) return absl::OkStatus();
  return NonFiniteError(bad->first, bad->second, response);
}

}  // namespace tactforce::api
