// Statistics of an in-hand run (net-force spread in hand and on a wrist,
// slip, tracker error and its relation to slip, holding forces), the fit
// options a run implies, and the files a run is written as.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "inhand_internal.h"
#include "tactforce/inertia/truth.h"
#include "tactforce/io/text_file.h"
#include "tactforce/planner/trajectory.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {
namespace inhand_internal {
namespace {

// Norm of the per-axis standard deviations.
double SpreadNorm(const std::vector<Vector3d>& v) {
  if (v.size() < 2) return 0;
  Vector3d mean = Vector3d::Zero();
  for (const Vector3d& x : v) mean += x;
  mean /= v.size();
  double ss = 0;
  for (const Vector3d& x : v) ss += (x - mean).squaredNorm();
  return std::sqrt(ss / (v.size() - 1));
}

double Pearson(const std::vector<double>& a, const std::vector<double>& b) {
  const size_t n = a.size();
  if (n < 2) return 0;
  double ma = 0, mb = 0;
  for (size_t i = 0; i < n; ++i) ma += a[i], mb += b[i];
  ma /= n, mb /= n;
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < n; ++i)
    sab += (a[i] - ma) * (b[i] - mb), saa += (a[i] - ma) * (a[i] - ma),
        sbb += (b[i] - mb) * (b[i] - mb);
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : 0;
}

// The wrist F/T sensor's force (object frame) along the default arm
// excitation: noise-free, same object, duration and rate.
double WristForceSpread(const Setup& s) {
  absl::StatusOr<inertia::SimulatedObject> o =
      inertia::ObjectFromParameters(s.object.name, s.truth);
  if (!o.ok()) return 0;
  inertia::SimulationOptions opt;
  opt.custom = *o;
  opt.mode = inertia::SimulationMode::kWristWrench;
  opt.duration = s.cfg.duration;
  opt.rate_hz = s.cfg.rate;
  absl::StatusOr<inertia::SimulationResult> r = inertia::SimulateInertia(opt);
  if (!r.ok()) return 0;
  std::vector<Vector3d> f;
  for (const inertia::InertiaSample& x : r->samples.samples) f.push_back(x.force);
  return SpreadNorm(f);
}

// Net contact force the commanded motion needs (object frame), per sample.
double CommandedForceSpread(const Setup& s, const InHandRun& run) {
  planner::ObjectModel om;
  om.mass = s.truth.mass;
  om.com = s.truth.com;
  std::vector<Vector3d> f;
  for (const InHandTruthRow& row : run.truth_log) {
    const Motion m = s.MotionAt(row.t);
    const Matrix3d Rt = m.R.transpose();
    planner::TrajectoryStep step;
    step.gravity = Rt * Vector3d(0, 0, -9.81);
    step.linear_acceleration = Rt * m.a;
    step.angular_velocity = Rt * m.w;
    step.angular_acceleration = Rt * m.dw;
    f.push_back(planner::RequiredContactWrench(om, s.truth.inertia_com.Matrix(), step).force);
  }
  return SpreadNorm(f);
}

void SlipAndTrackerStats(const Setup& s, InHandRun* run) {
  InHandStats& st = run->stats;
  std::vector<double> err, slip;
  st.min_normal_force = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < run->truth_log.size(); ++k) {
    const InHandTruthRow& row = run->truth_log[k];
    double worst = 0;
    for (int i = 0; i < kFingers; ++i) {
      worst = std::max(worst, row.slip_mm[i]);
      if (row.in_contact[i] && !s.InBreak(i, row.t) && !s.InBreak(i, row.t - kBreakBlend))
        st.min_normal_force = std::min(st.min_normal_force, row.force[i].dot(s.contact_normal[i]));
    }
    st.max_slip_mm = std::max(st.max_slip_mm, worst);
    const Vector3d& e = run->tracker_error[k];
    const Matrix3d Rt = run->samples.samples[k].orientation.toRotationMatrix();
    const Eigen::AngleAxisd dR(Rt * row.orientation.toRotationMatrix().transpose());
    st.tracker_position_error_max_mm = std::max(st.tracker_position_error_max_mm, 1e3 * e.norm());
    st.tracker_rotation_error_max_deg =
        std::max(st.tracker_rotation_error_max_deg, dR.angle() * 180 / M_PI);
    err.push_back(1e3 * e.norm());
    slip.push_back(worst);
  }
  if (!std::isfinite(st.min_normal_force)) st.min_normal_force = 0;
  if (!err.empty()) st.tracker_position_error_final_mm = err.back();
  st.slip_tracker_correlation = Pearson(err, slip);
}

}  // namespace

