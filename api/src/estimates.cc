// ApplyInertiaFit / ApplyFrictionEstimate (estimates.h).
#include "tactforce/api/estimates.h"

#include <cmath>

#include "absl/strings/str_cat.h"

namespace tactforce::api {

absl::Status ApplyInertiaFit(const v1::FitInertiaResponse& fit, const char* field,
                             v1::PlanRequest* request) {
  if (!(fit.mass() > 0.0) || !std::isfinite(fit.mass())) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ": the fit has no positive mass (", fit.mass(), " kg)"));
  }
  if (fit.covariance_size() != 0 && fit.covariance_size() != 100) {
    return absl::InvalidArgumentError(absl::StrCat(
        field, ": covariance has ", fit.covariance_size(), " entries, need 100 (10x10 row-major)"));
  }
  v1::ObjectModel* object = request->mutable_object();
  object->set_mass(fit.mass());
  *object->mutable_com() = fit.com();
  *object->mutable_inertia() = fit.inertia();
  v1::ParameterUncertainty* u = object->mutable_uncertainty();
  u->clear_covariance();
  u->clear_mass_sigma();
  u->clear_com_covariance();
  for (double v : fit.covariance()) u->add_covariance(v);
  return absl::OkStatus();
}

absl::Status ApplyFrictionEstimate(const v1::FrictionResponse& friction, const char* field,
                                   v1::PlanRequest* request) {
  if (friction.count() <= 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ": no trial slipped (count 0): no friction estimate"));
  }
  for (v1::Contact& c : *request->mutable_contacts()) {
    if (c.kind() == v1::CONTACT_KIND_EXTRINSIC) continue;
    c.set_friction(friction.median());
    c.set_friction_sigma(friction.mu_sigma());
  }
  return absl::OkStatus();
}

}  // namespace tactforce::api
