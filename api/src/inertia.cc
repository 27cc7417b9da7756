// Estimator.FitInertia over the API (inertia.h): options, samples, meshes
// and fits between inertia.proto and the inertia library, and the request
// stream with its per-sample field paths.
#include "tactforce/api/inertia.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <tuple>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/finite.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/planner/validation.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::api {
namespace {

using inertia::Vec3;

v1::Inertia TensorToProto(const inertia::InertiaTensor& t) {
  v1::Inertia out;
  out.set_ixx(t.ixx);
  out.set_iyy(t.iyy);
  out.set_izz(t.izz);
  out.set_ixy(t.ixy);
  out.set_ixz(t.ixz);
  out.set_iyz(t.iyz);
  return out;
}

inertia::InertiaTensor TensorFromProto(const v1::Inertia& t) {
  return inertia::InertiaTensor{t.ixx(), t.iyy(), t.izz(), t.ixy(), t.ixz(), t.iyz()};
}

// Library messages about the mesh start with its name ("box.stl: 3
// boundary edges ..."); over the API they start with the field. The
// others start with the option's own path ("gravity: ..."), which sits
// under "options.".
absl::Status PrefixedForField(const absl::Status& status, const std::string& mesh_name) {
  if (!mesh_name.empty() && absl::StartsWith(status.message(), absl::StrCat(mesh_name, ":")))
    return io::PrependPath(status, "options.mesh");
  return io::PrependPath(status, "options", ".");
}

// The library's enums and their proto values, one table each, read both
// ways: to the proto, the first row holding the value; from it, the row
// holding the number (none: `missing`).
template <class Proto, class Library>
struct EnumPair {
  Proto proto;
  Library library;
};
constexpr EnumPair<v1::RegionScheme, inertia::RegionScheme> kRegionSchemes[] = {
    {v1::REGION_SCHEME_AUTO, inertia::RegionScheme::kAuto},
    {v1::REGION_SCHEME_GRID, inertia::RegionScheme::kGrid},
    {v1::REGION_SCHEME_COLORS, inertia::RegionScheme::kColors},
    {v1::REGION_SCHEME_SINGLE, inertia::RegionScheme::kSingle}};
// UNSPECIFIED is C.
constexpr EnumPair<v1::FactorGraphVariant, inertia::FactorGraphVariant> kVariants[] = {
    {v1::FACTOR_GRAPH_VARIANT_BASELINE_FG, inertia::FactorGraphVariant::kBaselineFg},
    {v1::FACTOR_GRAPH_VARIANT_NO_C, inertia::FactorGraphVariant::kNoConstraint},
    {v1::FACTOR_GRAPH_VARIANT_C, inertia::FactorGraphVariant::kConstraint},
    {v1::FACTOR_GRAPH_VARIANT_C_G, inertia::FactorGraphVariant::kConstraintPrior},
    {v1::FACTOR_GRAPH_VARIANT_UNSPECIFIED, inertia::FactorGraphVariant::kConstraint}};
constexpr EnumPair<v1::InertiaMethod, inertia::InertiaMethod> kMethods[] = {
    {v1::INERTIA_METHOD_BASELINE_LS, inertia::InertiaMethod::kBaselineLs},
    {v1::INERTIA_METHOD_FACTOR_GRAPH, inertia::InertiaMethod::kFactorGraph},
    {v1::INERTIA_METHOD_CONSTRAINED, inertia::InertiaMethod::kConstrained},
    {v1::INERTIA_METHOD_DENSITY, inertia::InertiaMethod::kDensity}};

template <class Proto, class Library, size_t N>
Proto ProtoOf(const EnumPair<Proto, Library> (&pairs)[N], Library value, Proto missing) {
  for (const auto& p : pairs)
    if (p.library == value) return p.proto;
  return missing;
}
template <class Proto, class Library, size_t N>
std::optional<Library> LibraryOf(const EnumPair<Proto, Library> (&pairs)[N], int number) {
  for (const auto& p : pairs)
    if (static_cast<int>(p.proto) == number) return p.library;
  return std::nullopt;
}
// A request's value: "options.<field>: unknown value 7" when no row holds it.
template <class Proto, class Library, size_t N>
absl::StatusOr<Library> OptionOf(const EnumPair<Proto, Library> (&pairs)[N], int number,
                                 const char* field) {
  if (std::optional<Library> v = LibraryOf(pairs, number)) return *v;
  return absl::InvalidArgumentError(absl::StrCat("options.", field, ": unknown value ", number));
}

// UNSPECIFIED and unknown numbers: CONSTRAINED (a response's method; a
// request's is checked by InertiaOptionsFromProto first).
inertia::InertiaMethod InertiaMethodFromProto(v1::InertiaMethod method) {
  return LibraryOf(kMethods, method).value_or(inertia::InertiaMethod::kConstrained);
}

v1::MeshCheck MeshCheckToProto(const io::MeshCheck& c) {
  v1::MeshCheck out;
  out.set_closed(c.closed);
  out.set_consistently_oriented(c.consistently_oriented);
  out.set_volume(c.volume);
  out.set_faces(c.faces);
  out.set_vertices(c.vertices);
  out.set_boundary_edges(c.boundary_edges);
  out.set_non_manifold_edges(c.non_manifold_edges);
  out.set_inconsistent_edges(c.inconsistent_edges);
  out.set_degenerate_faces(c.degenerate_faces);
  out.set_area(c.area);
  out.set_junction_edges(c.junction_edges);
  return out;
}

io::MeshCheck MeshCheckFromProto(const v1::MeshCheck& c) {
  io::MeshCheck out;
  out.closed = c.closed();
  out.consistently_oriented = c.consistently_oriented();
  out.volume = c.volume();
  out.faces = c.faces();
  out.vertices = c.vertices();
  out.boundary_edges = c.boundary_edges();
  out.non_manifold_edges = c.non_manifold_edges();
  out.inconsistent_edges = c.inconsistent_edges();
  out.degenerate_faces = c.degenerate_faces();
  out.area = c.area();
  out.junction_edges = c.junction_edges();
  return out;
}

// Inertial parameters given in the options (prior, truth) within the
// planner's limits: "options.truth.inertia.ixx: magnitude exceeds 1e+12 kg m^2".
absl::Status CheckParameterMagnitudes(const std::string& path, const v1::InertialParameters& p) {
  TF_RETURN_IF_ERROR(planner::CheckMagnitude(path + ".mass", p.mass(), planner::kMaxMass, "kg"));
  TF_RETURN_IF_ERROR(
      planner::CheckMagnitude(path + ".com", FromProto(p.com()), planner::kMaxLength, "m"));
  const v1::Inertia& in = p.inertia();
  const std::pair<const char*, double> moments[] = {{"ixx", in.ixx()}, {"iyy", in.iyy()},
                                                    {"izz", in.izz()}, {"ixy", in.ixy()},
                                                    {"ixz", in.ixz()}, {"iyz", in.iyz()}};
  for (const auto& [name, v] : moments) {
    TF_RETURN_IF_ERROR(planner::CheckMagnitude(absl::StrCat(path, ".inertia.", name), v,
                                               planner::kMaxInertia, "kg m^2"));
  }
  return absl::OkStatus();
}

// The physical numbers of the options within the planner's limits (the
// fit's products of them stay finite); other options are the library's.
absl::Status CheckOptionMagnitudes(const v1::InertiaFitOptions& o) {
  using planner::CheckMagnitude;
  TF_RETURN_IF_ERROR(CheckMagnitude("options.gravity", FromProto(o.gravity()),
                                    planner::kMaxAcceleration, "m/s^2"));
  for (int i = 0; i < o.hull_size(); ++i) {
    if (!planner::IsBounded(FromProto(o.hull(i)), planner::kMaxLength))
      return planner::MagnitudeError(absl::StrCat("options.hull[", i, "]"), FromProto(o.hull(i)),
                                     planner::kMaxLength, "m");
  }
  if (o.has_prior()) {
    TF_RETURN_IF_ERROR(CheckParameterMagnitudes("options.prior.params", o.prior().params()));
  }
  if (o.has_truth()) {
    TF_RETURN_IF_ERROR(CheckParameterMagnitudes("options.truth", o.truth()));
  }
  const v1::InertiaNoise& n = o.noise();
  const std::tuple<const char*, double, double, const char*> sigmas[] = {
      {"options.noise.force_sigma", n.force_sigma(), planner::kMaxForce, "N"},
      {"options.noise.torque_sigma", n.torque_sigma(), planner::kMaxForce, "N m"},
      {"options.noise.position_sigma", n.position_sigma(), planner::kMaxLength, "m"},
      {"options.noise.angular_velocity_sigma", n.angular_velocity_sigma(),
       planner::kMaxAngularVelocity, "rad/s"},
      {"options.noise.linear_acceleration_sigma", n.linear_acceleration_sigma(),
       planner::kMaxAcceleration, "m/s^2"},
      {"options.noise.angular_acceleration_sigma", n.angular_acceleration_sigma(),
       planner::kMaxAngularAcceleration, "rad/s^2"}};
  for (const auto& [field, v, limit, unit] : sigmas) {
    TF_RETURN_IF_ERROR(CheckMagnitude(field, v, limit, unit));
  }
  return absl::OkStatus();
}

}  // namespace

