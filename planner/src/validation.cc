// ValidateProblem() (validation.h): field-by-field checks with API field paths.
#include "tactforce/planner/validation.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <string>

#include "absl/strings/str_cat.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/planner/parameter_uncertainty.h"

namespace tactforce::planner {
namespace {

bool Finite(const Vec3& v) { return v.allFinite(); }

absl::Status Invalid(const std::string& field, const std::string& what) {
  return absl::InvalidArgumentError(absl::StrCat(field, ": ", what));
}

// Field paths are formatted only on failure: a valid request allocates
// nothing here.
absl::Status InvalidContact(int index, const char* field, const std::string& what) {
  return Invalid(absl::StrCat("contacts[", index, "].", field), what);
}

absl::Status CheckContact(int index, Contact& c) {
  if (!IsBounded(c.position, kMaxLength)) {
    return MagnitudeError(absl::StrCat("contacts[", index, "].position"), c.position, kMaxLength,
                          "m");
  }
  if (!Finite(c.normal)) return InvalidContact(index, "normal", "not a finite vector");
  if (!NormalizeDirection(&c.normal)) return InvalidContact(index, "normal", "zero length");
  struct NonNegative {
    const char* field;
    double value;
    const char* rule;
    double limit;
    const char* unit;
  };
  const NonNegative numbers[] = {
      {"friction", c.friction, "must be >= 0", kMaxFriction, ""},
      {"friction_sigma", c.friction_sigma, "must be >= 0", kMaxFriction, ""},
      {"sigma", c.sigma, "must be >= 0", kMaxForce, " N"},
      {"min_normal_force", c.min_normal_force, "must be >= 0", kMaxForce, " N"},
      {"max_normal_force", c.max_normal_force, "must be >= 0 (0 = none)", kMaxForce, " N"}};
  for (const NonNegative& n : numbers) {
    if (!std::isfinite(n.value)) return InvalidContact(index, n.field, "not a finite number");
    if (n.value < 0.0) return InvalidContact(index, n.field, n.rule);
    if (n.value > n.limit)
      return InvalidContact(index, n.field, absl::StrCat("exceeds ", n.limit, n.unit));
  }
  if (c.max_normal_force > 0.0 && c.min_normal_force > c.max_normal_force)
    return InvalidContact(index, "min_normal_force",
                          absl::StrCat("exceeds max_normal_force (", c.min_normal_force, " > ",
                                       c.max_normal_force, ")"));
  return absl::OkStatus();
}

// Every check of CheckContact but the normal's length, branch-light and
// without messages: `lo <= v <= limit` is false for NaN, so it is also the
// finiteness test; a normal is finite when n - n is zero.
bool ContactWithinLimits(const Contact& c) {
  const auto in = [](double v, double limit) { return v >= 0.0 && v <= limit; };
  const Vec3 zero = c.normal - c.normal;
  const bool normal_finite = zero(0) == 0.0 && zero(1) == 0.0 && zero(2) == 0.0;
  return (c.position.cwiseAbs().array() <= kMaxLength).all() & normal_finite &
         in(c.friction, kMaxFriction) & in(c.friction_sigma, kMaxFriction) &
         in(c.sigma, kMaxForce) & in(c.min_normal_force, kMaxForce) &
         in(c.max_normal_force, kMaxForce) &
         !(c.max_normal_force > 0.0 && c.min_normal_force > c.max_normal_force);
}

// Every check of ValidateProblem on the object, wrench, motion and contacts
// (the uncertainty's by its own function), with no messages: the common valid
// request passes here in one pass; any failure is then named by the checks
// in order.
bool WithinLimits(const PlanProblem& p, const PlanOptions& options) {
  const auto bounded = [](const Vec3& v, double limit) {
    return (v.cwiseAbs().array() <= limit).all();
  };
  const ObjectModel& o = p.object;
  const Motion& m = p.motion;
  bool ok = o.mass >= 0.0 && o.mass <= kMaxMass;
  ok &= bounded(o.com, kMaxLength) & bounded(o.gravity, kMaxAcceleration) &
        bounded(p.external_wrench.force, kMaxForce) & bounded(p.external_wrench.torque, kMaxForce) &
        bounded(m.linear_acceleration, kMaxAcceleration) &
        bounded(m.angular_velocity, kMaxAngularVelocity) &
        bounded(m.angular_acceleration, kMaxAngularAcceleration);
  ok &= !p.contacts.empty() && static_cast<int>(p.contacts.size()) <= options.max_contacts;
  for (const Contact& c : p.contacts) ok &= ContactWithinLimits(c);
  return ok && ValidateParameterUncertainty(o.uncertainty).ok();
}

}  // namespace

bool IsBounded(double value, double limit) { return std::abs(value) <= limit; }  // false for NaN
bool IsBounded(const Vec3& value, double limit) {
  return value.allFinite() && value.cwiseAbs().maxCoeff() <= limit;
}

absl::Status MagnitudeError(absl::string_view field, double value, double limit,
                            absl::string_view unit) {
  if (!std::isfinite(value)) return Invalid(std::string(field), "not a finite number");
  return Invalid(std::string(field), absl::StrCat("magnitude exceeds ", limit, " ", unit));
}
absl::Status MagnitudeError(absl::string_view field, const Vec3& value, double limit,
                            absl::string_view unit) {
  if (!Finite(value)) return Invalid(std::string(field), "not a finite vector");
  return Invalid(std::string(field),
                 absl::StrCat("component magnitude exceeds ", limit, " ", unit));
}
absl::Status CheckMagnitude(absl::string_view field, double value, double limit,
                            absl::string_view unit) {
  return IsBounded(value, limit) ? absl::OkStatus() : MagnitudeError(field, value, limit, unit);
}
absl::Status CheckMagnitude(absl::string_view field, const Vec3& value, double limit,
                            absl::string_view unit) {
  return IsBounded(value, limit) ? absl::OkStatus() : MagnitudeError(field, value, limit, unit);
}

absl::Status CheckTime(absl::string_view field, double t, const double* previous) {
  if (!IsBounded(t, kMaxTime)) return MagnitudeError(field, t, kMaxTime, "s");
  if (previous != nullptr && t > *previous && t - *previous < kMinTimeStep) {
    return Invalid(
        std::string(field),
        absl::StrCat("step ", t - *previous,
                     " s after the previous sample is below the resolution ", kMinTimeStep, " s"));
  }
  return absl::OkStatus();
}

bool NormalizeDirection(Vec3* direction) {
  if (!Finite(*direction)) return false;
  const double largest = direction->cwiseAbs().maxCoeff();
  const Vec3 scaled = *direction / (largest > 0 ? largest : 1.0);
  const double norm = scaled.norm();  // >= 1 when largest > 0
  if (!(largest * norm >= kMinDirectionLength)) return false;
  *direction = scaled / norm;  // as Vec3::normalize() of the scaled vector
  return true;
}

absl::Status ValidateProblem(const PlanProblem& problem, const PlanOptions& options,
                             PlanProblem* validated) {
  std::string option_error;
  if (!options.IsValid(&option_error)) return absl::InvalidArgumentError(option_error);

  PlanProblem& out = *validated;
  out.object = problem.object;
  out.external_wrench = problem.external_wrench;
  out.contacts = problem.contacts;  // element-wise: keeps capacity
  out.motion = problem.motion;
  if (WithinLimits(out, options)) {
    bool normals = true;
    for (Contact& c : out.contacts) normals &= NormalizeDirection(&c.normal);
    if (normals) return absl::OkStatus();
    out.contacts = problem.contacts;  // a zero normal: named below
  }
  TF_RETURN_IF_ERROR(CheckMagnitude("object.mass", out.object.mass, kMaxMass, "kg"));
  if (out.object.mass < 0.0) return Invalid("object.mass", "must be >= 0");
  TF_RETURN_IF_ERROR(CheckMagnitude("object.com", out.object.com, kMaxLength, "m"));
  TF_RETURN_IF_ERROR(
      CheckMagnitude("object.gravity", out.object.gravity, kMaxAcceleration, "m/s^2"));
  TF_RETURN_IF_ERROR(
      CheckMagnitude("external_wrench.force", out.external_wrench.force, kMaxForce, "N"));
  TF_RETURN_IF_ERROR(
      CheckMagnitude("external_wrench.torque", out.external_wrench.torque, kMaxForce, "N m"));

  TF_RETURN_IF_ERROR(ValidateParameterUncertainty(out.object.uncertainty));
  const Motion& motion = out.motion;
  TF_RETURN_IF_ERROR(CheckMagnitude("motion.linear_acceleration", motion.linear_acceleration,
                                    kMaxAcceleration, "m/s^2"));
  TF_RETURN_IF_ERROR(CheckMagnitude("motion.angular_velocity", motion.angular_velocity,
                                    kMaxAngularVelocity, "rad/s"));
  TF_RETURN_IF_ERROR(CheckMagnitude("motion.angular_acceleration", motion.angular_acceleration,
                                    kMaxAngularAcceleration, "rad/s^2"));

  if (out.contacts.empty()) return Invalid("contacts", "at least one contact is required");
  if (static_cast<int>(out.contacts.size()) > options.max_contacts)
    return Invalid("contacts", absl::StrCat(out.contacts.size(), " contacts exceed the limit of ",
                                            options.max_contacts));
  for (int i = 0; i < static_cast<int>(out.contacts.size()); ++i) {
    TF_RETURN_IF_ERROR(CheckContact(i, out.contacts[i]));
  }
  return absl::OkStatus();
}

absl::Status ValidateInertia(const Inertia& in) {
  for (double v : {in.ixx, in.iyy, in.izz, in.ixy, in.ixz, in.iyz}) {
    if (!std::isfinite(v)) return absl::InvalidArgumentError("object.inertia: not finite");
    if (std::abs(v) > kMaxInertia) {
      return Invalid("object.inertia",
                     absl::StrCat("component magnitude exceeds ", kMaxInertia, " kg m^2"));
    }
  }
  Eigen::Matrix3d m;
  m << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  const Eigen::Vector3d moments =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m, Eigen::EigenvaluesOnly).eigenvalues();
  const double tolerance = 1e-12 * std::max(1.0, moments.cwiseAbs().maxCoeff());
  if (moments(0) < -tolerance) {
    return absl::InvalidArgumentError(
        absl::StrCat("object.inertia: not positive semidefinite (smallest principal moment ",
                     moments(0), " kg m^2)"));
  }
  if (moments(2) > moments(0) + moments(1) + tolerance) {
    return absl::InvalidArgumentError(absl::StrCat("object.inertia: principal moments ", moments(0),
                                                   ", ", moments(1), ", ", moments(2),
                                                   " kg m^2 break the triangle inequality"));
  }
  return absl::OkStatus();
}

