// The inertia CSV (samples.h): which force source and which optional
// columns a table holds, one InertiaSample per row, the checks every sample
// must pass (errors name the file, line and column, or the struct field) and
// the writer of the same format.
#include "tactforce/inertia/samples.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <set>
#include <string_view>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/io/text_file.h"
#include "tactforce/planner/validation.h"
#include "internal.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::inertia {
namespace {

constexpr double kMinQuaternionNorm = 1e-3;

const std::vector<std::string> kPoseColumns = {"t", "px", "py", "pz", "qw", "qx", "qy", "qz"};
const std::vector<std::string> kWrenchColumns = {"fx", "fy", "fz", "tx", "ty", "tz"};
const std::vector<std::string> kKinematicsRequired = {"wx",  "wy", "wz", "dwx", "dwy",
                                                      "dwz", "ax", "ay", "az"};
const std::vector<std::string> kVelocityColumns = {"vx", "vy", "vz"};

std::vector<std::string> ContactColumns(int i) {
  std::vector<std::string> out;
  for (const char* s : {"px", "py", "pz", "fx", "fy", "fz"})
    out.push_back(absl::StrCat("c", i, "_", s));
  return out;
}

// Location of sample i for messages.
struct Locator {
  const InertiaSamples& s;
  std::string Sample(int i) const {
    if (i < static_cast<int>(s.line_numbers.size()))
      return absl::StrCat(s.source_name, ":", s.line_numbers[i]);
    return absl::StrCat(s.source_name.empty() ? "" : s.source_name + ": ", "samples[", i, "]");
  }
  bool csv() const { return !s.line_numbers.empty(); }
  // field: CSV column names, or the struct path.
  std::string At(int i, const std::string& csv_columns, const std::string& field) const {
    if (csv())
      return absl::StrCat(Sample(i), ": column",
                          csv_columns.find(',') == std::string::npos ? " '" : "s '", csv_columns,
                          "'");
    return absl::StrCat(Sample(i), ".", field);
  }
};

bool Finite(const Vec3& v) { return v.allFinite(); }

std::string Fmt(double v) { return absl::StrFormat("%.6g", v); }

// A finite value past planner/validation.h's limit for its kind: named, so
// that no fit runs on numbers whose products overflow.
template <typename Value>
absl::Status CheckBounded(const Locator& loc, int i, std::string_view csv_columns,
                          std::string_view field, const Value& v, double limit, const char* unit) {
  if (planner::IsBounded(v, limit)) return absl::OkStatus();
  return planner::MagnitudeError(loc.At(i, std::string(csv_columns), std::string(field)), v, limit,
                                 unit);
}

// Time, position and orientation of sample i.
absl::Status ValidatePose(const Locator& loc, const InertiaSamples& s, int i) {
  const InertiaSample& x = s.samples[i];
  if (!std::isfinite(x.t))
    return absl::InvalidArgumentError(absl::StrCat(loc.At(i, "t", "t"), ": not finite"));
  if (i > 0 && !(x.t > s.samples[i - 1].t)) {
    return absl::InvalidArgumentError(absl::StrCat(
        loc.At(i, "t", "t"), ": time ", Fmt(x.t),
        x.t == s.samples[i - 1].t ? " duplicates" : " is before", " the previous sample's ",
        Fmt(s.samples[i - 1].t), " (times must be strictly increasing)"));
  }
  // Poses are differentiated over time: a step below the resolution is noise.
  const double* previous = i > 0 ? &s.samples[i - 1].t : nullptr;
  if (!planner::IsBounded(x.t, planner::kMaxTime) ||
      (previous && x.t - *previous < planner::kMinTimeStep))
    return planner::CheckTime(loc.At(i, "t", "t"), x.t, previous);
  if (!Finite(x.position))
    return absl::InvalidArgumentError(
        absl::StrCat(loc.At(i, "px,py,pz", "position"), ": not finite"));
  TF_RETURN_IF_ERROR(
      CheckBounded(loc, i, "px,py,pz", "position", x.position, planner::kMaxLength, "m"));
  const double qn = x.orientation.coeffs().norm();
  if (!std::isfinite(qn))
    return absl::InvalidArgumentError(
        absl::StrCat(loc.At(i, "qw,qx,qy,qz", "orientation"), ": not finite"));
  if (qn < kMinQuaternionNorm) {
    return absl::InvalidArgumentError(absl::StrCat(loc.At(i, "qw,qx,qy,qz", "orientation"),
                                                   ": quaternion norm ", Fmt(qn),
                                                   " is near zero (not a rotation)"));
  }
  return absl::OkStatus();
}

// The wrench of sample i and its sigmas.
absl::Status ValidateWrench(const Locator& loc, const InertiaSample& x, int i) {
  if (!Finite(x.force))
    return absl::InvalidArgumentError(
        absl::StrCat(loc.At(i, "fx,fy,fz", "wrench.force"), ": not finite"));
  if (!Finite(x.torque))
    return absl::InvalidArgumentError(
        absl::StrCat(loc.At(i, "tx,ty,tz", "wrench.torque"), ": not finite"));
  if (!(x.force_sigma >= 0) || !std::isfinite(x.force_sigma))
    return absl::InvalidArgumentError(
        absl::StrCat(loc.At(i, "f_sigma", "force_sigma"), ": must be finite and >= 0"));
  if (!(x.torque_sigma >= 0) || !std::isfinite(x.torque_sigma))
    return absl::InvalidArgumentError(
        absl::StrCat(loc.At(i, "t_sigma", "torque_sigma"), ": must be finite and >= 0"));
  for (auto st :
       {CheckBounded(loc, i, "fx,fy,fz", "wrench.force", x.force, planner::kMaxForce, "N"),
        CheckBounded(loc, i, "tx,ty,tz", "wrench.torque", x.torque, planner::kMaxForce, "N m"),
        CheckBounded(loc, i, "f_sigma", "force_sigma", x.force_sigma, planner::kMaxForce, "N"),
        CheckBounded(loc, i, "t_sigma", "torque_sigma", x.torque_sigma, planner::kMaxForce, "N m")})
    TF_RETURN_IF_ERROR(st);
  return absl::OkStatus();
}

// The contact readings of sample i: the same contact set as every sample.
absl::Status ValidateContacts(const Locator& loc, const InertiaSamples& s, int i) {
  const InertiaSample& x = s.samples[i];
  if (static_cast<int>(x.contacts.size()) != s.num_contacts) {
    return absl::InvalidArgumentError(absl::StrCat(loc.Sample(i), ": ", x.contacts.size(),
                                                   " contacts, expected ", s.num_contacts,
                                                   " (the same contact set in every sample)"));
  }
  for (int c = 0; c < s.num_contacts; ++c) {
    const ContactReading& r = x.contacts[c];
    const std::string pfx = absl::StrCat("c", c, "_");
    if (!Finite(r.point))
      return absl::InvalidArgumentError(
          absl::StrCat(loc.At(i, absl::StrCat(pfx, "px,", pfx, "py,", pfx, "pz"),
                              absl::StrCat("contacts[", c, "].point")),
                       ": not finite"));
    if (!Finite(r.force))
      return absl::InvalidArgumentError(
          absl::StrCat(loc.At(i, absl::StrCat(pfx, "fx,", pfx, "fy,", pfx, "fz"),
                              absl::StrCat("contacts[", c, "].force")),
                       ": not finite"));
    if (!(r.sigma >= 0) || !std::isfinite(r.sigma))
      return absl::InvalidArgumentError(absl::StrCat(
          loc.At(i, absl::StrCat(pfx, "sigma"), absl::StrCat("contacts[", c, "].sigma")),
          ": must be finite and >= 0"));
    if (!planner::IsBounded(r.point, planner::kMaxLength) ||
        !planner::IsBounded(r.force, planner::kMaxForce) ||
        !planner::IsBounded(r.sigma, planner::kMaxForce)) {
      for (auto st :
           {CheckBounded(loc, i, absl::StrCat(pfx, "px,", pfx, "py,", pfx, "pz"),
                         absl::StrCat("contacts[", c, "].point"), r.point, planner::kMaxLength,
                         "m"),
            CheckBounded(loc, i, absl::StrCat(pfx, "fx,", pfx, "fy,", pfx, "fz"),
                         absl::StrCat("contacts[", c, "].force"), r.force, planner::kMaxForce, "N"),
            CheckBounded(loc, i, absl::StrCat(pfx, "sigma"),
                         absl::StrCat("contacts[", c, "].sigma"), r.sigma, planner::kMaxForce,
                         "N")})
        TF_RETURN_IF_ERROR(st);
    }
  }
  return absl::OkStatus();
}

// Measured kinematics of sample i: present in all samples or none, finite.
absl::Status ValidateKinematics(const Locator& loc, const InertiaSample& x, int i, bool expected) {
  if (x.kinematics.has_value() != expected) {
    return absl::InvalidArgumentError(absl::StrCat(
        loc.Sample(i), ": measured kinematics must be given for all samples or for none"));
  }
  if (!expected) return absl::OkStatus();
  const MeasuredKinematics& k = *x.kinematics;
  struct Field {
    const char* names;
    const Vec3* value;
    double limit;
    const char* unit;
  };
  const Field fields[] = {
      {"wx,wy,wz|angular_velocity", &k.angular_velocity, planner::kMaxAngularVelocity, "rad/s"},
      {"vx,vy,vz|velocity", &k.velocity, planner::kMaxVelocity, "m/s"},
      {"dwx,dwy,dwz|angular_acceleration", &k.angular_acceleration,
       planner::kMaxAngularAcceleration, "rad/s^2"},
      {"ax,ay,az|acceleration", &k.acceleration, planner::kMaxAcceleration, "m/s^2"}};
  for (const Field& f : fields) {
    if (!planner::IsBounded(*f.value, f.limit)) {
      const std::string both(f.names);
      const size_t bar = both.find('|');
      const std::string where =
          loc.At(i, both.substr(0, bar), "kinematics." + both.substr(bar + 1));
      if (!Finite(*f.value)) return absl::InvalidArgumentError(absl::StrCat(where, ": not finite"));
      return planner::MagnitudeError(where, *f.value, f.limit, f.unit);
    }
  }
  return absl::OkStatus();
}

// Contact columns c0_.. up to c9999_.. (far beyond any hand).
constexpr int kMaxContactColumn = 9999;

// The force source from the columns: wrench columns or contact columns
// c0_.. c{n-1}_.., not both; sets out->source and out->num_contacts.
absl::Status DetectForceSource(const io::CsvTable& table, InertiaSamples* out) {
  const std::string& src = table.source;
  std::set<int> contact_ids;
  for (const std::string& c : table.columns) {
    if (c.size() > 1 && c[0] == 'c' && std::isdigit(static_cast<unsigned char>(c[1]))) {
      const size_t us = c.find('_');
      if (us == std::string::npos) continue;
      bool digits = true;
      for (size_t k = 1; k < us; ++k)
        digits = digits && std::isdigit(static_cast<unsigned char>(c[k]));
      if (!digits) continue;
      int id = 0;
      // Found by the csv fuzzer: std::stoi threw on c99999999999_px.
      if (!absl::SimpleAtoi(c.substr(1, us - 1), &id) || id > kMaxContactColumn) {
        return absl::InvalidArgumentError(absl::StrCat(
            src, ": column '", c, "': contact index out of range (0..", kMaxContactColumn, ")"));
      }
      contact_ids.insert(id);
    }
  }
  bool any_wrench = false;
  for (const auto& c : kWrenchColumns) any_wrench = any_wrench || table.Has(c);
  if (any_wrench && !contact_ids.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat(src, ": both wrench columns (fx..tz) and contact columns (c",
                     *contact_ids.begin(), "_...) are present; give one force source"));
  }
  if (any_wrench) {
    TF_RETURN_IF_ERROR(table.Require(kWrenchColumns));
    out->source = ForceSource::kWrench;
    return absl::OkStatus();
  }
  if (contact_ids.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(
        src,
        ": missing force columns: need fx,fy,fz,tx,ty,tz (wrench) or c0_px..c0_fz (contacts)"));
  }
  out->source = ForceSource::kContacts;
  const int n = *contact_ids.rbegin() + 1;
  for (int i = 0; i < n; ++i) {
    if (!contact_ids.count(i)) {
      return absl::InvalidArgumentError(absl::StrCat(
          src, ": inconsistent contact columns: contact ", i, " has no columns but contact ",
          *contact_ids.rbegin(), " does (contacts must be numbered 0..n-1)"));
    }
    std::vector<std::string> missing;
    for (const auto& c : ContactColumns(i))
      if (!table.Has(c)) missing.push_back(c);
    if (!missing.empty()) {
      return absl::InvalidArgumentError(
          absl::StrCat(src, ": inconsistent contact columns: contact ", i, ": missing column(s) ",
                       absl::StrJoin(missing, ", ")));
    }
  }
  out->num_contacts = n;
  return absl::OkStatus();
}

