// Scoring of one parameter vector: the channel output g on the reference and
// the closed-form least-squares gain/offset of the reading on g over the
// training samples (sums of g, y, g^2, g*y, y^2), with the held-out RSS at
// that gain/offset when asked. Every fit of the audit calls this in its inner
// loop.
#include "channel_evaluator.h"

#include <algorithm>

namespace tactforce::audit::internal {

ChannelEvaluator::ChannelEvaluator(const MeasuredData& data, int n_train)
    : ChannelEvaluator(data, {{0, n_train}},
                       SampleRanges{{n_train, static_cast<int>(data.t.size())}}) {}

ChannelEvaluator::ChannelEvaluator(const MeasuredData& data, SampleRanges train,
                                   SampleRanges heldout)
    : data_(data), train_(std::move(train)), heldout_(std::move(heldout)) {
  for (const auto& [first, last] : train_) {
    n_train_ += last - first;
    train_end_ = std::max(train_end_, last);
    train_reading_.insert(train_reading_.end(), data.reading.begin() + first,
                          data.reading.begin() + last);
  }
  end_ = train_end_;
  for (const auto& [first, last] : heldout_) {
    n_heldout_ += last - first;
    end_ = std::max(end_, last);
  }
  train_is_prefix_ = train_.size() == 1 && train_[0].first == 0;
  input_.t = data.t.data();
  input_.force = data.reference.data();
  input_.shear = data.shear.empty() ? nullptr : data.shear.data();
  input_.segment_starts = &data.segment_starts;
  input_.t0 = data.t.front();
}

void ChannelEvaluator::Run(const sim::EffectParams& p, int n) {
  sim::ChannelInput in = input_;
  in.n = n;
  sim::ApplyChannel(p, in, &channel_);
}

AffineFit ChannelEvaluator::Evaluate(const sim::EffectParams& p, bool heldout) {
  Run(p, heldout ? end_ : train_end_);
  double sg = 0, sy = 0, sgg = 0, sgy = 0, syy = 0;
  const double* y = data_.reading.data();
  for (const auto& [first, last] : train_)
    for (int i = first; i < last; ++i) {
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
    for (const auto& [first, last] : heldout_)
      for (int i = first; i < last; ++i) {
        const double e = y[i] - ev.a * channel_[i] - ev.b;
        r += e * e;
      }
    ev.rss_heldout = r;
  }
  return ev;
}

const std::vector<double>& ChannelEvaluator::TrainChannel(const sim::EffectParams& p) {
  Run(p, train_end_);
  if (train_is_prefix_) return channel_;
  train_channel_.clear();
  for (const auto& [first, last] : train_)
    train_channel_.insert(train_channel_.end(), channel_.begin() + first, channel_.begin() + last);
  return train_channel_;
}

const std::vector<double>& ChannelEvaluator::FullChannel(const sim::EffectParams& p) {
  Run(p, static_cast<int>(data_.t.size()));
  return channel_;
}

}  // namespace tactforce::audit::internal
