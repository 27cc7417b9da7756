// In-hand configuration (inhand.h): tracker names, the built-in boxes of the
// paper's Table II, object JSON files, the box's inertia and mesh, the named
// tactile force models and ValidateInHandConfig.
#include <cmath>
#include <filesystem>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "tactforce/experiment/inhand.h"
#include "tactforce/io/json.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {
namespace {

using Eigen::Vector3d;

// Table II ground truth: mass, CoM, inertia about the origin (1e-5 kg m^2,
// diagonal only: the products are the parallel-axis terms).
struct TableRow {
  const char* name;
  double mass;
  Vector3d com;
  Vector3d inertia_origin_diag;
};

const TableRow kTableII[] = {
    {"box_0", 0.115, {0.094, -0.037, 0.032}, {37.20, 150.80, 154.00}},
    {"box_1", 0.179, {0.071, -0.033, 0.031}, {50.00, 165.30, 166.90}},
    {"box_2", 0.179, {0.090, -0.033, 0.031}, {50.00, 204.60, 206.20}},
    {"box_3", 0.131, {0.099, -0.036, 0.033}, {42.00, 182.90, 184.40}},
    {"box_4", 0.147, {0.109, -0.035, 0.031}, {43.30, 239.00, 242.00}},
};

// The uniform box whose inertia about its centre is the table's diagonal
// minus the parallel-axis terms.
InHandObject BoxFromTable(const TableRow& r) {
  const Vector3d c = r.com;
  const Vector3d parallel(r.mass * (c.y() * c.y() + c.z() * c.z()),
                          r.mass * (c.x() * c.x() + c.z() * c.z()),
                          r.mass * (c.x() * c.x() + c.y() * c.y()));
  const Vector3d ic = r.inertia_origin_diag * 1e-5 - parallel;  // Ixx = m/12 (b^2 + c^2), ...
  const Vector3d s = 12.0 * ic / r.mass;                        // b2+c2, a2+c2, a2+b2
  const double sum = 0.5 * s.sum();
  InHandObject o;
  o.name = r.name;
  o.mass = r.mass;
  o.center = c;
  o.dimensions = Vector3d(sum - s.x(), sum - s.y(), sum - s.z()).cwiseMax(1e-8).cwiseSqrt();
  return o;
}

absl::Status FieldError(const std::string& where, const std::string& what) {
  return absl::InvalidArgumentError(absl::StrCat(where, ": ", what));
}

absl::StatusOr<Vector3d> JsonTriple(const io::JsonValue& v, const std::string& where) {
  if (!v.is_array() || v.array().size() != 3)
    return FieldError(where, "expected an array of 3 numbers");
  Vector3d out;
  for (int k = 0; k < 3; ++k) {
    const io::JsonValue& x = v.array()[k];
    if (!x.is_number() || !std::isfinite(x.number()))
      return FieldError(where, "expected an array of 3 numbers");
    out(k) = x.number();
  }
  return out;
}

absl::StatusOr<double> JsonNumber(const io::JsonValue& v, const std::string& where) {
  if (!v.is_number() || !std::isfinite(v.number())) return FieldError(where, "expected a number");
  return v.number();
}

absl::StatusOr<std::vector<PointMass>> JsonPointMasses(const io::JsonValue& v,
                                                       const std::string& where) {
  if (!v.is_array()) return FieldError(where, "expected an array of {\"mass\", \"position\"}");
  std::vector<PointMass> out;
  for (size_t i = 0; i < v.array().size(); ++i) {
    const io::JsonValue& e = v.array()[i];
    const std::string at = absl::StrCat(where, "[", i, "]");
    if (!e.is_object()) return FieldError(at, "expected an object {\"mass\", \"position\"}");
    const io::JsonValue* m = e.Find("mass");
    const io::JsonValue* p = e.Find("position");
    if (m == nullptr || p == nullptr) return FieldError(at, "needs \"mass\" and \"position\"");
    PointMass pm;
    TF_ASSIGN_OR_RETURN(double mass, JsonNumber(*m, at + ".mass"));
    TF_ASSIGN_OR_RETURN(Vector3d pos, JsonTriple(*p, at + ".position"));
    pm.mass = mass;
    pm.position = pos;
    out.push_back(pm);
  }
  return out;
}

// One member of the object JSON into `o`.
absl::Status ReadObjectMember(const std::string& key, const io::JsonValue& value,
                              const std::string& where, InHandObject* o) {
  if (key == "name") {
    if (!value.is_string()) return FieldError(where, "expected a string");
    o->name = value.string();
  } else if (key == "dimensions" || key == "center") {
    TF_ASSIGN_OR_RETURN(Vector3d v, JsonTriple(value, where));
    (key == "dimensions" ? o->dimensions : o->center) = v;
  } else if (key == "mass") {
    TF_ASSIGN_OR_RETURN(o->mass, JsonNumber(value, where));
  } else if (key == "point_masses") {
    TF_ASSIGN_OR_RETURN(o->point_masses, JsonPointMasses(value, where));
  } else {
    return FieldError(where, "unknown key (expected name, dimensions, mass, center, point_masses)");
  }
  return absl::OkStatus();
}

}  // namespace

