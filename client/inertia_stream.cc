// FitInertiaMessages (inertia_stream.h): the FitInertia request stream, one
// message at a time.
#include "inertia_stream.h"

#include <algorithm>

#include "tactforce/api/inertia.h"

namespace tactforce::cli {

FitInertiaMessages::FitInertiaMessages(const inertia::InertiaSamples& samples,
                                       const v1::InertiaFitOptions& options, size_t batch)
    : samples_(samples), options_(options), batch_(std::max<size_t>(batch, 1)) {}

bool FitInertiaMessages::Next(v1::FitInertiaRequest* message) {
  message->Clear();
  if (done_) return false;
  const size_t n = samples_.samples.size();
  if (!options_sent_) {
    *message->mutable_options() = options_;
    options_sent_ = true;
    // The mesh makes the options big: they travel alone.
    if (options_.has_mesh() && n > 0) return true;
  }
  const size_t end = std::min(n, sent_ + batch_);
  for (size_t i = sent_; i < end; ++i)
    *message->add_samples() = api::InertiaSampleToProto(samples_.samples[i], samples_.source);
  sent_ = end;
  done_ = sent_ >= n;
  return true;
}

std::vector<v1::FitInertiaRequest> AllFitInertiaMessages(const inertia::InertiaSamples& samples,
                                                         const v1::InertiaFitOptions& options,
                                                         size_t batch) {
  std::vector<v1::FitInertiaRequest> messages;
  FitInertiaMessages stream(samples, options, batch);
  v1::FitInertiaRequest message;
  while (stream.Next(&message)) messages.push_back(message);
  return messages;
}

}  // namespace tactforce::cli