absl::Status ValidateTrajectoryStep(const TrajectoryStep& s, int index, bool has_inertia) {
  struct Bounded {
    const char* name;
    const Vec3* value;
    double limit;
    const char* unit;
  };
  const Bounded fields[] = {
      {"gravity", &s.gravity, kMaxAcceleration, "m/s^2"},
      {"linear_acceleration", &s.linear_acceleration, kMaxAcceleration, "m/s^2"},
      {"angular_velocity", &s.angular_velocity, kMaxAngularVelocity, "rad/s"},
      {"angular_acceleration", &s.angular_acceleration, kMaxAngularAcceleration, "rad/s^2"},
      {"external_wrench.force", &s.external_wrench.force, kMaxForce, "N"},
      {"external_wrench.torque", &s.external_wrench.torque, kMaxForce, "N m"}};
  for (const Bounded& f : fields) {
    if (!IsBounded(*f.value, f.limit)) {
      return MagnitudeError(absl::StrCat("steps[", index, "].", f.name), *f.value, f.limit, f.unit);
    }
  }
  if (!has_inertia &&
      (s.angular_velocity.squaredNorm() > 0 || s.angular_acceleration.squaredNorm() > 0)) {
    return Invalid("object.inertia",
                   absl::StrCat("required because steps[", index, "] rotates the object"));
  }
  return absl::OkStatus();
}