// Measured kinematics: any of the columns present -> the required set, and
// the velocity either complete or absent.
struct KinematicsColumns {
  bool present = false;
  bool velocity = false;
};

absl::StatusOr<KinematicsColumns> DetectKinematics(const io::CsvTable& table) {
  const std::string& src = table.source;
  KinematicsColumns k;
  for (const auto& c : kKinematicsRequired) k.present = k.present || table.Has(c);
  for (const auto& c : kVelocityColumns) k.present = k.present || table.Has(c);
  if (!k.present) return k;
  std::vector<std::string> missing;
  for (const auto& c : kKinematicsRequired)
    if (!table.Has(c)) missing.push_back(c);
  if (!missing.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(
        src, ": incomplete measured kinematics: missing column(s) ", absl::StrJoin(missing, ", "),
        " (give wx..wz, dwx..dwz, ax..az, optionally vx..vz, or none of them)"));
  }
  int nv = 0;
  for (const auto& c : kVelocityColumns) nv += table.Has(c);
  if (nv != 0 && nv != 3) {
    std::vector<std::string> m;
    for (const auto& c : kVelocityColumns)
      if (!table.Has(c)) m.push_back(c);
    return absl::InvalidArgumentError(
        absl::StrCat(src, ": incomplete velocity: missing column(s) ", absl::StrJoin(m, ", ")));
  }
  k.velocity = nv == 3;
  return k;
}

