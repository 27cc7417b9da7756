// Scores a parameter vector on the measured data (not installed): runs the
// force-domain channel (sim::ApplyChannel, the simulation's own operators) on
// the reference and fits the reading's gain and offset to it in closed form.
#pragma once

#include <utility>
#include <vector>

#include "tactforce/audit/measured_data.h"
#include "tactforce/sim/sensor_model.h"

namespace tactforce::audit::internal {

// reading ~ a * channel(reference) + b, least squares on the training block.
struct AffineFit {
  double a = 0, b = 0;     // gain (reading units per N) and offset (reading units)
  double rss_train = 0;    // reading units^2, training block
  double rss_heldout = 0;  // reading units^2, held-out block (0 unless asked for)
};

// Sample index ranges [first, last) of the measured data.
using SampleRanges = std::vector<std::pair<int, int>>;

// The training and held-out samples are index ranges of `data`; the channel
// always runs from the data's first sample, so a dynamic effect's state
// (hysteresis, lag, delay) at a range's start is the one the whole recording
// leads to, not a rest state. Keeps a reference to `data`; not thread-safe
// (scratch buffers).
class ChannelEvaluator {
 public:
  // Training = the first n_train samples, held-out = the rest.
  ChannelEvaluator(const MeasuredData& data, int n_train);
  // Training and held-out = the given ranges (each in increasing order;
  // held-out may be empty).
  ChannelEvaluator(const MeasuredData& data, SampleRanges train, SampleRanges heldout);

  // Gain/offset fitted on the training samples; the held-out RSS with that
  // gain/offset too when `heldout`.
  AffineFit Evaluate(const sim::EffectParams& p, bool heldout);
  // Force-domain channel output on the training samples, in order (N; valid
  // until the next call).
  const std::vector<double>& TrainChannel(const sim::EffectParams& p);
  // Force-domain channel output on all samples (N; valid until the next call).
  const std::vector<double>& FullChannel(const sim::EffectParams& p);
  const MeasuredData& data() const { return data_; }

  int n_train() const { return n_train_; }
  int n_heldout() const { return n_heldout_; }
  const std::vector<double>& reading() const {
    return train_reading_;
  }  // the training samples', in order

 private:
  // Runs the channel over samples [0, n) into channel_.
  void Run(const sim::EffectParams& p, int n);

  const MeasuredData& data_;
  SampleRanges train_, heldout_;
  int n_train_ = 0, n_heldout_ = 0;
  int train_end_ = 0, end_ = 0;   // the channel runs up to these for training / all
  bool train_is_prefix_ = false;  // train_ == {{0, n_train_}}: TrainChannel needs no gather
  sim::ChannelInput input_;
  std::vector<double> train_reading_;
  std::vector<double> channel_, train_channel_;  // scratch
};

}  // namespace tactforce::audit::internal
