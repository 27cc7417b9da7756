// ValidateProblem() (validation.h): field-by-field checks with API field paths.
#include "tactforce/planner/validation.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <string>

#include "absl/strings/str_cat.h"

namespace tactforce::planner {
namespace {

bool Finite(const Vec3& v) { return v.allFinite(); }

absl::Status Invalid(const std::string& field, const std::string& what) {
  return absl::InvalidArgumentError(absl::StrCat(field, ": ", what));
}

// Finite with every component's magnitude at most `limit` (`unit` names it).
absl::Status CheckBounded(const char* field, double value, double limit, const char* unit) {
  if (!std::isfinite(value)) return Invalid(field, "not a finite number");
  if (std::abs(value) > limit) return Invalid(field, absl::StrCat("magnitude exceeds ", limit, " ", unit));
  return absl::OkStatus();
}
absl::Status CheckBounded(const char* field, const Vec3& value, double limit, const char* unit) {
  if (!Finite(value)) return Invalid(field, "not a finite vector");
  if (value.cwiseAbs().maxCoeff() > limit) {
    return Invalid(field, absl::StrCat("component magnitude exceeds ", limit, " ", unit));
  }
  return absl::OkStatus();
}

// Field paths are formatted only on failure: a valid request allocates
// nothing here.
absl::Status InvalidContact(int index, const char* field, const std::string& what) {
  return Invalid(absl::StrCat("contacts[", index, "].", field), what);
}

absl::Status CheckContact(int index, Contact& c) {
  if (!Finite(c.position)) return InvalidContact(index, "position", "not a finite vector");
  if (c.position.cwiseAbs().maxCoeff() > kMaxLength) {
    return InvalidContact(index, "position", absl::StrCat("component magnitude exceeds ", kMaxLength, " m"));
  }
  if (!Finite(c.normal)) return InvalidContact(index, "normal", "not a finite vector");
  // Scaled by its largest component first: |n| of a finite n may overflow.
  const double largest = c.normal.cwiseAbs().maxCoeff();
  if (!(largest * (c.normal / (largest > 0 ? largest : 1.0)).norm() >= 1e-9)) {
    return InvalidContact(index, "normal", "zero length");
  }
  c.normal /= largest;
  c.normal.normalize();
  struct NonNegative {
    const char* field;
    double value;
    const char* rule;
    double limit;
    const char* unit;
  };
  const NonNegative numbers[] = {{"friction", c.friction, "must be >= 0", kMaxFriction, ""},
                                 {"sigma", c.sigma, "must be >= 0", kMaxForce, " N"},
                                 {"min_normal_force", c.min_normal_force, "must be >= 0", kMaxForce, " N"},
                                 {"max_normal_force", c.max_normal_force, "must be >= 0 (0 = none)", kMaxForce, " N"}};
  for (const NonNegative& n : numbers) {
    if (!std::isfinite(n.value)) return InvalidContact(index, n.field, "not a finite number");
    if (n.value < 0.0) return InvalidContact(index, n.field, n.rule);
    if (n.value > n.limit) return InvalidContact(index, n.field, absl::StrCat("exceeds ", n.limit, n.unit));
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
  if (auto s = CheckBounded("object.mass", out.object.mass, kMaxMass, "kg"); !s.ok()) return s;
  if (out.object.mass < 0.0) return Invalid("object.mass", "must be >= 0");
  if (auto s = CheckBounded("object.com", out.object.com, kMaxLength, "m"); !s.ok()) return s;
  if (auto s = CheckBounded("object.gravity", out.object.gravity, kMaxAcceleration, "m/s^2"); !s.ok()) return s;
  if (auto s = CheckBounded("external_wrench.force", out.external_wrench.force, kMaxForce, "N"); !s.ok()) return s;
  if (auto s = CheckBounded("external_wrench.torque", out.external_wrench.torque, kMaxForce, "N m"); !s.ok()) {
    return s;
  }

  if (out.contacts.empty()) return Invalid("contacts", "at least one contact is required");
  if (static_cast<int>(out.contacts.size()) > options.max_contacts)
    return Invalid("contacts", absl::StrCat(out.contacts.size(), " contacts exceed the limit of ",
                                            options.max_contacts));
  for (int i = 0; i < static_cast<int>(out.contacts.size()); ++i) {
    if (auto s = CheckContact(i, out.contacts[i]); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status ValidateInertia(const Inertia& in) {
  for (double v : {in.ixx, in.iyy, in.izz, in.ixy, in.ixz, in.iyz}) {
    if (!std::isfinite(v)) return absl::InvalidArgumentError("object.inertia: not finite");
  }
  Eigen::Matrix3d m;
  m << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m, Eigen::EigenvaluesOnly).eigenvalues();
  const double tolerance = 1e-12 * std::max(1.0, moments.cwiseAbs().maxCoeff());
  if (moments(0) < -tolerance) {
    return absl::InvalidArgumentError(absl::StrCat("object.inertia: not positive semidefinite (smallest principal moment ",
                                                   moments(0), " kg m^2)"));
  }
  if (moments(2) > moments(0) + moments(1) + tolerance) {
    return absl::InvalidArgumentError(absl::StrCat("object.inertia: principal moments ", moments(0), ", ", moments(1),
                                                   ", ", moments(2), " kg m^2 break the triangle inequality"));
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