const char* ToString(Tracker t) { return t == Tracker::kVision ? "vision" : "kinematic"; }

absl::StatusOr<Tracker> ParseTracker(std::string_view text) {
  const std::string given(text);
  const std::string s = absl::AsciiStrToLower(given);
  if (s == "vision") return Tracker::kVision;
  if (s == "kinematic") return Tracker::kKinematic;
  return absl::InvalidArgumentError(
      absl::StrCat("tracker: unknown '", given, "' (expected vision or kinematic)"));
}

std::vector<std::string> BuiltInInHandObjects() {
  std::vector<std::string> names;
  for (const TableRow& r : kTableII) names.push_back(r.name);
  return names;
}

absl::StatusOr<InHandObject> BuiltInInHandObject(const std::string& name) {
  for (const TableRow& r : kTableII)
    if (name == r.name) return BoxFromTable(r);
  return absl::InvalidArgumentError(absl::StrCat("object: unknown '", name, "' (expected ",
                                                 absl::StrJoin(BuiltInInHandObjects(), ", "),
                                                 " or a JSON file)"));
}

absl::Status ValidateInHandObject(const InHandObject& o, const std::string& prefix) {
  if (!(o.mass > 0) || !std::isfinite(o.mass))
    return FieldError(prefix + "mass", absl::StrFormat("must be > 0, got %g", o.mass));
  if (o.mass > 20)
    return FieldError(prefix + "mass", absl::StrFormat("must be <= 20 kg, got %g", o.mass));
  for (int k = 0; k < 3; ++k)
    if (!(o.dimensions(k) >= 0.02 && o.dimensions(k) <= 0.5))
      return FieldError(
          prefix + "dimensions",
          absl::StrFormat("each edge must be in [0.02, 0.5] m, got %g", o.dimensions(k)));
  if (!o.center.allFinite() || o.center.norm() > 1)
    return FieldError(prefix + "center", "must be within 1 m");
  double sum = 0;
  for (size_t i = 0; i < o.point_masses.size(); ++i) {
    const PointMass& p = o.point_masses[i];
    const std::string at = absl::StrCat(prefix, "point_masses[", i, "]");
    if (!(p.mass > 0) || !std::isfinite(p.mass))
      return FieldError(at + ".mass", absl::StrFormat("must be > 0, got %g", p.mass));
    const Vector3d rel = (p.position - o.center).cwiseAbs();
    if (!p.position.allFinite() || (rel.array() > 0.5 * o.dimensions.array()).any())
      return FieldError(at + ".position", "must lie inside the box");
    sum += p.mass;
  }
  if (sum >= o.mass)
    return FieldError(prefix + "point_masses",
                      absl::StrFormat("total %g kg must be below mass %g kg", sum, o.mass));
  return absl::OkStatus();
}

absl::StatusOr<InHandObject> ParseInHandObjectJson(const std::string& text,
                                                   const std::string& source) {
  TF_ASSIGN_OR_RETURN(io::JsonValue root, io::ParseJson(text, source));
  if (!root.is_object()) return FieldError(source, "expected a JSON object");
  InHandObject o;
  o.name = std::filesystem::path(source).stem().string();
  if (root.Find("dimensions") == nullptr) return FieldError(source, "missing key 'dimensions'");
  if (root.Find("mass") == nullptr) return FieldError(source, "missing key 'mass'");
  for (const auto& [key, value] : root.members())
    TF_RETURN_IF_ERROR(ReadObjectMember(key, value, absl::StrCat(source, ": ", key), &o));
  TF_RETURN_IF_ERROR(ValidateInHandObject(o, source + ": "));
  return o;
}

absl::StatusOr<InHandObject> ReadInHandObjectFile(const std::string& path) {
  TF_ASSIGN_OR_RETURN(std::string text, io::ReadTextFile(path));
  return ParseInHandObjectJson(text, path);
}

inertia::InertialParameters InHandObjectInertia(const InHandObject& o) {
  double point_sum = 0;
  Vector3d moment = Vector3d::Zero();
  for (const PointMass& p : o.point_masses) point_sum += p.mass, moment += p.mass * p.position;
  const double mb = o.mass - point_sum;
  const Vector3d com = (moment + mb * o.center) / o.mass;
  const Vector3d d2 = o.dimensions.cwiseProduct(o.dimensions);
  Eigen::Matrix3d I =
      (mb / 12.0 * Vector3d(d2.y() + d2.z(), d2.x() + d2.z(), d2.x() + d2.y())).asDiagonal();
  auto shift = [&com](double m, const Vector3d& x) {
    const Vector3d d = x - com;
    return Eigen::Matrix3d(m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose()));
  };
  I += shift(mb, o.center);
  for (const PointMass& p : o.point_masses) I += shift(p.mass, p.position);
  inertia::InertialParameters out;
  out.mass = o.mass;
  out.com = com;
  out.inertia_com = inertia::InertiaTensor::FromMatrix(I);
  return out;
}