// Column indices of every field a row fills (-1: absent).
struct RowLayout {
  int t = -1;
  int p[3], q[4];
  int wrench[6] = {-1, -1, -1, -1, -1, -1};
  int force_sigma = -1, torque_sigma = -1;
  std::vector<std::array<int, 7>> contacts;  // point, force, sigma
  std::array<int, 3> w, v, dw, a;
  KinematicsColumns kinematics;
};

RowLayout LayoutRows(const io::CsvTable& table, const InertiaSamples& out,
                     const KinematicsColumns& kin) {
  auto col = [&](const std::string& name) { return table.ColumnIndex(name); };
  RowLayout l;
  l.t = col("t");
  for (int k = 0; k < 3; ++k) l.p[k] = col(kPoseColumns[1 + k]);
  for (int k = 0; k < 4; ++k) l.q[k] = col(kPoseColumns[4 + k]);
  for (int k = 0; k < 6 && out.source == ForceSource::kWrench; ++k)
    l.wrench[k] = col(kWrenchColumns[k]);
  l.force_sigma = col("f_sigma"), l.torque_sigma = col("t_sigma");
  for (int i = 0; i < out.num_contacts; ++i) {
    std::array<int, 7> a;
    const auto names = ContactColumns(i);
    for (int k = 0; k < 6; ++k) a[k] = col(names[k]);
    a[6] = col(absl::StrCat("c", i, "_sigma"));
    l.contacts.push_back(a);
  }
  auto kc = [&](const char* a, const char* b, const char* c) {
    return std::array<int, 3>{col(a), col(b), col(c)};
  };
  l.w = kc("wx", "wy", "wz"), l.v = kc("vx", "vy", "vz"), l.dw = kc("dwx", "dwy", "dwz"),
  l.a = kc("ax", "ay", "az");
  l.kinematics = kin;
  return l;
}