v1::FactorGraphVariant FactorGraphVariantToProto(inertia::FactorGraphVariant variant) {
  return ProtoOf(kVariants, variant, v1::FACTOR_GRAPH_VARIANT_UNSPECIFIED);
}

v1::RegionScheme RegionSchemeToProto(inertia::RegionScheme scheme) {
  return ProtoOf(kRegionSchemes, scheme, v1::REGION_SCHEME_AUTO);
}

v1::InertiaMethod InertiaMethodToProto(inertia::InertiaMethod method) {
  return ProtoOf(kMethods, method, v1::INERTIA_METHOD_UNSPECIFIED);
}

absl::StatusOr<ObjectMesh> MeshFromProto(const v1::MeshInput& input, std::string_view field_view) {
  const std::string field(field_view);
  ObjectMesh out;
  out.name = input.name().empty() ? "mesh" : input.name();
  if (input.data().empty())
    return absl::InvalidArgumentError(absl::StrCat(field, ".data: empty (give the bytes of ",
                                                   out.name, ", an STL, OBJ or PLY file)"));
  std::string format = input.format();
  if (format.empty()) {
    if (input.name().empty())
      return absl::InvalidArgumentError(absl::StrCat(
          field, ".format: empty and no name to take it from (give \"stl\", \"obj\" or \"ply\")"));
    absl::StatusOr<std::string> from_name = io::MeshFormatFromPath(input.name());
    if (!from_name.ok()) return io::PrependPath(from_name.status(), absl::StrCat(field, ".format"));
    format = *std::move(from_name);
  }
  io::MeshPlacement placement;
  if (input.has_scale()) placement.scale = input.scale();
  if (input.has_position()) placement.position = FromProto(input.position());
  if (input.has_orientation()) {
    const v1::Quaternion& q = input.orientation();
    placement.orientation = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z());
  }
  TF_RETURN_IF_ERROR(io::ValidatePlacement(placement, field));
  absl::StatusOr<io::TriangleMesh> mesh = io::ReadMeshBytes(input.data(), format, out.name);
  if (!mesh.ok()) return io::PrependPath(mesh.status(), field);
  out.mesh = io::TransformToObjectFrame(*mesh, placement);
  return out;
}

