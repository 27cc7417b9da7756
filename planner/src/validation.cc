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

absl::Status CheckFinite(const char* field, double value) {
  return std::isfinite(value) ? absl::OkStatus() : Invalid(field, "not a finite number");
}

absl::Status CheckFinite(const char* field, const Vec3& value) {
  return Finite(value) ? absl::OkStatus() : Invalid(field, "not a finite vector");
}

// Field paths are formatted only on failure: a valid request allocates
// nothing here.
absl::Status InvalidContact(int index, const char* field, const std::string& what) {
  return Invalid(absl::StrCat("contacts[", index, "].", field), what);
}

absl::Status CheckContact(int index, Contact& c) {
  if (!Finite(c.position)) return InvalidContact(index, "position", "not a finite vector");
  if (!Finite(c.normal)) return InvalidContact(index, "normal", "not a finite vector");
  const double length = c.normal.norm();
  if (length < 1e-9) return InvalidContact(index, "normal", "zero length");
  c.normal /= length;
  struct NonNegative {
    const char* field;
    double value;
    const char* rule;
  };
  const NonNegative numbers[] = {{"friction", c.friction, "must be >= 0"},
                                 {"sigma", c.sigma, "must be >= 0"},
                                 {"min_normal_force", c.min_normal_force, "must be >= 0"},
                                 {"max_normal_force", c.max_normal_force, "must be >= 0 (0 = none)"}};
  for (const NonNegative& n : numbers) {
    if (!std::isfinite(n.value)) return InvalidContact(index, n.field, "not a finite number");
    if (n.value < 0.0) return InvalidContact(index, n.field, n.rule);
  }
  if (c.max_normal_force > 0.0 && c.min_normal_force > c.max_normal_force)
    return InvalidContact(index, "min_normal_force",
                          absl::StrCat("exceeds max_normal_force (", c.min_normal_force, " > ",
                                       c.max_normal_force, ")"));
  return absl::OkStatus();
}

}  // namespace

absl::Status ValidateProblem(const PlanProblem& problem, const PlanOptions& options,
                             PlanProblem* validated) {
  std::string option_error;
  if (!options.IsValid(&option_error)) return absl::InvalidArgumentError(option_error);

  PlanProblem& out = *validated;
  out.object = problem.object;
  out.external_wrench = problem.external_wrench;
  out.contacts = problem.contacts;  // element-wise: keeps capacity
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
  return absl::OkStatus();
}

absl::StatusOr<PlanProblem> ValidateProblem(const PlanProblem& problem,
                                            const PlanOptions& options) {
  PlanProblem out;
  if (absl::Status s = ValidateProblem(problem, options, &out); !s.ok()) return s;
  return out;
}

}  // namespace tactforce::planner
