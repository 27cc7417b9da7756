// ValidateProblem() (validation.h): field-by-field checks with API field paths.
#include "tactforce/planner/validation.h"

#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"

namespace tactforce::planner {
namespace {

bool Finite(const Vec3& v) { return v.allFinite(); }

absl::Status Invalid(const std::string& field, const std::string& what) {
  return absl::InvalidArgumentError(absl::StrCat(field, ": ", what));
}

absl::Status CheckFinite(const std::string& field, double value) {
  return std::isfinite(value) ? absl::OkStatus() : Invalid(field, "not a finite number");
}

absl::Status CheckFinite(const std::string& field, const Vec3& value) {
  return Finite(value) ? absl::OkStatus() : Invalid(field, "not a finite vector");
}

absl::Status CheckContact(int index, Contact& c) {
  const std::string path = absl::StrCat("contacts[", index, "]");
  if (auto s = CheckFinite(path + ".position", c.position); !s.ok()) return s;
  if (auto s = CheckFinite(path + ".normal", c.normal); !s.ok()) return s;
  const double length = c.normal.norm();
  if (length < 1e-9) return Invalid(path + ".normal", "zero length");
  c.normal /= length;
  if (auto s = CheckFinite(path + ".friction", c.friction); !s.ok()) return s;
  if (c.friction < 0.0) return Invalid(path + ".friction", "must be >= 0");
  if (auto s = CheckFinite(path + ".sigma", c.sigma); !s.ok()) return s;
  if (c.sigma < 0.0) return Invalid(path + ".sigma", "must be >= 0");
  if (auto s = CheckFinite(path + ".min_normal_force", c.min_normal_force); !s.ok()) return s;
  if (c.min_normal_force < 0.0) return Invalid(path + ".min_normal_force", "must be >= 0");
  if (auto s = CheckFinite(path + ".max_normal_force", c.max_normal_force); !s.ok()) return s;
  if (c.max_normal_force < 0.0) return Invalid(path + ".max_normal_force", "must be >= 0 (0 = none)");
  if (c.max_normal_force > 0.0 && c.min_normal_force > c.max_normal_force)
    return Invalid(path + ".min_normal_force",
                   absl::StrCat("exceeds max_normal_force (", c.min_normal_force, " > ",
                                c.max_normal_force, ")"));
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<PlanProblem> ValidateProblem(const PlanProblem& problem,
                                            const PlanOptions& options) {
  std::string option_error;
  if (!options.IsValid(&option_error)) return absl::InvalidArgumentError(option_error);

  PlanProblem out = problem;
  if (auto s = CheckFinite("object.mass", out.object.mass); !s.ok()) return s;
  if (out.object.mass < 0.0) return Invalid("object.mass", "must be >= 0");
  if (auto s = CheckFinite("object.com", out.object.com); !s.ok()) return s;
  if (auto s = CheckFinite("object.gravity", out.object.gravity); !s.ok()) return s;
  if (auto s = CheckFinite("external_wrench.force", out.external_wrench.force); !s.ok()) return s;
  if (auto s = CheckFinite("external_wrench.torque", out.external_wrench.torque); !s.ok()) return s;

  if (out.contacts.empty()) return Invalid("contacts", "at least one contact is required");
  if (static_cast<int>(out.contacts.size()) > options.max_contacts)
    return Invalid("contacts", absl::StrCat(out.contacts.size(), " contacts exceed the limit of ",
                                            options.max_contacts));
  for (int i = 0; i < static_cast<int>(out.contacts.size()); ++i) {
    if (auto s = CheckContact(i, out.contacts[i]); !s.ok()) return s;
  }
  return out;
}

}  // namespace tactforce::planner