io::TriangleMesh InHandObjectMesh(const InHandObject& o) {
  io::TriangleMesh mesh;
  const Vector3d h = 0.5 * o.dimensions;
  for (int sx : {-1, 1})
    for (int sy : {-1, 1})
      for (int sz : {-1, 1})
        mesh.vertices.push_back(o.center + Vector3d(sx * h.x(), sy * h.y(), sz * h.z()));
  // Corner 4*(x>0) + 2*(y>0) + (z>0); counter-clockwise seen from outside.
  mesh.triangles = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                    {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  return mesh;
}

absl::StatusOr<TactileForceModel> NamedForceModel(const std::string& name) {
  TactileForceModel m;
  if (name == "biotac") return m;
  if (name == "ideal") return TactileForceModel{"ideal", 0, 1, 0, 0, 0};
  return absl::InvalidArgumentError(
      absl::StrCat("force_model: unknown '", name, "' (expected biotac or ideal)"));
}

absl::Status ValidateInHandConfig(const InHandConfig& c) {
  auto bad = [](const char* field, const std::string& why) { return FieldError(field, why); };
  if (c.custom) {
    TF_RETURN_IF_ERROR(ValidateInHandObject(*c.custom));
  } else {
    TF_RETURN_IF_ERROR(BuiltInInHandObject(c.object).status());
  }
  if (!(c.rate > 0) || !std::isfinite(c.rate) || c.rate > 1000)
    return bad("rate", absl::StrFormat("must be in (0, 1000] Hz, got %g", c.rate));
  if (!(c.duration > 0) || !std::isfinite(c.duration) || c.duration > 600)
    return bad("duration", absl::StrFormat("must be in (0, 600] s, got %g", c.duration));
  if (c.duration * c.rate < 10)
    return bad("duration", "duration * rate must give at least 10 samples");
  if (!c.custom_force_model) {
    TF_RETURN_IF_ERROR(NamedForceModel(c.force_model).status());
  } else {
    const TactileForceModel& m = *c.custom_force_model;
    for (double v : {m.bias_sigma, m.noise_floor, m.noise_slope, m.point_sigma})
      if (!(v >= 0) || !std::isfinite(v))
        return bad("force_model", "parameters must be finite and >= 0");
    if (!(m.bias_time > 0)) return bad("force_model", "bias_time must be > 0");
  }
  const VisionTrackerModel& v = c.vision;
  if (!(v.position_sigma >= 0 && v.orientation_sigma_deg >= 0 && v.dropout_probability >= 0 &&
        v.dropout_probability < 1 && v.dropout_max_samples >= 1))
    return bad("vision", "sigmas >= 0, dropout_probability in [0, 1), dropout_max_samples >= 1");
  if (!(c.support_fraction >= 0 && c.support_fraction <= 0.9))
    return bad("support_fraction",
               absl::StrFormat("must be in [0, 0.9], got %g", c.support_fraction));
  for (size_t i = 0; i < c.breaks.size(); ++i) {
    const ContactBreak& b = c.breaks[i];
    if (b.contact < 0 || b.contact > 3 || !(b.start >= 0) || !(b.duration > 0) ||
        !std::isfinite(b.start + b.duration))
      return FieldError(absl::StrCat("breaks[", i, "]"), "contact 0..3, start >= 0, duration > 0");
  }
  for (size_t i = 0; i < c.pushes.size(); ++i)
    if (!(c.pushes[i].start >= 0) || !(c.pushes[i].duration > 0) ||
        !c.pushes[i].force.allFinite() || c.pushes[i].force.norm() > 100)
      return FieldError(absl::StrCat("pushes[", i, "]"),
                        "start >= 0, duration > 0, |force| <= 100 N");
  if (!(c.position_scale >= 0 && c.position_scale <= 2 && c.orientation_scale >= 0 &&
        c.orientation_scale <= 1.5))
    return bad("position_scale", "position_scale in [0, 2], orientation_scale in [0, 1.5]");
  if (!(c.friction > 0 && c.plan_friction > 0 && c.plan_friction <= c.friction &&
        c.min_normal_force > 0))
    return bad("friction", "0 < plan_friction <= friction, min_normal_force > 0");
  if (!(c.control_rate >= 50 && c.control_rate <= 1000 && c.settle >= 0.1 && c.kp > 0 &&
        c.fingertip_mass > 0 && c.fingertip_radius > 0))
    return bad("control_rate",
               "control_rate in [50, 1000] Hz, settle >= 0.1 s, kp, fingertip mass/radius > 0");
  return ValidatePhysics(c.physics);
}

}  // namespace tactforce::experiment
