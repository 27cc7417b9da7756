// CauseTracker (grasp_internal.h): the failure causes of grasp.h's
// FailureCause, judged tick by tick from each fingertip's reading and true
// normal force between the settle and the first failure criterion.
#include <algorithm>
#include <cmath>

#include "grasp_internal.h"

namespace tactforce::experiment {
namespace {

constexpr double kContactForce = 0.1;       // N: below this a fingertip is not touching
constexpr double kNonActivationTime = 0.1;  // s of reading < 50 % of a rising true force
constexpr double kPhantomMargin = 0.5;      // N above the true force while not touching
constexpr double kDetachTime = 0.05;        // s without contact after touching = detached
constexpr double kOverReadMargin = 0.25;    // N, mean reading - truth of an over-reading fingertip

}  // namespace

CauseTracker::CauseTracker(int n_fingers) : fingers_(n_fingers) {}

void CauseTracker::Tick(double t, const std::vector<double>& truth,
                        const std::vector<double>& reading) {
  ++ticks_;
  for (size_t i = 0; i < fingers_.size(); ++i) {
    Finger& f = fingers_[i];
    const double fn = truth[i], r = reading[i];
    f.over_sum += r - fn;
    // Non-activation: the reading stays under half of a true force that rises.
    if (fn > kContactForce && r < 0.5 * fn) {
      if (f.low_since < 0) f.low_since = t, f.low_truth = fn;
      if (t - f.low_since > kNonActivationTime - 1e-9 && fn > f.low_truth) non_activation_ = true;
    } else {
      f.low_since = -1;
    }
    // Phantom force: reading well above a lost contact, or a detached finger.
    if (fn < kContactForce && r > fn + kPhantomMargin) phantom_ = true;
    if (fn >= kContactForce) {
      f.touched = true;
      f.off_since = -1;
    } else if (f.touched) {
      if (f.off_since < 0) f.off_since = t;
      if (t - f.off_since >= kDetachTime - 1e-9) phantom_ = true;
    }
  }
}

FailureCause CauseTracker::Label(bool failed, bool tilted) const {
  if (!failed) return FailureCause::kNone;
  if (non_activation_) return FailureCause::kNonActivation;
  if (phantom_) return FailureCause::kPhantomForce;
  double worst_over = -INFINITY;
  for (const Finger& f : fingers_)
    worst_over = std::max(worst_over, ticks_ > 0 ? f.over_sum / ticks_ : 0.0);
  if (tilted && worst_over > kOverReadMargin) return FailureCause::kOverReadingTilt;
  return FailureCause::kSlipDrop;
}

}  // namespace tactforce::experiment
