// The generalised least squares shared by CONSTRAINED and DENSITY (not
// installed): the samples' regressors, wrenches and wrench covariances, the
// whitened normal equations at an estimate with their errors-in-variables
// bias, and the bias correction.
#pragma once

#include <string>
#include <vector>

#include "internal.h"

namespace tactforce::inertia::internal {

// Generalised least squares data shared by CONSTRAINED and DENSITY: the
// smoothed kinematics, regressors, wrenches and wrench covariances of the
// samples that give an equation.
struct GlsData {
  std::vector<KinPoint> kin;
  std::vector<Vector6d> wrench;
  std::vector<Matrix6d> wcov;
  std::vector<Matrix6x10> Y;
  bool known = true;                // wrench noise given (else estimated from residuals)
  double floor_f = 0, floor_t = 0;  // variance floors (noise-free data)
  Matrix10d YtY = Matrix10d::Zero();
  Vector10d Ytb = Vector10d::Zero();
};
GlsData PrepareGls(const InertiaSamples& s, const InertiaOptions& o,
                   std::vector<std::string>* notes, InterruptPoll* poll);

// Normal equations of the whitened problem at the estimate pi: A = sum
// (WY)^T WY, b = sum (WY)^T W w, c = sum |W w|^2, and the first-order
// errors-in-variables bias E[dY^T W dY].
struct GlsSums {
  Matrix10d A = Matrix10d::Zero();
  Matrix10d bias = Matrix10d::Zero();
  Vector10d b = Vector10d::Zero();
  double c = 0;
  int count = 0;
};
// Totals, and optionally per contiguous block of samples (`blocks` >= 1)
// and the whitening matrices W (W^T W = C^-1) per sample.
void AccumulateGls(const GlsData& d, const Vector10d& pi, InterruptPoll* poll, GlsSums* total,
                   int blocks = 1, std::vector<GlsSums>* per_block = nullptr,
                   std::vector<Matrix6d>* whiteners = nullptr);
// Block of sample k when the samples are cut into `blocks` contiguous blocks.
inline int BlockOf(int k, int n, int blocks) {
  return static_cast<int>((static_cast<long>(k) * blocks) / n);
}
// A - bias when the corrected matrix stays well positive definite (its
// smallest scaled eigenvalue above half of A's), else A.
Matrix10d BiasCorrected(const GlsSums& sums, const Vector10d& scale, bool* applied);

}  // namespace tactforce::inertia::internal
