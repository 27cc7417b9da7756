// FitInertia (fit.h): validation of the samples and options, the method's
// run (CONSTRAINED with the mesh as a prior; DENSITY with its fallback to
// CONSTRAINED when the data contradict the mesh), and what every fit reports
// besides the parameters: consistency, standard errors, excitation; the
// text of DescribeFit; and two helpers the methods share (ResidualRms,
// RoughScale).
#include "tactforce/inertia/fit.h"

#include <algorithm>
#include <time.h>

#include <chrono>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "internal.h"
#include "tactforce/io/enum_names.h"
#include "tactforce/inertia/hull.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::inertia {

int64_t FitWorkingBytes(InertiaMethod method, int64_t samples) {
  const int64_t per_sample = method == InertiaMethod::kFactorGraph ? 4608 : 2048;
  return samples * per_sample;
}

namespace {

// Enum names (io/enum_names.h): the CLI spelling, and the proto's after its prefix.
constexpr io::EnumNameRow<InertiaMethod> kMethodNames[] = {
    {InertiaMethod::kBaselineLs, "baseline-ls"},
    {InertiaMethod::kFactorGraph, "factor-graph"},
    {InertiaMethod::kConstrained, "constrained"},
    {InertiaMethod::kDensity, "density"}};
constexpr io::EnumNameRow<FactorGraphVariant> kVariantNames[] = {
    {FactorGraphVariant::kBaselineFg, "baseline-fg"},
    {FactorGraphVariant::kNoConstraint, "fg-no-c", "no-c"},
    {FactorGraphVariant::kConstraint, "fg-c", "c"},
    {FactorGraphVariant::kConstraintPrior, "fg-c-g", "c-g"}};

}  // namespace

const char* ToString(InertiaMethod m) { return io::EnumName(kMethodNames, m); }

absl::StatusOr<InertiaMethod> ParseInertiaMethod(std::string_view text) {
  return io::ParseEnumName(kMethodNames, text, "method", "inertia-method-");
}

const char* ToString(FactorGraphVariant v) { return io::EnumName(kVariantNames, v); }

absl::StatusOr<FactorGraphVariant> ParseFactorGraphVariant(std::string_view text) {
  return io::ParseEnumName(kVariantNames, text, "fg_variant", "factor-graph-variant-");
}

int MinimumSamples(const InertiaSamples& s, InertiaMethod method) {
  if (method != InertiaMethod::kFactorGraph && s.HasKinematics()) return 2;
  return method == InertiaMethod::kConstrained || method == InertiaMethod::kDensity ? 5 : 4;
}

