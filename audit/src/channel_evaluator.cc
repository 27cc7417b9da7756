// Scoring of one parameter vector: the channel output g on the reference and
// the closed-form least-squares gain/offset of the reading on g over the
// training block (sums of g, y, g^2, g*y, y^2), with the held-out RSS at that
// gain/offset when asked. Every fit of the audit calls this in its inner loop.
#include "channel_evaluator.h"

#include <algorithm>

namespace tactforce::audit::internal {

ChannelEvaluator::ChannelEvaluator(const MeasuredData& data, int n_train) : data_(data), n_train_(n_train) {
  input_.t = data.t.data();
  input_.force = data.reference.data();
  input_.shear = data.shear.empty() ? nullptr : data.shear.data();
  input_.segment_starts = &data.segment_starts;
  input_.t0 = data.t.front();
}

AffineFit ChannelEvaluator::Evaluate(const sim::EffectParams& p, bool heldout) {
  sim::ChannelInput in = input_;
  in.n = heldout ? static_cast<int>(data_.t.size()) : n_train_;
  sim::ApplyChannel(p, in, &channel_);
  double sg = 0, sy = 0, sgg = 0, sgy = 0, syy = 0;
  const double* y = data_.reading.data();
  for (int i = 0; i < n_train_; ++i) {
    const double g = channel_[i];
    sg += g;
    sy += y[i];
    sgg += g * g;
    sgy += g * y[i];
    syy += y[i] * y[i];
  }
  const double n = n_train_;
  const double vg = sgg - sg * sg / n;
  const double cgy = sgy - sg * sy / n;
  const double vy = syy - sy * sy / n;
  AffineFit ev;
  if (vg > 1e-12 * std::max(1.0, sgg)) {
    ev.a = cgy / vg;
    ev.b = (sy - ev.a * sg) / n;
    ev.rss_train = std::max(0.0, vy - cgy * cgy / vg);
  } else {
    ev.a = 0;
    ev.b = sy / n;
    ev.rss_train = std::max(0.0, vy);
  }
  if (heldout) {
    double r = 0;
    for (size_t i = n_train_; i < data_.t.size(); ++i) {
      const double e = y[i] - ev.a * channel_[i] - ev.b;
      r += e * e;
    }
    ev.rss_heldout = r;
  }
  return ev;
}

const std::vector<double>& ChannelEvaluator::TrainChannel(const sim::EffectParams& p) {
  sim::ChannelInput in = input_;
  in.n = n_train_;
  sim::ApplyChannel(p, in, &channel_);
  return channel_;
}

const std::vector<double>& ChannelEvaluator::FullChannel(const sim::EffectParams& p) {
  sim::ChannelInput in = input_;
  in.n = static_cast<int>(data_.t.size());
  sim::ApplyChannel(p, in, &channel_);
  return channel_;
}

}  // namespace tactforce::audit::internal