absl::Status ValidateFrictionProbe(const FrictionProbe& probe, Vec3* unit_normal,
                                   Vec3* unit_tangent) {
  TF_RETURN_IF_ERROR(CheckMagnitude("probe.position", probe.position, kMaxLength, "m"));
  Vec3 n = probe.normal;
  if (!NormalizeDirection(&n)) {
    return Invalid("probe.normal", Finite(n) ? "zero length" : "not a finite vector");
  }
  Vec3 t = probe.tangent;
  if (!Finite(t)) return Invalid("probe.tangent", "not a finite vector");
  // Unit length first, so the projection cannot overflow.
  const bool unit = NormalizeDirection(&t);
  if (unit) t -= t.dot(n) * n;
  if (!unit || !NormalizeDirection(&t)) {
    return Invalid("probe.tangent", "zero length after projection onto the tangent plane");
  }
  for (const auto& [name, v] : {std::pair{"probe.tangential_force", probe.tangential_force},
                                std::pair{"probe.initial_normal_force", probe.initial_normal_force},
                                std::pair{"probe.final_normal_force", probe.final_normal_force}}) {
    if (!std::isfinite(v) || v < 0) return Invalid(name, "must be finite and >= 0");
    TF_RETURN_IF_ERROR(CheckMagnitude(name, v, kMaxForce, "N"));
  }
  if (!(probe.initial_normal_force > probe.final_normal_force))
    return Invalid("probe.final_normal_force", "must be below initial_normal_force");
  if (!std::isfinite(probe.ramp_rate) || probe.ramp_rate <= 0)
    return Invalid("probe.ramp_rate", "must be > 0");
  TF_RETURN_IF_ERROR(CheckMagnitude("probe.ramp_rate", probe.ramp_rate, kMaxForce, "N/s"));
  if (!std::isfinite(probe.sample_rate) || probe.sample_rate <= 0) {
    return Invalid("probe.sample_rate", "must be > 0");
  }
  constexpr double kMaxSampleRate = 1e9;  // Hz: a sample per kMinTimeStep
  TF_RETURN_IF_ERROR(CheckMagnitude("probe.sample_rate", probe.sample_rate, kMaxSampleRate, "Hz"));
  *unit_normal = n;
  *unit_tangent = t;
  return absl::OkStatus();
}

absl::StatusOr<PlanProblem> ValidateProblem(const PlanProblem& problem,
                                            const PlanOptions& options) {
  PlanProblem out;
  TF_RETURN_IF_ERROR(ValidateProblem(problem, options, &out));
  return out;
}

absl::Status ValidatePlan(const PlanProblem& problem, const PlanOptions& options,
                          ValidatedPlan* plan) {
  plan->validated_ = false;
  TF_RETURN_IF_ERROR(ValidateProblem(problem, options, &plan->problem_));
  plan->options_ = options;
  plan->validated_ = true;
  return absl::OkStatus();
}

absl::StatusOr<ValidatedPlan> ValidatePlan(const PlanProblem& problem, const PlanOptions& options) {
  ValidatedPlan plan;
  TF_RETURN_IF_ERROR(ValidatePlan(problem, options, &plan));
  return plan;
}

}  // namespace tactforce::planner