v1::MeshInput MeshInputToProto(std::string bytes, const std::string& format,
                               const std::string& name, const io::MeshPlacement& placement) {
  v1::MeshInput out;
  out.set_data(std::move(bytes));
  out.set_format(format);
  out.set_name(name);
  out.set_scale(placement.scale);
  *out.mutable_position() = ToProto(placement.position);
  v1::Quaternion* q = out.mutable_orientation();
  q->set_w(placement.orientation.w());
  q->set_x(placement.orientation.x());
  q->set_y(placement.orientation.y());
  q->set_z(placement.orientation.z());
  return out;
}

std::string InertiaMethodName(inertia::InertiaMethod method) {
  return v1::InertiaMethod_Name(InertiaMethodToProto(method));
}

inertia::InertialParameters InertialParametersFromProto(const v1::InertialParameters& p) {
  inertia::InertialParameters out;
  out.mass = p.mass();
  out.com = FromProto(p.com());
  out.inertia_com = TensorFromProto(p.inertia());
  return out;
}

v1::InertialParameters InertialParametersToProto(const inertia::InertialParameters& p) {
  v1::InertialParameters out;
  out.set_mass(p.mass);
  *out.mutable_com() = ToProto(p.com);
  *out.mutable_inertia() = TensorToProto(p.inertia_com);
  return out;
}