namespace {

absl::Status CheckSigma(double v, const char* name) {
  if (!std::isfinite(v) || v < 0)
    return absl::InvalidArgumentError(
        absl::StrCat(name, ": must be finite and >= 0 (got ", v, ")"));
  return absl::OkStatus();
}

absl::Status CheckPositive(double v, const char* name) {
  if (!std::isfinite(v) || !(v > 0))
    return absl::InvalidArgumentError(absl::StrCat(name, ": must be finite and > 0 (got ", v, ")"));
  return absl::OkStatus();
}

std::string Vec(const Vec3& v) {
  return absl::StrFormat("(%.6g, %.6g, %.6g)", v.x(), v.y(), v.z());
}

absl::Status ValidateMeshOptions(const InertiaOptions& o) {
  TF_RETURN_IF_ERROR(CheckSigma(o.constrained.mesh_prior_weight, "mesh_prior_weight"));
  if (!std::isfinite(o.density.regularization))
    return absl::InvalidArgumentError("density_regularization: must be finite (< 0 = automatic)");
  if (o.density.folds < 2) return absl::InvalidArgumentError("density.folds: must be >= 2");
  TF_RETURN_IF_ERROR(CheckSigma(o.density.mesh_tolerance, "mesh_tolerance"));
  if (o.density.regions.target_regions < 1 || o.density.regions.target_regions > kMaxTargetRegions)
    return absl::InvalidArgumentError(absl::StrCat("regions.target_regions: must be in 1..",
                                                   kMaxTargetRegions, " (got ",
                                                   o.density.regions.target_regions, ")"));
  if (o.method == InertiaMethod::kDensity && !o.mesh)
    return absl::InvalidArgumentError(
        "mesh: the density method needs the object's closed mesh (--mesh)");
  if (o.mesh) {
    for (size_t i = 0; i < o.mesh->vertices.size(); ++i)
      if (!o.mesh->vertices[i].allFinite())
        return absl::InvalidArgumentError(
            absl::StrCat(o.mesh_name, ": vertex ", i, " is not finite"));
    for (size_t t = 0; t < o.mesh->triangles.size(); ++t)
      for (int k : o.mesh->triangles[t])
        if (k < 0 || k >= static_cast<int>(o.mesh->vertices.size()))
          return absl::InvalidArgumentError(absl::StrCat(o.mesh_name, ": triangle ", t,
                                                         " has vertex index ", k, " out of range"));
    if (o.method == InertiaMethod::kDensity || o.method == InertiaMethod::kConstrained) {
      TF_RETURN_IF_ERROR(io::RequireClosedSolid(io::CheckMesh(*o.mesh), o.mesh_name));
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status ValidateInertiaOptions(const InertiaOptions& o) {
  if (!o.gravity.allFinite()) return absl::InvalidArgumentError("gravity: not finite");
  const InertiaNoise& n = o.noise;
  const std::pair<double, const char*> sigmas[] = {
      {n.force_sigma, "noise.force_sigma"},
      {n.torque_sigma, "noise.torque_sigma"},
      {n.position_sigma, "noise.position_sigma"},
      {n.orientation_sigma, "noise.orientation_sigma"},
      {n.angular_velocity_sigma, "noise.angular_velocity_sigma"},
      {n.linear_acceleration_sigma, "noise.linear_acceleration_sigma"},
      {n.angular_acceleration_sigma, "noise.angular_acceleration_sigma"}};
  for (const auto& [v, name] : sigmas) TF_RETURN_IF_ERROR(CheckSigma(v, name));
  const BaselineLsOptions& ls = o.baseline_ls;
  if (ls.savitzky_golay && (ls.savitzky_golay_window < 5 || ls.savitzky_golay_window % 2 == 0))
    return absl::InvalidArgumentError(absl::StrCat(
        "savitzky_golay_window: must be odd and >= 5 (got ", ls.savitzky_golay_window, ")"));
  if (o.smoothing_window != 0 && (o.smoothing_window < 5 || o.smoothing_window % 2 == 0))
    return absl::InvalidArgumentError(absl::StrCat(
        "smoothing_window: must be 0 (automatic) or odd and >= 5 (got ", o.smoothing_window, ")"));
  if (!std::isfinite(o.constrained.regularization) || o.constrained.regularization < 0)
    return absl::InvalidArgumentError("regularization: must be finite and >= 0");
  if (o.reweighting_rounds < 1)
    return absl::InvalidArgumentError("reweighting_rounds: must be >= 1");
  if (o.max_iterations < 1) return absl::InvalidArgumentError("max_iterations: must be >= 1");
  const FactorGraphOptions& fg = o.factor_graph;
  const std::pair<double, const char*> pos[] = {
      {fg.dynamics_force_sigma, "factor_graph.dynamics_force_sigma"},
      {fg.dynamics_torque_sigma, "factor_graph.dynamics_torque_sigma"},
      {fg.min_force_sigma, "factor_graph.min_force_sigma"},
      {fg.min_torque_sigma, "factor_graph.min_torque_sigma"},
      {fg.min_position_sigma, "factor_graph.min_position_sigma"},
      {fg.min_orientation_sigma, "factor_graph.min_orientation_sigma"},
      {fg.constraint_sigma, "factor_graph.constraint_sigma"}};
  for (const auto& [v, name] : pos) TF_RETURN_IF_ERROR(CheckPositive(v, name));
  if (!(o.excitation_threshold >= 0 && o.excitation_threshold < 1))
    return absl::InvalidArgumentError("excitation_threshold: must be in [0, 1)");
  TF_RETURN_IF_ERROR(ValidateMeshOptions(o));
  std::optional<ConvexHull> hull;
  if (!o.hull.empty()) {
    TF_ASSIGN_OR_RETURN(hull, ComputeConvexHull(o.hull));
  }
  if (o.method == InertiaMethod::kFactorGraph &&
      o.factor_graph.variant == FactorGraphVariant::kConstraintPrior && !o.prior)
    return absl::InvalidArgumentError(
        "prior: the factor-graph variant fg-c-g needs a prior (the geodesic prior factor B); give "
        "one or use fg-c");
  if (o.prior) {
    const InertialParameters& p = o.prior->params;
    TF_RETURN_IF_ERROR(CheckPositive(p.mass, "prior.mass"));
    if (!p.com.allFinite()) return absl::InvalidArgumentError("prior.com: not finite");
    for (double v : p.inertia_com.ToArray())
      if (!std::isfinite(v)) return absl::InvalidArgumentError("prior.inertia: not finite");
    TF_RETURN_IF_ERROR(CheckSigma(o.prior->weight, "prior.weight"));
    if (!IsPhysicallyConsistent(p))
      return absl::InvalidArgumentError(
          "prior: not physically consistent (its pseudo-inertia is not positive definite: check "
          "the inertia's triangle inequalities)");
    if (hull && !hull->Contains(p.com, 1e-9)) {
      return absl::InvalidArgumentError(
          absl::StrCat("prior.com ", Vec(p.com), " is outside the hull (by ",
                       absl::StrFormat("%.3g", hull->SignedDistanceBound(p.com)), " m)"));
    }
  }
  return absl::OkStatus();
}

namespace internal {

void ResidualRms(const std::vector<KinPoint>& kin, const std::vector<Vector6d>& wrench,
                 const Vector10d& pi, InterruptPoll* poll, double* rms_force, double* rms_torque) {
  double sf = 0, st = 0;
  for (size_t i = 0; i < kin.size(); ++i) {
    if (poll->Tick()) break;
    const Vector6d r = Regressor(kin[i].w, kin[i].dw, kin[i].a_minus_g) * pi - wrench[i];
    sf += r.head<3>().squaredNorm();
    st += r.tail<3>().squaredNorm();
  }
  const double n = std::max<size_t>(kin.size(), 1) * 3.0;
  *rms_force = std::sqrt(sf / n);
  *rms_torque = std::sqrt(st / n);
}

void RoughScale(const Vector10d& pi, const ConvexHull* hull, double* m0, double* length) {
  double m = pi(0);
  if (!(m > 0) || !std::isfinite(m)) m = std::abs(m) > 0 && std::isfinite(m) ? std::abs(m) : 1.0;
  double l = 0;
  if (hull) l = 0.5 * hull->size;
  if (!(l > 0)) {
    const double tr = pi(4) + pi(5) + pi(6);  // = 2 tr(second moment)
    const double c2 = pi.segment<3>(1).squaredNorm() / (m * m);
    l = std::sqrt(std::max({0.5 * tr / m, c2, 0.0}));
  }
  if (!(l > 1e-6) || !std::isfinite(l)) l = 0.1;
  *m0 = m;
  *length = l;
}

}  // namespace internal

namespace {

// Describes a unit direction in scaled parameter space.
std::string NameDirection(const Vector10d& v) {
  const auto& names = StandardParameterNames();
  int imax = 0;
  for (int i = 1; i < 10; ++i)
    if (std::abs(v(i)) > std::abs(v(imax))) imax = i;
  const double sign = v(imax) < 0 ? -1.0 : 1.0;
  std::string out;
  for (int i = 0; i < 10; ++i) {
    const double c = sign * v(i);
    if (std::abs(c) < 0.1 * std::abs(v(imax))) continue;
    if (out.empty()) {
      out = absl::StrFormat("%.2g %s", c, names[i]);
    } else {
      out += absl::StrFormat(" %s %.2g %s", c < 0 ? "-" : "+", std::abs(c), names[i]);
    }
  }
  return out;
}

}  // namespace

namespace {
double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}
}  // namespace

std::string DescribeFit(const InertiaFit& f) {
  const auto in = f.params.inertia_com.ToArray();
  const auto se = f.inertia_se.ToArray();
  std::string out =
      absl::StrFormat("method: %s (%d iterations, %.1f ms, %d samples used)\n", ToString(f.method),
                      f.iterations, 1e3 * f.time_seconds, f.samples_used);
  out += absl::StrFormat("mass: %.6g kg (se %.2g)\n", f.params.mass, f.mass_se);
  out +=
      absl::StrFormat("com: (%.6g, %.6g, %.6g) m (se %.2g, %.2g, %.2g)\n", f.params.com.x(),
                      f.params.com.y(), f.params.com.z(), f.com_se.x(), f.com_se.y(), f.com_se.z());
  out += "inertia about the CoM (kg m^2):";
  const char* names[] = {"Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"};
  for (int i = 0; i < 6; ++i)
    out += absl::StrFormat(" %s %.6g (se %.2g)%s", names[i], in[i], se[i], i < 5 ? "," : "\n");
  out += absl::StrFormat("principal moments: %.6g, %.6g, %.6g\n", f.principal_moments(0),
                         f.principal_moments(1), f.principal_moments(2));
  for (int i = 0; i < 3; ++i)
    out += absl::StrFormat("  axis %d: (%.4f, %.4f, %.4f)\n", i, f.principal_axes(0, i),
                           f.principal_axes(1, i), f.principal_axes(2, i));
  out += absl::StrFormat(
      "physically consistent: %s (smallest eigenvalue of the scaled pseudo-inertia %.3g)\n",
      f.physically_consistent ? "yes" : "NO", f.pseudo_inertia_min_eigenvalue);
  if (!f.com_in_hull) out += "CoM outside the hull\n";
  out += absl::StrFormat("residual RMS: force %.4g N, torque %.4g N m\n", f.residual_rms_force,
                         f.residual_rms_torque);
  out += "relative singular values:";
  for (double v : f.singular_values) out += absl::StrFormat(" %.3g", v);
  out += "\n";
  if (f.poorly_excited.empty()) {
    out += "poorly excited directions: none\n";
  } else {
    for (const std::string& d : f.poorly_excited) out += "poorly excited: " + d + "\n";
  }
  if (f.mesh_check) {
    const io::MeshCheck& m = *f.mesh_check;
    out += absl::StrFormat(
        "mesh: %d faces, %d vertices, %s%s, volume %.6g m^3\n", m.faces, m.vertices,
        m.closed && m.consistently_oriented ? "closed and consistently oriented"
                                            : "NOT a closed solid",
        m.junction_edges > 0
            ? absl::StrCat(" (", m.junction_edges, " edges where closed parts touch)")
            : std::string(),
        m.volume);
  }
  if (!f.densities.empty()) {
    out += absl::StrFormat("densities (%s%s, regulariser %.3g by %s):\n",
                           f.density_realizable ? "density-realizable" : "not used",
                           f.mesh_contradicted ? ", mesh contradicted" : "",
                           f.density_regularization, f.density_regularization_rule);
    for (const InertiaFit::RegionDensity& d : f.densities)
      out += absl::StrFormat("  %-18s %10.5g kg/m^3 (se %.2g)  volume %.4g m^3\n", d.label,
                             d.density, d.standard_error, d.volume);
  }
  if (f.method == InertiaMethod::kDensity)
    out += absl::StrFormat("density-realizable: %s\n", f.density_realizable ? "yes" : "NO");
  // A contradicted mesh's line is the first note.
  for (const std::string& n : f.notes) out += "note: " + n + "\n";
  return out;
}

namespace {

// CONSTRAINED; given a mesh and no prior, the mesh's uniform-density inertia
// scaled to the mass of a first fit is the prior of a second.
absl::StatusOr<internal::MethodOutput> FitConstrainedWithMesh(const InertiaSamples& samples,
                                                              const InertiaOptions& options,
                                                              const ConvexHull* hull) {
  absl::StatusOr<internal::MethodOutput> first = internal::FitConstrained(samples, options, hull);
  if (!first.ok() || !options.mesh || options.prior || !(options.constrained.mesh_prior_weight > 0))
    return first;
  const SolidMoments solid = MeshMoments(*options.mesh);
  if (!(solid.volume > 0) || !(first->pi(0) > 0)) return first;
  InertiaOptions with_prior = options;
  with_prior.prior =
      InertiaPrior{InertialParameters::FromStandard(solid.Standard(first->pi(0) / solid.volume)),
                   options.constrained.mesh_prior_weight};
  TF_ASSIGN_OR_RETURN(internal::MethodOutput second,
                      internal::FitConstrained(samples, with_prior, hull));
  second.iterations += first->iterations;
  second.notes.push_back(absl::StrFormat(
      "prior: %s at uniform density %.4g kg/m^3 (the fitted mass %.6g kg), weight %g",
      options.mesh_name, first->pi(0) / solid.volume, first->pi(0),
      options.constrained.mesh_prior_weight));
  return second;
}

// The data contradict the mesh (FitDensity's verdict in `fit`): CONSTRAINED's
// answer without the mesh, its notes led by the verdict and by the rejected
// DENSITY fit's mesh-test and held-out notes (the last two of `density`).
absl::StatusOr<internal::MethodOutput> ConstrainedInstead(const InertiaSamples& samples,
                                                          const InertiaOptions& options,
                                                          const ConvexHull* hull,
                                                          const internal::MethodOutput& density,
                                                          const InertiaFit& fit) {
  InertiaOptions plain = options;
  plain.mesh = nullptr;
  plain.method = InertiaMethod::kConstrained;
  TF_ASSIGN_OR_RETURN(internal::MethodOutput c, internal::FitConstrained(samples, plain, hull));
  const std::vector<std::string>& n = density.notes;
  c.notes.insert(c.notes.begin(), {fit.mesh_contradiction, n[n.size() - 1], n[n.size() - 2]});
  c.iterations += density.iterations;
  return c;
}

// Standard errors of (m, c, H_c) from the covariance of pi (first order).
void SetStandardErrors(const internal::MethodOutput& r, InertiaFit* fit) {
  auto reported = [](const Vector10d& pi) {
    const InertialParameters p = InertialParameters::FromStandard(pi);
    Vector10d out;
    const auto in = p.inertia_com.ToArray();
    out << p.mass, p.com, in[0], in[1], in[2], in[3], in[4], in[5];
    return out;
  };
  internal::Matrix10d J;
  for (int i = 0; i < 10; ++i) {
    const double h = 1e-6 * r.scale(i);
    Vector10d a = r.pi, b = r.pi;
    a(i) += h;
    b(i) -= h;
    J.col(i) = (reported(a) - reported(b)) / (2 * h);
  }
  const internal::Matrix10d c = J * r.cov * J.transpose();
  const Vector10d se = c.diagonal().cwiseMax(0.0).cwiseSqrt();
  fit->mass_se = se(0);
  fit->com_se = se.segment<3>(1);
  fit->inertia_se = InertiaTensor::FromArray({se(4), se(5), se(6), se(7), se(8), se(9)});
}

// Excitation: eigen-decomposition of S info S (S = parameter scale); the
// relative singular values, and the directions below `threshold` named.
void SetExcitation(const internal::MethodOutput& r, double threshold, InertiaFit* fit) {
  const internal::Matrix10d S = r.scale.asDiagonal();
  const internal::Matrix10d M = S * r.info * S;
  Eigen::SelfAdjointEigenSolver<internal::Matrix10d> es(0.5 * (M + M.transpose()));
  const double top = std::max(es.eigenvalues()(9), 0.0);
  for (int i = 9; i >= 0; --i) {
    const double sv = std::sqrt(std::max(es.eigenvalues()(i), 0.0));
    const double rel = top > 0 ? sv / std::sqrt(top) : 0.0;
    fit->singular_values.push_back(rel);
    if (rel < threshold) {
      fit->poorly_excited.push_back(absl::StrFormat("%s (relative singular value %.2g)",
                                                    NameDirection(es.eigenvectors().col(i)), rel));
    }
  }
}

}  // namespace

absl::StatusOr<InertiaFit> FitInertia(const InertiaSamples& samples_in,
                                      const InertiaOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = ThreadCpuSeconds();
  internal::InterruptPoll poll(options.interrupt);
  InertiaSamples samples;  // samples_in with unit quaternions
  TF_RETURN_IF_ERROR(internal::ValidateInertiaSamples(samples_in, &poll, &samples));
  TF_RETURN_IF_ERROR(ValidateInertiaOptions(options));
  const int need = MinimumSamples(samples_in, options.method);
  if (static_cast<int>(samples_in.samples.size()) < need) {
    return absl::InvalidArgumentError(
        absl::StrCat(samples_in.source_name.empty() ? "samples" : samples_in.source_name, ": ",
                     samples_in.samples.size(), " sample(s), at least ", need, " needed by ",
                     ToString(options.method), " for the 10 inertial parameters"));
  }
  std::optional<ConvexHull> hull;
  if (!options.hull.empty()) hull = *ComputeConvexHull(options.hull);
  const ConvexHull* hp = hull ? &*hull : nullptr;

  InertiaFit fit;
  absl::StatusOr<internal::MethodOutput> r;
  switch (options.method) {
    case InertiaMethod::kBaselineLs:
      r = internal::FitBaselineLs(samples, options);
      break;
    case InertiaMethod::kFactorGraph:
      r = internal::FitFactorGraph(samples, options, hp);
      break;
    case InertiaMethod::kConstrained:
      r = FitConstrainedWithMesh(samples, options, hp);
      break;
    case InertiaMethod::kDensity:
      r = internal::FitDensity(samples, options, &fit);
      if (r.ok() && fit.mesh_contradicted) r = ConstrainedInstead(samples, options, hp, *r, fit);
      break;
  }
  if (!r.ok()) return r.status();
  if (options.mesh && (options.method == InertiaMethod::kBaselineLs ||
                       options.method == InertiaMethod::kFactorGraph))
    r->notes.push_back(absl::StrCat("mesh ignored by ", ToString(options.method)));
  const FactorGraphVariant variant = options.factor_graph.variant;
  if (options.method != InertiaMethod::kFactorGraph && variant != FactorGraphVariant::kConstraint)
    r->notes.push_back(
        absl::StrCat("fg_variant ", ToString(variant), " ignored by ", ToString(options.method)));

  fit.method = options.method;
  fit.standard = r->pi;
  fit.params = InertialParameters::FromStandard(r->pi);
  PrincipalAxes(fit.params.inertia_com, &fit.principal_moments, &fit.principal_axes);
  fit.pseudo_inertia_min_eigenvalue = ScaledPseudoInertiaMinEigenvalue(fit.params);
  fit.physically_consistent = fit.pseudo_inertia_min_eigenvalue > 1e-12;
  fit.com_in_hull = hp ? hp->Contains(fit.params.com, 1e-7) : true;
  fit.residual_rms_force = r->rms_force;
  fit.residual_rms_torque = r->rms_torque;
  fit.iterations = r->iterations;
  fit.samples_used = r->samples_used;
  fit.notes = r->notes;

  if (r->cov.allFinite() && r->cov.norm() > 0 && fit.params.mass != 0) {
    SetStandardErrors(*r, &fit);
    fit.covariance = 0.5 * (r->cov + r->cov.transpose());
  }
  SetExcitation(*r, options.excitation_threshold, &fit);
  fit.time_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  fit.cpu_seconds = ThreadCpuSeconds() - cpu_start;
  if (options.progress) options.progress(1.0);
  return fit;
}

}  // namespace tactforce::inertia
