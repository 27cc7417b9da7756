// The geometry shared by every backend, derived once per request
// (GeoDEx Sec. III): the equilibrium equations G f = b, the force-equilibrium
// plane (FE-plane) f = f0 + B x, the trusted measurement ellipsoid and the
// robustly tightened linear constraint rows A f <= d.
//
// f stacks the n contact forces (3n, object frame, N) in request order.
//
// Each step has two forms: a value-returning one for one-off use and an
// in-place one (`..., Out* out`) that reuses the storage of `out` (and of a
// scratch), so that a PlanningWorkspace solving problems of one size
// allocates nothing.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "tactforce/planner/types.h"

namespace tactforce::planner {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// Equilibrium of the contact forces with gravity and the external wrench.
struct ForceEquilibrium {
  MatrixXd grasp_matrix;    // G = [I ... I; [p_1]x ... [p_n]x], 6 x 3n (see range_rows)
  Vector6d wrench;          // b = -(w_g + w_ext), w_g = (m g, c x m g)
  MatrixXd null_basis;      // B: orthonormal basis of null(G), 3n x d
  VectorXd particular;      // f0 = G^+ b (minimum norm; orthogonal to B)
  int rank = 0;             // numerical rank of G
  double residual = 0.0;    // |G f0 - b| (N, N m)
  bool consistent = false;  // b in range(G) within tolerance
  // Independent equilibrium rows U_r^T G f = U_r^T b (r = rank): the same
  // affine set as G f = b when consistent, without redundant rows.
  MatrixXd independent_rows;
  VectorXd independent_rhs;
};

// Buffers ComputeForceEquilibrium reuses (contents are scratch).
struct EquilibriumScratch {
  MatrixXd reflected;     // (H x I3) T, the mixed torque columns (3n x 3)
  MatrixXd reduced;       // their last 3(n-1) rows, reduced in place to R_t
  MatrixXd reflectors;    // Householder vectors, 3(n-1) x 3
  MatrixXd orthogonal;    // Q'' (3(n-1) x 3(n-1))
  MatrixXd torque_basis;  // Q_t (3n x 3)
};

// Builds G and b and the FE-plane: about the contacts' centroid c the force
// rows of the centred G_c = [I ...; [p_i - c]x ...] are orthogonal to its
// torque rows, and G_c has the same null space and equilibrium set as G
// (G = T G_c, T invertible). The force rows' range and complement come in
// closed form from one Householder reflection of the n contacts (H x I3, H e_1
// = -1 / sqrt(n)), which maps the torque columns to [0; T'']; a Householder
// QR of T'' (3(n-1) x 3) gives the torque block R_t and the rest of the
// basis. Rank: a torque direction counts when its singular value exceeds
// rank_tolerance * max(1, sqrt(n), sigma_max(R_t)) (the singular values of
// G_c); bounds from det R_t and |R_t|_F decide a clearly full rank, else a
// 3x3 SVD of R_t. Lost rotations (collinear or coincident contacts) move
// their directions from the range to the null space. independent_rows are
// then the orthonormal range basis (rank x 3n), independent_rhs = rows f0.
// In place with `range_rows` false, G and the independent rows and rhs
// (which only the Ipopt formulation and the parameter tightening read) are
// left empty.
ForceEquilibrium ComputeForceEquilibrium(const PlanProblem& problem, double rank_tolerance);
void ComputeForceEquilibrium(const PlanProblem& problem, double rank_tolerance,
                             EquilibriumScratch* scratch, ForceEquilibrium* out,
                             bool range_rows = true);

// Trusted measurement ellipsoid (GeoDEx Def. 5, Prop. 3) in force space:
// S_f = B E diag(sigma^2) E^T B^T with E = B^T N_I, stored as the factor
// L = B E diag(sigma) (3n x n_I), so S_f = L L^T.
struct MeasurementEllipsoid {
  MatrixXd factor;
  MatrixXd
      plane_factor;  // E diag(sigma) = B^T N_I diag(sigma): L in FE-plane coordinates (d x n_I)
  // sqrt(a^T S_f a): the support function of the unit ellipsoid along a.
  double Support(const VectorXd& a) const;
  MatrixXd ForceCovariance() const { return factor * factor.transpose(); }
  // 3x3 block S_ii of contact i (N^2), formed once per ellipsoid.
  const Eigen::Matrix3d& ContactCovariance(int contact) const {
    return contact_covariance[contact];
  }
  std::vector<Eigen::Matrix3d> contact_covariance;  // S_ii, one per contact
};

MeasurementEllipsoid ComputeMeasurementEllipsoid(const PlanProblem& problem,
                                                 const ForceEquilibrium& eq);
void ComputeMeasurementEllipsoid(const PlanProblem& problem, const ForceEquilibrium& eq,
                                 MeasurementEllipsoid* out);

// Fixed tangent basis: e = coordinate axis with the smallest |e . n| (first
// on ties), t1 = normalize(e - (e . n) n), t2 = n x t1.
std::pair<Vec3, Vec3> TangentBasis(const Vec3& normal);

// "contact 2 (thumb)" (index, and the name when there is one), for messages.
std::string ContactLabel(const PlanProblem& problem, int contact);

enum class RowKind { kFrictionFacet, kMinNormal, kMaxNormal };

struct RowInfo {
  int contact = 0;
  RowKind kind = RowKind::kFrictionFacet;
  int facet = 0;  // friction facets only
};

// Linear rows a^T f <= d. `nominal_rhs` is d; `rhs` is the robust
// d - kappa sqrt(a^T S_f a). Row r touches only the three coordinates of
// contact info[r].contact, so only those are stored: the full m x 3n matrix
// A is never formed unless a caller asks for it (Dense).
struct ConstraintRows {
  Eigen::Matrix<double, Eigen::Dynamic, 3> directions;  // m x 3: row r of A on its contact
  VectorXd rhs;
  VectorXd nominal_rhs;
  std::vector<RowInfo> info;
  // A contact's rows are consecutive: those of contact i are
  // [contact_first[i], contact_first[i + 1]) (n + 1 entries, the last m).
  std::vector<int> contact_first;
  // A (m x 3n, zero outside each row's contact), for backends that take
  // whole rows (the Ipopt formulation) and for checks.
  MatrixXd Dense(int num_contacts) const;
  // "contact 2 (index) friction facet 5", for messages.
  std::string Describe(int row, const PlanProblem& problem) const;
};

// Pyramid facets (when `with_friction_facets`) and normal-force bounds of
// every contact, tightened by `confidence` times the ellipsoid support.
// Facet directions come from a table built once per process.
ConstraintRows BuildConstraintRows(const PlanProblem& problem,
                                   const MeasurementEllipsoid& ellipsoid, int cone_sides,
                                   double confidence, bool with_friction_facets);
void BuildConstraintRows(const PlanProblem& problem, const MeasurementEllipsoid& ellipsoid,
                         int cone_sides, double confidence, bool with_friction_facets,
                         ConstraintRows* out);

// The rows' slacks d_r - a_r . f_i at the stacked forces f (3n, N; f_i its
// row's contact's three entries), a_r . f_i summed (a_x f_x + a_y f_y) + a_z
// f_z; two rows per SSE2 instruction, each lane the scalar expression.
void RowSlacks(const ConstraintRows& rows, const double* forces, double* slacks);
// The least of them, a_r . f_i summed a_x f_x + (a_y f_y + a_z f_z) (as
// Eigen's 3-vector dot); +inf without rows.
double MinRowSlack(const ConstraintRows& rows, const double* forces);

// The rows on the FE-plane f = f0 + B x: plane_matrix = A B (m x d),
// plane_rhs = d - A f0, formed contact by contact (each row of A touches
// one contact's three coordinates).
void RowsOnPlane(const ConstraintRows& rows, const ForceEquilibrium& eq, MatrixXd* plane_matrix,
                 VectorXd* plane_rhs);

// Per-contact normal-force std. dev. rho_n,i = sqrt(n_i^T S_ii n_i) (N).
std::vector<double> NormalForceSigma(const PlanProblem& problem,
                                     const MeasurementEllipsoid& ellipsoid);
void NormalForceSigma(const PlanProblem& problem, const MeasurementEllipsoid& ellipsoid,
                      std::vector<double>* out);

// Tangential spread rho_t,i = sqrt(lambda_max(P_t S_ii P_t)) (N), in closed
// form: the larger eigenvalue of the 2x2 block of S_ii in TangentBasis().
std::vector<double> TangentialForceSigma(const PlanProblem& problem,
                                         const MeasurementEllipsoid& ellipsoid);
void TangentialForceSigma(const PlanProblem& problem, const MeasurementEllipsoid& ellipsoid,
                          std::vector<double>* out);

// sqrt(lambda_max(P_t S P_t)) of a 3x3 covariance S at a contact with unit
// `normal` (P_t its tangent-plane projector), in closed form.
double TangentialSpread(const Vec3& normal, const Eigen::Matrix3d& covariance);

// Robust tightening of each contact's exact (circular) friction cone (N):
// shift_i = kappa (mu_i rho_n,i + rho_t,i), so the cone every force the
// sensors could mistake for f_i stays in is
//   |P_i f_i| <= mu_i n_i . f_i - shift_i,   P_i = I - n_i n_i^T.
// `normal_sigma` / `tangential_sigma` as from the two functions above.
std::vector<double> ExactConeShift(const PlanProblem& problem,
                                   const std::vector<double>& normal_sigma,
                                   const std::vector<double>& tangential_sigma, double confidence);
void ExactConeShift(const PlanProblem& problem, const std::vector<double>& normal_sigma,
                    const std::vector<double>& tangential_sigma, double confidence,
                    std::vector<double>* out);

// Slack (N) of that robust cone at the force f of a contact with unit
// normal n and friction mu: mu n . f - shift - |P f|; >= 0 inside.
double ExactConeSlack(const Vec3& normal, double mu, double shift, const Vec3& force);

// The tightening for uncertain inertial parameters (parameter_uncertainty.h).
struct ParameterTightening {
  bool active = false;                              // non-zero covariance and kappa_b > 0
  double confidence = 0.0;                          // kappa_b
  std::vector<Eigen::Matrix3d> contact_covariance;  // P_i = (G^+ S_b G^+T)_ii (N^2)
  VectorXd row_margin;              // kappa_b sqrt(a^T P_i a) per row (N), taken off rhs
  std::vector<double> cone_margin;  // EXACT: kappa_b (mu rho_n,b + rho_t,b) (N), in cone_shift
};

// Everything a backend needs, derived once from a validated request.
struct PreparedProblem {
  PlanProblem problem;  // validated, normals of unit length
  ForceEquilibrium equilibrium;
  MeasurementEllipsoid ellipsoid;
  ConstraintRows rows;                   // PYRAMID: facets + bounds; EXACT: bounds only
  std::vector<double> normal_sigma;      // rho_n,i (N)
  std::vector<double> tangential_sigma;  // rho_t,i (N); empty after a geometric_only prepare
  // EXACT: ExactConeShift() at options.confidence (N), the one tightening of
  // the exact cones that every backend and the reported margin use.
  // PYRAMID: empty (the facets in `rows` carry the tightening).
  std::vector<double> cone_shift;
  // Model uncertainty (parameter_uncertainty.h). `problem`'s frictions are
  // the planning ones, mu - kappa sigma_mu; the request's are kept here
  // (empty when no contact has a friction_sigma).
  std::vector<double> nominal_friction;
  ParameterTightening parameters;
  int num_contacts() const { return static_cast<int>(problem.contacts.size()); }
};

PreparedProblem Prepare(PlanProblem validated, const PlanOptions& options);
// In place: `prepared->problem` already holds the validated problem; every
// other member is recomputed, reusing its storage. `geometric_only`: for the
// GEOMETRIC backend alone, which does not read G and the independent
// equilibrium rows (left empty unless the problem carries model uncertainty,
// HasModelUncertainty, whose tightening reads them) nor the tangential sigmas
// (left empty: only the EXACT cones use them).
void PrepareInPlace(const PlanOptions& options, EquilibriumScratch* scratch,
                    PreparedProblem* prepared, bool geometric_only = false);

}  // namespace tactforce::planner