InertiaSample ReadRow(const std::vector<double>& row, const RowLayout& l, ForceSource source) {
  auto v3 = [&](const int* idx) { return Vec3(row[idx[0]], row[idx[1]], row[idx[2]]); };
  InertiaSample s;
  s.t = row[l.t];
  s.position = v3(l.p);
  s.orientation = Eigen::Quaterniond(row[l.q[0]], row[l.q[1]], row[l.q[2]], row[l.q[3]]);
  if (source == ForceSource::kWrench) {
    s.force = v3(l.wrench);
    s.torque = v3(l.wrench + 3);
    if (l.force_sigma >= 0) s.force_sigma = row[l.force_sigma];
    if (l.torque_sigma >= 0) s.torque_sigma = row[l.torque_sigma];
  } else {
    for (const auto& a : l.contacts) {
      ContactReading c;
      c.point = v3(a.data());
      c.force = v3(a.data() + 3);
      if (a[6] >= 0) c.sigma = row[a[6]];
      s.contacts.push_back(c);
    }
  }
  if (l.kinematics.present) {
    MeasuredKinematics k;
    k.angular_velocity = v3(l.w.data());
    if (l.kinematics.velocity) k.velocity = v3(l.v.data());
    k.angular_acceleration = v3(l.dw.data());
    k.acceleration = v3(l.a.data());
    s.kinematics = k;
  }
  return s;
}