namespace {

inertia::InertiaNoise NoiseFromProto(const v1::InertiaNoise& n) {
  inertia::InertiaNoise out;
  out.force_sigma = n.force_sigma();
  out.torque_sigma = n.torque_sigma();
  out.position_sigma = n.position_sigma();
  out.orientation_sigma = n.orientation_sigma();
  out.angular_velocity_sigma = n.angular_velocity_sigma();
  out.linear_acceleration_sigma = n.linear_acceleration_sigma();
  out.angular_acceleration_sigma = n.angular_acceleration_sigma();
  return out;
}

}  // namespace

absl::StatusOr<inertia::InertiaOptions> InertiaOptionsFromProto(const v1::InertiaFitOptions& o) {
  inertia::InertiaOptions out;
  TF_RETURN_IF_ERROR(CheckOptionMagnitudes(o));
  if (!v1::InertiaMethod_IsValid(o.method()))
    return absl::InvalidArgumentError(absl::StrCat("options.method: unknown value ", o.method()));
  if (o.method() == v1::INERTIA_METHOD_UNSPECIFIED) {
    out.method =
        o.has_mesh() ? inertia::InertiaMethod::kDensity : inertia::InertiaMethod::kConstrained;
  } else {
    out.method = InertiaMethodFromProto(o.method());
  }
  if (o.has_gravity()) out.gravity = FromProto(o.gravity());
  for (const v1::Vec3& v : o.hull()) out.hull.push_back(FromProto(v));
  if (o.has_prior()) {
    inertia::InertiaPrior prior;
    prior.params = InertialParametersFromProto(o.prior().params());
    prior.weight = o.prior().weight() == 0.0 ? 1.0 : o.prior().weight();
    out.prior = prior;
  }
  out.noise = NoiseFromProto(o.noise());
  out.baseline_ls.savitzky_golay = o.savitzky_golay();
  // uint32 counts past int's range are named here, not wrapped negative.
  for (const auto& [value, field] : {std::pair{o.savitzky_golay_window(), "savitzky_golay_window"},
                                     std::pair{o.smoothing_window(), "smoothing_window"},
                                     std::pair{o.max_iterations(), "max_iterations"}}) {
    if (value > static_cast<uint32_t>(std::numeric_limits<int>::max())) {
      return absl::InvalidArgumentError(absl::StrCat("options.", field, ": ", value,
                                                     " is out of range (at most ",
                                                     std::numeric_limits<int>::max(), ")"));
    }
  }
  if (o.savitzky_golay_window() != 0)
    out.baseline_ls.savitzky_golay_window = static_cast<int>(o.savitzky_golay_window());
  out.smoothing_window = static_cast<int>(o.smoothing_window());
  if (o.max_iterations() != 0) out.max_iterations = static_cast<int>(o.max_iterations());
  if (o.has_regularization()) out.constrained.regularization = o.regularization();
  TF_ASSIGN_OR_RETURN(out.density.regions.scheme, OptionOf(kRegionSchemes, o.regions(), "regions"));
  TF_ASSIGN_OR_RETURN(out.factor_graph.variant, OptionOf(kVariants, o.fg_variant(), "fg_variant"));
  if (o.target_regions() != 0) {
    if (o.target_regions() > static_cast<uint32_t>(inertia::kMaxTargetRegions))
      return absl::InvalidArgumentError(absl::StrCat("options.target_regions: must be in 1..",
                                                     inertia::kMaxTargetRegions, ", 0 = 12 (got ",
                                                     o.target_regions(), ")"));
    out.density.regions.target_regions = static_cast<int>(o.target_regions());
  }
  if (o.has_density_regularization()) out.density.regularization = o.density_regularization();
  if (o.has_mesh_prior_weight()) out.constrained.mesh_prior_weight = o.mesh_prior_weight();
  if (o.has_contradiction_ratio()) {
    if (o.contradiction_ratio() != 0)
      return absl::InvalidArgumentError(
          absl::StrCat("options.contradiction_ratio: ", o.contradiction_ratio(),
                       " is no longer used (only 0, which disables the mesh test); set "
                       "options.mesh_tolerance instead "
                       "(first-order Riemannian, default ",
                       inertia::kDefaultMeshTolerance, ", 0 disables)"));
    out.density.mesh_tolerance = 0;
  }
  if (o.has_mesh_tolerance()) out.density.mesh_tolerance = o.mesh_tolerance();
  if (o.has_mesh()) {
    TF_ASSIGN_OR_RETURN(ObjectMesh mesh, MeshFromProto(o.mesh()));
    out.mesh_name = mesh.name;
    out.mesh = std::make_shared<const io::TriangleMesh>(std::move(mesh.mesh));
  }
  if (o.has_truth() && !inertia::IsPhysicallyConsistent(InertialParametersFromProto(o.truth()))) {
    return absl::InvalidArgumentError(
        "options.truth: not physically consistent (mass > 0 and a positive-definite pseudo-inertia "
        "needed)");
  }
  if (absl::Status s = inertia::ValidateInertiaOptions(out); !s.ok())
    return PrefixedForField(s, out.mesh ? out.mesh_name : std::string());
  return out;
}

