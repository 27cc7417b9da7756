// Scores a parameter vector on the measured data (not installed): runs the
// force-domain channel (sim::ApplyChannel, the simulation's own operators) on
// the reference and fits the reading's gain and offset to it in closed form.
#pragma once

#include <vector>

#include "tactforce/audit/measured_data.h"
#include "tactforce/sim/sensor_model.h"

namespace tactforce::audit::internal {

// reading ~ a * channel(reference) + b, least squares on the training block.
struct AffineFit {
  double a = 0, b = 0;  // gain (reading units per N) and offset (reading units)
  double rss_train = 0;    // reading units^2, training block
  double rss_heldout = 0;  // reading units^2, held-out block (0 unless asked for)
};

// The first n_train samples of `data` are the training block, the rest the
// held-out block. Keeps a reference to `data`; not thread-safe (one scratch
// buffer).
class ChannelEvaluator {
 public:
  ChannelEvaluator(const MeasuredData& data, int n_train);

  // Gain/offset fitted on the training block; the held-out RSS with that
  // gain/offset too when `heldout` (the channel then runs over all samples).
  AffineFit Evaluate(const sim::EffectParams& p, bool heldout);
  // Force-domain channel output on the training block (N; valid until the
  // next call).
  const std::vector<double>& TrainChannel(const sim::EffectParams& p);
  // Force-domain channel output on all samples (N; valid until the next call).
  const std::vector<double>& FullChannel(const sim::EffectParams& p);
  const MeasuredData& data() const { return data_; }

  int n_train() const { return n_train_; }
  int n_heldout() const { return static_cast<int>(data_.t.size()) - n_train_; }
  const std::vector<double>& reading() const { return data_.reading; }  // the first n_train() are training

 private:
  const MeasuredData& data_;
  int n_train_;
  sim::ChannelInput input_;
  std::vector<double> channel_;  // scratch: the last channel output
};

}  // namespace tactforce::audit::internal