void ComputeStats(const Setup& s, InHandRun* run) {
  InHandStats& st = run->stats;
  st.mg = s.truth.mass * 9.81;
  std::vector<Vector3d> net;
  for (const InHandTruthRow& row : run->truth_log) {
    Vector3d f = Vector3d::Zero();
    for (const Vector3d& x : row.force) f += x;
    net.push_back(f);
  }
  st.net_force_std = SpreadNorm(net);
  st.wrist_net_force_std = WristForceSpread(s);
  st.wrist_same_trajectory_net_force_std = CommandedForceSpread(s, *run);
  SlipAndTrackerStats(s, run);
}

}  // namespace inhand_internal

inertia::InertiaOptions InHandFitOptions(const InHandRun& run, inertia::InertiaMethod method) {
  inertia::InertiaOptions o;
  o.method = method;
  o.gravity = run.gravity;
  o.hull = run.hull;
  o.mesh = run.mesh;
  o.mesh_name = run.object_name;
  o.noise.position_sigma = run.tracker_position_sigma;
  o.noise.orientation_sigma = run.tracker_orientation_sigma;
  return o;
}

namespace {

std::string EventsCsv(const InHandRun& run) {
  std::string s = "t,kind,contact,detail\n";
  for (const InHandEvent& e : run.events)
    absl::StrAppend(&s, absl::StrFormat("%.6f,%s,%d,%s\n", e.t, e.kind, e.contact, e.detail));
  return s;
}

std::string TruthLogCsv(const InHandRun& run) {
  std::string s = "t,px,py,pz,qw,qx,qy,qz";
  for (int i = 0; i < inhand_internal::kFingers; ++i)
    absl::StrAppend(
        &s, absl::StrFormat(",c%d_px,c%d_py,c%d_pz,c%d_fx,c%d_fy,c%d_fz,c%d_slip_mm,c%d_on", i, i,
                            i, i, i, i, i, i));
  s += "\n";
  for (const InHandTruthRow& r : run.truth_log) {
    const Eigen::Quaterniond& q = r.orientation;
    absl::StrAppend(&s,
                    absl::StrFormat("%.6f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", r.t, r.position.x(),
                                    r.position.y(), r.position.z(), q.w(), q.x(), q.y(), q.z()));
    for (size_t i = 0; i < r.force.size(); ++i)
      absl::StrAppend(
          &s, absl::StrFormat(",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%d", r.point[i].x(),
                              r.point[i].y(), r.point[i].z(), r.force[i].x(), r.force[i].y(),
                              r.force[i].z(), r.slip_mm[i], r.in_contact[i] ? 1 : 0));
    s += "\n";
  }
  return s;
}

std::string MeshObj(const io::TriangleMesh& mesh, const std::string& name) {
  std::string s = absl::StrCat("# tactforce experiment inhand: ", name, " (object frame, m)\n");
  for (const auto& v : mesh.vertices)
    absl::StrAppend(&s, absl::StrFormat("v %.9g %.9g %.9g\n", v.x(), v.y(), v.z()));
  for (const auto& t : mesh.triangles)
    absl::StrAppend(&s, "f ", t[0] + 1, " ", t[1] + 1, " ", t[2] + 1, "\n");
  return s;
}

}  // namespace

absl::Status WriteInHandRun(const InHandRun& run, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    return absl::InvalidArgumentError(absl::StrCat("out: cannot create ", dir, ": ", ec.message()));
  const std::filesystem::path d(dir);
  inertia::InertiaTruth truth;
  truth.params = run.truth;
  truth.gravity_world = run.gravity;
  TF_RETURN_IF_ERROR(inertia::WriteInertiaCsvFile(run.samples, (d / "inertia.csv").string()));
  TF_RETURN_IF_ERROR(inertia::WriteTruthJsonFile(truth, (d / "truth.json").string()));
  TF_RETURN_IF_ERROR(io::WriteTextFile((d / "events.csv").string(), EventsCsv(run)));
  TF_RETURN_IF_ERROR(io::WriteTextFile((d / "truth_log.csv").string(), TruthLogCsv(run)));
  if (run.mesh)
    return io::WriteTextFile((d / "mesh.obj").string(), MeshObj(*run.mesh, run.object_name));
  return absl::OkStatus();
}

}  // namespace tactforce::experiment