v1::InertiaSample InertiaSampleToProto(const inertia::InertiaSample& s,
                                       inertia::ForceSource source) {
  v1::InertiaSample out;
  out.set_t(s.t);
  *out.mutable_position() = ToProto(s.position);
  v1::Quaternion* q = out.mutable_orientation();
  q->set_w(s.orientation.w());
  q->set_x(s.orientation.x());
  q->set_y(s.orientation.y());
  q->set_z(s.orientation.z());
  if (source == inertia::ForceSource::kWrench) {
    *out.mutable_wrench()->mutable_force() = ToProto(s.force);
    *out.mutable_wrench()->mutable_torque() = ToProto(s.torque);
    out.set_force_sigma(s.force_sigma);
    out.set_torque_sigma(s.torque_sigma);
  } else {
    for (const inertia::ContactReading& c : s.contacts) {
      v1::ContactSample* cs = out.add_contacts();
      *cs->mutable_point() = ToProto(c.point);
      *cs->mutable_force() = ToProto(c.force);
      cs->set_sigma(c.sigma);
    }
  }
  if (s.kinematics) {
    v1::MeasuredKinematics* k = out.mutable_kinematics();
    *k->mutable_angular_velocity() = ToProto(s.kinematics->angular_velocity);
    *k->mutable_velocity() = ToProto(s.kinematics->velocity);
    *k->mutable_angular_acceleration() = ToProto(s.kinematics->angular_acceleration);
    *k->mutable_acceleration() = ToProto(s.kinematics->acceleration);
  }
  return out;
}

