// Plans that hold for every value of uncertain inertial parameters and
// friction, in the spirit of GeoDEx's own tightening.
//
// The wrench the contacts supply is linear in the 10 inertial parameters
// pi = (m, m c, I_o) (types.h): b = Y(g, a, w, dw) pi. A covariance S_pi
// gives the wrench ellipsoid S_b = Y S_pi Y^T; keeping the internal forces,
// a wrench change db moves the forces by G^+ db. Each row a^T f <= d is then
//   a^T f + kappa sqrt(a^T S_f a) + kappa_b sqrt(a^T G^+ S_b G^+T a) <= d,
// the exact support function of the Minkowski sum of the measurement and
// the parameter ellipsoids. An EXACT cone i is shifted by
// kappa_b (mu rho_n,b + rho_t,b) with rho from the 3x3 block P_i of
// G^+ S_b G^+T (the same bound GeoDEx uses for the measurement part).
// A friction coefficient mu +- sigma_mu plans with the cone at
// max(0, mu - kappa sigma_mu): the rows' worst case, exact because the
// normal force is non-negative. SI units, object frame.
#pragma once

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "tactforce/planner/force_model.h"

namespace tactforce::planner {

using Vector10d = Eigen::Matrix<double, 10, 1>;
using WrenchRegressorMatrix = Eigen::Matrix<double, 6, 10>;

// Y with b = Y pi: the wrench (force; torque about the origin) the contacts
// must supply for an object moving with `motion` under `gravity`
//   sum f = m (a - g) + dw x h + w x (w x h),            h = m c
//   sum p x f = I_o dw + w x (I_o w) + h x (a - g).
// Static (zero motion): b = -(m g, c x m g).
WrenchRegressorMatrix WrenchRegressor(const Vec3& gravity, const Motion& motion);

// pi of a mass, CoM and inertia about the CoM (parallel axis to the origin).
Vector10d StandardParameters(double mass, const Vec3& com, const Eigen::Matrix3d& inertia_com);

// The short form for static plans: independent mass (std. dev., kg) and CoM
// (3x3 covariance, m^2) errors mapped to the covariance of pi to first order
// (h = m c: dh = c dm + m dc). Inertia rows and columns are zero.
Matrix10d CovarianceFromMassAndCom(double mass, const Vec3& com, double mass_sigma,
                                   const Eigen::Matrix3d& com_covariance);

// A covariance matrix given row-major as `field`: finite, entries within
// `limit`, symmetric (relative 1e-9) and positive semidefinite (relative
// 1e-9). InvalidArgument naming the entry: "object.uncertainty.covariance[12]:
// not symmetric (...)", "...[37]: not a finite number"; not PSD names the
// diagonal entry of the index the offending eigenvector weighs most (and
// that index's name when `names` has one per row).
absl::Status CheckCovariance(absl::string_view field, const Eigen::MatrixXd& covariance,
                             double limit, const char* const* names = nullptr);

// object.uncertainty (covariance, confidence) as above.
absl::Status ValidateParameterUncertainty(const ParameterUncertainty& uncertainty);

// True when the problem asks for robustness beyond the measurement noise
// (a non-zero covariance of pi or a friction_sigma > 0).
bool HasModelUncertainty(const PlanProblem& problem);

// Replaces each contact's friction by max(0, mu - confidence sigma_mu) and
// zeroes friction_sigma (so a prepared problem solved again is unchanged);
// `nominal_friction` receives the request's mu per contact (cleared when no
// contact has a friction_sigma).
void ApplyFrictionUncertainty(double confidence, PlanProblem* problem,
                              std::vector<double>* nominal_friction);

// Computes `out` (force_model.h) from the prepared problem and tightens its
// rows (rhs -= row_margin) and, for EXACT, cone_shift (+= cone_margin).
// Does nothing (out->active = false) for a zero covariance or kappa_b = 0.
void TightenForParameters(const PlanOptions& options, PreparedProblem* prepared);

// PlanResult::row_margins of a prepared problem: every row, then every
// EXACT cone, with the slack at `forces` (0 when `forces` is empty) and the
// measurement and parameter parts of its tightening.
void FillRowMargins(const PreparedProblem& prepared, const std::vector<Vec3>& forces,
                    std::vector<RowMargin>* out);

}  // namespace tactforce::planner
