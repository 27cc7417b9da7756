// The sensing chain of an in-hand run (inhand_internal.h): the tactile force
// model (per-contact bias, heteroscedastic noise, its reported sigma), the
// contact-point noise, the vision tracker (white pose noise, dropouts that
// repeat the last pose) and the kinematic tracker (the object rigidly
// attached to fingertip 0 from the first sample; the hand's rotation from the
// fingertip centres by Kabsch).
#include <cmath>

#include <Eigen/SVD>

#include "inhand_internal.h"

namespace tactforce::experiment::inhand_internal {

Matrix3d KabschRotation(const std::array<Vector3d, kFingers>& from,
                        const std::array<Vector3d, kFingers>& to,
                        const std::array<bool, kFingers>& use) {
  Vector3d cf = Vector3d::Zero(), ct = Vector3d::Zero();
  int n = 0;
  for (int i = 0; i < kFingers; ++i)
    if (use[i]) cf += from[i], ct += to[i], ++n;
  if (n < 3) return Matrix3d::Identity();
  cf /= n, ct /= n;
  Matrix3d H = Matrix3d::Zero();
  for (int i = 0; i < kFingers; ++i)
    if (use[i]) H += (from[i] - cf) * (to[i] - ct).transpose();
  Eigen::JacobiSVD<Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3d D = Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  return svd.matrixV() * D * svd.matrixU().transpose();
}

Sensing::Sensing(const Setup& setup, uint64_t seed) : s_(setup), rng_(seed) {
  for (int i = 0; i < kFingers; ++i)
    bias_[i] = s_.force_model.bias_sigma * Vector3d(normal_(rng_), normal_(rng_), normal_(rng_));
}

void Sensing::Advance() {
  const double decay = std::exp(-1.0 / (s_.cfg.rate * s_.force_model.bias_time));
  const double kick = s_.force_model.bias_sigma * std::sqrt(1 - decay * decay);
  for (Vector3d& b : bias_)
    b = decay * b + kick * Vector3d(normal_(rng_), normal_(rng_), normal_(rng_));
}

Vector3d Sensing::ReadForce(int i, const Vector3d& f_true, double* sigma) {
  const TactileForceModel& m = s_.force_model;
  const double s = m.noise_floor + m.noise_slope * f_true.norm();
  *sigma = std::sqrt(m.bias_sigma * m.bias_sigma + s * s);
  if (s_.cfg.ideal_forces) {
    *sigma = 0;
    return f_true;
  }
  return f_true + bias_[i] + s * Vector3d(normal_(rng_), normal_(rng_), normal_(rng_));
}

Vector3d Sensing::ReadPoint(const Vector3d& x_true) {
  if (s_.cfg.ideal_forces) return x_true;
  return x_true +
         s_.force_model.point_sigma * Vector3d(normal_(rng_), normal_(rng_), normal_(rng_));
}

void Sensing::Track(int sample, const Vector3d& p_true, const Matrix3d& R_true,
                    const std::array<Vector3d, kFingers>& tips,
                    const std::array<bool, kFingers>& tip_usable, Vector3d* p, Matrix3d* R,
                    bool* dropout) {
  *dropout = false;
  if (s_.cfg.ideal_tracking) {
    *p = p_true, *R = R_true;
    return;
  }
  if (s_.cfg.tracker == Tracker::kKinematic) {
    if (!attached_) {
      attached_ = true;
      tips0_ = tips;
      anchor_offset_ = p_true - tips[0];
      R0_ = R_true;
    }
    const Matrix3d Rk = KabschRotation(tips0_, tips, tip_usable);
    *R = Rk * R0_;
    *p = tips[0] + Rk * anchor_offset_;
    return;
  }
  const VisionTrackerModel& v = s_.cfg.vision;
  if (sample > 0 && dropout_left_ == 0 &&
      std::uniform_real_distribution<double>(0, 1)(rng_) < v.dropout_probability)
    dropout_left_ = std::uniform_int_distribution<int>(1, v.dropout_max_samples)(rng_);
  if (dropout_left_ > 0) {
    --dropout_left_;
    *p = last_p_, *R = last_R_, *dropout = true;
    return;
  }
  const double so = v.orientation_sigma_deg * M_PI / 180;
  const Vector3d e = so * Vector3d(normal_(rng_), normal_(rng_), normal_(rng_));
  *p = p_true + v.position_sigma * Vector3d(normal_(rng_), normal_(rng_), normal_(rng_));
  *R = R_true *
       Eigen::AngleAxisd(e.norm(), e.norm() > 0 ? Vector3d(e.normalized()) : Vector3d::UnitX())
           .toRotationMatrix();
  last_p_ = *p, last_R_ = *R;
}

}  // namespace tactforce::experiment::inhand_internal