v1::FitInertiaResponse InertiaFitToProto(const inertia::InertiaFit& fit) {
  v1::FitInertiaResponse out;
  out.set_method(InertiaMethodToProto(fit.method));
  out.set_mass(fit.params.mass);
  *out.mutable_com() = ToProto(fit.params.com);
  *out.mutable_inertia() = TensorToProto(fit.params.inertia_com);
  *out.mutable_principal_moments() = ToProto(fit.principal_moments);
  for (int k = 0; k < 3; ++k) *out.add_principal_axes() = ToProto(Vec3(fit.principal_axes.col(k)));
  out.set_physically_consistent(fit.physically_consistent);
  out.set_pseudo_inertia_min_eigenvalue(fit.pseudo_inertia_min_eigenvalue);
  out.set_com_in_hull(fit.com_in_hull);
  out.set_residual_rms_force(fit.residual_rms_force);
  out.set_residual_rms_torque(fit.residual_rms_torque);
  v1::InertiaStandardErrors* se = out.mutable_standard_errors();
  se->set_mass(fit.mass_se);
  *se->mutable_com() = ToProto(fit.com_se);
  *se->mutable_inertia() = TensorToProto(fit.inertia_se);
  if (!fit.covariance.isZero(0.0)) {
    for (int k = 0; k < 100; ++k) out.add_covariance(fit.covariance(k / 10, k % 10));
  }
  for (double s : fit.singular_values) out.add_singular_values(s);
  for (const std::string& d : fit.poorly_excited) out.add_poorly_excited(d);
  out.set_iterations(fit.iterations);
  out.set_time_seconds(fit.time_seconds);
  out.set_samples_used(fit.samples_used);
  for (const std::string& n : fit.notes) out.add_notes(n);
  for (const inertia::InertiaFit::RegionDensity& d : fit.densities) {
    v1::DensityRegion* r = out.add_densities();
    r->set_label(d.label);
    r->set_density(d.density);
    r->set_volume(d.volume);
    r->set_standard_error(d.standard_error);
  }
  out.set_density_realizable(fit.density_realizable);
  if (fit.mesh_check) *out.mutable_mesh_check() = MeshCheckToProto(*fit.mesh_check);
  out.set_density_regularization(fit.density_regularization);
  out.set_density_regularization_rule(fit.density_regularization_rule);
  out.set_heldout_residual_ratio(fit.heldout_residual_ratio);
  out.set_mesh_contradicted(fit.mesh_contradicted);
  out.set_mesh_contradiction(fit.mesh_contradiction);
  if (fit.region_model) out.set_region_scheme(RegionSchemeToProto(fit.region_model->scheme));
  return out;
}