// NaN cells: io::ParseCsv normally rejects them; a table built otherwise may hold them.
absl::Status RejectNan(const io::CsvTable& table) {
  for (size_t r = 0; r < table.rows.size(); ++r) {
    for (size_t c = 0; c < table.rows[r].size(); ++c) {
      if (std::isnan(table.rows[r][c])) {
        return absl::InvalidArgumentError(absl::StrCat(table.source, ":", table.line_numbers[r],
                                                       ": column '", table.columns[c], "': NaN"));
      }
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status ValidateInertiaSamples(const InertiaSamples& s) {
  internal::InterruptPoll never(nullptr);
  return internal::ValidateInertiaSamples(s, &never);
}

void NormalizeOrientations(InertiaSamples& s) {
  for (InertiaSample& x : s.samples) x.orientation.normalize();
}

namespace internal {

absl::Status ValidateInertiaSamples(const InertiaSamples& s, InterruptPoll* poll,
                                    InertiaSamples* normalized) {
  const Locator loc{s};
  const std::string src = s.source_name.empty() ? "samples" : s.source_name;
  if (s.source == ForceSource::kContacts && s.num_contacts < 1)
    return absl::InvalidArgumentError(absl::StrCat(src, ": contact source with no contacts"));
  if (normalized != nullptr) {
    normalized->source = s.source;
    normalized->num_contacts = s.num_contacts;
    normalized->source_name = s.source_name;
    normalized->line_numbers = s.line_numbers;
    normalized->samples.clear();
    normalized->samples.reserve(s.samples.size());
  }
  const bool kin = s.HasKinematics();
  for (int i = 0; i < static_cast<int>(s.samples.size()); ++i) {
    if (poll->Tick()) return Interrupted();
    const InertiaSample& x = s.samples[i];
    TF_RETURN_IF_ERROR(ValidatePose(loc, s, i));
    TF_RETURN_IF_ERROR(s.source == ForceSource::kWrench ? ValidateWrench(loc, x, i)
                                                        : ValidateContacts(loc, s, i));
    TF_RETURN_IF_ERROR(ValidateKinematics(loc, x, i, kin));
    if (normalized != nullptr) {
      normalized->samples.push_back(x);
      normalized->samples.back().orientation.normalize();
    }
  }
  return absl::OkStatus();
}

}  // namespace internal

absl::StatusOr<InertiaSamples> InertiaSamplesFromCsv(const io::CsvTable& table) {
  const std::string& src = table.source;
  TF_RETURN_IF_ERROR(table.Require(kPoseColumns));
  InertiaSamples out;
  out.source_name = src;
  TF_RETURN_IF_ERROR(DetectForceSource(table, &out));
  TF_ASSIGN_OR_RETURN(KinematicsColumns kin, DetectKinematics(table));
  const RowLayout layout = LayoutRows(table, out, kin);
  out.samples.reserve(table.rows.size());
  out.line_numbers = table.line_numbers;
  for (const std::vector<double>& row : table.rows)
    out.samples.push_back(ReadRow(row, layout, out.source));
  TF_RETURN_IF_ERROR(RejectNan(table));
  TF_RETURN_IF_ERROR(ValidateInertiaSamples(out));
  const int need = MinimumSamples(out, InertiaMethod::kBaselineLs);  // the least of the methods
  if (static_cast<int>(out.samples.size()) < need) {
    return absl::InvalidArgumentError(
        absl::StrCat(src, ": ", out.samples.size(), " sample(s), at least ", need,
                     " needed for the 10 inertial parameters (6 equations per sample",
                     out.HasKinematics() ? "" : ", after differentiating the poses", ")"));
  }
  NormalizeOrientations(out);
  return out;
}

absl::StatusOr<InertiaSamples> ParseInertiaCsv(const std::string& text, const std::string& source) {
  TF_ASSIGN_OR_RETURN(io::CsvTable t, io::ParseCsv(text, source));
  return InertiaSamplesFromCsv(t);
}

absl::StatusOr<InertiaSamples> ReadInertiaCsvFile(const std::string& path) {
  TF_ASSIGN_OR_RETURN(io::CsvTable t, io::ReadCsvFile(path));
  return InertiaSamplesFromCsv(t);
}

std::string InertiaSamplesToCsv(const InertiaSamples& s) {
  std::vector<std::string> cols = kPoseColumns;
  if (s.source == ForceSource::kWrench) {
    cols.insert(cols.end(), kWrenchColumns.begin(), kWrenchColumns.end());
  } else {
    for (int i = 0; i < s.num_contacts; ++i) {
      auto c = ContactColumns(i);
      cols.insert(cols.end(), c.begin(), c.end());
    }
  }
  bool has_sigma = false;
  for (const auto& x : s.samples) {
    has_sigma = has_sigma || x.force_sigma > 0 || x.torque_sigma > 0;
    for (const auto& c : x.contacts) has_sigma = has_sigma || c.sigma > 0;
  }
  if (has_sigma) {
    if (s.source == ForceSource::kWrench) {
      cols.push_back("f_sigma");
      cols.push_back("t_sigma");
    } else {
      for (int i = 0; i < s.num_contacts; ++i) cols.push_back(absl::StrCat("c", i, "_sigma"));
    }
  }
  const bool kin = s.HasKinematics();
  if (kin) {
    for (const char* c :
         {"wx", "wy", "wz", "vx", "vy", "vz", "dwx", "dwy", "dwz", "ax", "ay", "az"})
      cols.push_back(c);
  }
  std::string out = absl::StrJoin(cols, ",") + "\n";
  char buf[32];
  auto add = [&](double v) {
    std::snprintf(buf, sizeof(buf), "%.17g", v);
    out += ',';
    out += buf;
  };
  for (const auto& x : s.samples) {
    std::snprintf(buf, sizeof(buf), "%.17g", x.t);
    out += buf;
    for (int k = 0; k < 3; ++k) add(x.position(k));
    add(x.orientation.w());
    add(x.orientation.x());
    add(x.orientation.y());
    add(x.orientation.z());
    if (s.source == ForceSource::kWrench) {
      for (int k = 0; k < 3; ++k) add(x.force(k));
      for (int k = 0; k < 3; ++k) add(x.torque(k));
    } else {
      for (const auto& c : x.contacts) {
        for (int k = 0; k < 3; ++k) add(c.point(k));
        for (int k = 0; k < 3; ++k) add(c.force(k));
      }
    }
    if (has_sigma) {
      if (s.source == ForceSource::kWrench) {
        add(x.force_sigma);
        add(x.torque_sigma);
      } else {
        for (const auto& c : x.contacts) add(c.sigma);
      }
    }
    if (kin) {
      const MeasuredKinematics& k = *x.kinematics;
      for (const Vec3* v :
           {&k.angular_velocity, &k.velocity, &k.angular_acceleration, &k.acceleration})
        for (int j = 0; j < 3; ++j) add((*v)(j));
    }
    out += '\n';
  }
  return out;
}

absl::Status WriteInertiaCsvFile(const InertiaSamples& samples, const std::string& path) {
  return io::WriteTextFile(path, InertiaSamplesToCsv(samples));
}

}  // namespace tactforce::inertia
