// Plans from earlier estimates: a FitInertiaResponse and a
// FrictionResponse fill a PlanRequest's object and friction together with
// their uncertainty, so the plan holds for every value the estimates allow.
#pragma once

#include "absl/status/status.h"
#include "tactforce/v1/estimator.pb.h"
#include "tactforce/v1/inertia.pb.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {

// object.mass, .com, .inertia from the fit and object.uncertainty.covariance
// = fit.covariance unchanged (same order and frame); the short form and any
// earlier covariance are cleared, the uncertainty's confidence kept.
// InvalidArgument naming `field` (e.g. "--inertia: ...") when the fit has
// no positive mass or its covariance is not 0 or 100 entries.
absl::Status ApplyInertiaFit(const v1::FitInertiaResponse& fit, const char* field,
                             v1::PlanRequest* request);

// Every INTRINSIC (fingertip) contact's friction = the estimate's median and
// friction_sigma = its mu_sigma; environment contacts keep theirs.
// InvalidArgument naming `field` when no trial gave an estimate (count 0).
absl::Status ApplyFrictionEstimate(const v1::FrictionResponse& friction, const char* field,
                                   v1::PlanRequest* request);

}  // namespace tactforce::api