inertia::InertiaFit InertiaFitFromProto(const v1::FitInertiaResponse& r) {
  inertia::InertiaFit fit;
  fit.method = InertiaMethodFromProto(r.method());
  fit.params.mass = r.mass();
  fit.params.com = FromProto(r.com());
  fit.params.inertia_com = TensorFromProto(r.inertia());
  fit.standard = fit.params.ToStandard();
  fit.principal_moments = FromProto(r.principal_moments());
  for (int k = 0; k < std::min(3, r.principal_axes_size()); ++k)
    fit.principal_axes.col(k) = FromProto(r.principal_axes(k));
  fit.physically_consistent = r.physically_consistent();
  fit.pseudo_inertia_min_eigenvalue = r.pseudo_inertia_min_eigenvalue();
  fit.com_in_hull = r.com_in_hull();
  fit.residual_rms_force = r.residual_rms_force();
  fit.residual_rms_torque = r.residual_rms_torque();
  fit.mass_se = r.standard_errors().mass();
  fit.com_se = FromProto(r.standard_errors().com());
  fit.inertia_se = TensorFromProto(r.standard_errors().inertia());
  if (r.covariance_size() == 100) {
    for (int k = 0; k < 100; ++k) fit.covariance(k / 10, k % 10) = r.covariance(k);
  }
  fit.singular_values.assign(r.singular_values().begin(), r.singular_values().end());
  fit.poorly_excited.assign(r.poorly_excited().begin(), r.poorly_excited().end());
  fit.iterations = r.iterations();
  fit.time_seconds = r.time_seconds();
  fit.samples_used = r.samples_used();
  fit.notes.assign(r.notes().begin(), r.notes().end());
  for (const v1::DensityRegion& d : r.densities())
    fit.densities.push_back({d.label(), d.density(), d.volume(), d.standard_error()});
  fit.density_realizable = r.density_realizable();
  if (r.has_mesh_check()) fit.mesh_check = MeshCheckFromProto(r.mesh_check());
  fit.density_regularization = r.density_regularization();
  fit.density_regularization_rule = r.density_regularization_rule();
  fit.heldout_residual_ratio = r.heldout_residual_ratio();
  fit.mesh_contradicted = r.mesh_contradicted();
  fit.mesh_contradiction = r.mesh_contradiction();
  return fit;
}

absl::StatusOr<v1::FitInertiaResponse> FitInertiaSamples(const inertia::InertiaSamples& samples,
                                                         const v1::InertiaFitOptions& options,
                                                         const CallLimits& limits,
                                                         std::function<void(double)> progress,
                                                         inertia::InertiaFit* fit_out,
                                                         const CallState& state) {
  TF_ASSIGN_OR_RETURN(inertia::InertiaOptions converted, InertiaOptionsFromProto(options));
  const int64_t n = static_cast<int64_t>(samples.samples.size());
  if (n == 0) return absl::InvalidArgumentError("samples: the stream carried no samples");
  if (limits.max_fit_bytes > 0 &&
      inertia::FitWorkingBytes(converted.method, n) > limits.max_fit_bytes) {
    return absl::InvalidArgumentError(absl::StrCat(
        "samples: a ", InertiaMethodName(converted.method), " fit of ", n, " samples needs about ",
        inertia::FitWorkingBytes(converted.method, n) >> 20,
        " MiB of working memory, over the server's limit of ", limits.max_fit_bytes >> 20,
        " MiB (--max-fit-bytes): send at most ",
        limits.max_fit_bytes / inertia::FitWorkingBytes(converted.method, 1), " samples"));
  }
  converted.progress = std::move(progress);
  converted.interrupt = state.interrupt;
  TF_ASSIGN_OR_RETURN(inertia::InertiaFit fit, inertia::FitInertia(samples, converted));
  v1::FitInertiaResponse response = InertiaFitToProto(fit);
  if (fit_out != nullptr) *fit_out = fit;
  response.set_samples_received(static_cast<int32_t>(samples.samples.size()));
  if (options.has_truth()) {
    const inertia::InertiaErrors e =
        inertia::CompareInertia(InertialParametersFromProto(options.truth()), fit.params);
    v1::InertiaErrors* errors = response.mutable_errors();
    errors->set_paper_metric(e.paper_metric);
    errors->set_riemannian(e.riemannian);
    errors->set_mass_percent(e.mass_percent);
    errors->set_com_mm(e.com_mm);
    errors->set_consistent(e.consistent);
  }
  return FiniteAnswer<v1::FitInertiaResponse>(std::move(response));
}

namespace {

// The sample vector's capacity once `needed` samples are held: grown
// explicitly (doubling) so that held_bytes_after can know it in advance.
size_t GrownCapacity(size_t capacity, size_t needed) {
  return needed <= capacity ? capacity : std::max(needed, 2 * capacity);
}

}  // namespace

int64_t InertiaStream::held_bytes() const {
  return static_cast<int64_t>(samples_.samples.capacity() * sizeof(inertia::InertiaSample) +
                              contacts_held_ * sizeof(inertia::ContactReading) +
                              options_.SpaceUsedLong());
}

int64_t InertiaStream::held_bytes_after(const v1::FitInertiaRequest& message) const {
  int64_t contacts = 0;
  for (const v1::InertiaSample& in : message.samples()) contacts += in.contacts_size();
  const size_t capacity = GrownCapacity(
      samples_.samples.capacity(),
      std::min<size_t>(samples_.samples.size() + message.samples_size(), max_samples_));
  const size_t options =
      message.has_options() ? message.options().SpaceUsedLong() : options_.SpaceUsedLong();
  return static_cast<int64_t>(capacity * sizeof(inertia::InertiaSample) +
                              (contacts_held_ + contacts) * sizeof(inertia::ContactReading) +
                              options);
}

absl::Status InertiaStream::Add(const v1::FitInertiaRequest& message) {
  const int index = messages_++;
  samples_.samples.reserve(GrownCapacity(
      samples_.samples.capacity(),
      std::min<size_t>(samples_.samples.size() + message.samples_size(), max_samples_)));
  if (message.has_options()) {
    if (index != 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("options: only the first message of the stream may carry options (message ",
                       index, " does)"));
    }
    options_ = message.options();
  }
  for (const v1::InertiaSample& in : message.samples()) {
    const int64_t i = samples_received();
    if (i >= max_samples_) {
      return absl::InvalidArgumentError(absl::StrCat(
          "samples: more than ", max_samples_, " samples in one stream (the server's limit)"));
    }
    const std::string where = absl::StrCat("samples[", i, "]");
    const bool has_contacts = in.contacts_size() > 0;
    if (i == 0) {
      if (has_contacts == in.has_wrench()) {
        return absl::InvalidArgumentError(
            absl::StrCat(where,
                         ": give exactly one force source, wrench or contacts (the first sample "
                         "sets it for the stream)"));
      }
      samples_.source =
          has_contacts ? inertia::ForceSource::kContacts : inertia::ForceSource::kWrench;
      samples_.num_contacts = in.contacts_size();
    } else if (samples_.source == inertia::ForceSource::kWrench &&
               (has_contacts || !in.has_wrench())) {
      return absl::InvalidArgumentError(
          absl::StrCat(where, ": wrench expected (samples[0] has a wrench)"));
    } else if (samples_.source == inertia::ForceSource::kContacts && in.has_wrench()) {
      return absl::InvalidArgumentError(
          absl::StrCat(where, ".wrench: contacts expected (samples[0] has contacts)"));
    }
    inertia::InertiaSample s;
    s.t = in.t();
    s.position = FromProto(in.position());
    s.orientation = Eigen::Quaterniond(in.orientation().w(), in.orientation().x(),
                                       in.orientation().y(), in.orientation().z());
    s.force = FromProto(in.wrench().force());
    s.torque = FromProto(in.wrench().torque());
    s.force_sigma = in.force_sigma();
    s.torque_sigma = in.torque_sigma();
    s.contacts.reserve(in.contacts_size());
    contacts_held_ += in.contacts_size();
    for (const v1::ContactSample& c : in.contacts()) {
      s.contacts.push_back(
          inertia::ContactReading{FromProto(c.point()), FromProto(c.force()), c.sigma()});
    }
    if (in.has_kinematics()) {
      const v1::MeasuredKinematics& k = in.kinematics();
      s.kinematics = inertia::MeasuredKinematics{
          FromProto(k.angular_velocity()), FromProto(k.velocity()),
          FromProto(k.angular_acceleration()), FromProto(k.acceleration())};
    }
    samples_.samples.push_back(std::move(s));
  }
  return absl::OkStatus();
}

}  // namespace tactforce::api
