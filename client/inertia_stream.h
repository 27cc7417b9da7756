// The Estimator.FitInertia request stream as the client sends it, shared by
// `tactforce inertia --server` (written as it is built) and `tactforce load
// --rpc fit-inertia` (built once, sent whole in every call): the options in
// the first message (alone when they carry a mesh, so that only the mesh
// counts against the server's --max-message-bytes), then the samples in
// messages of `batch`; at least one message, even for an empty log.
#pragma once

#include <cstddef>
#include <vector>

#include "tactforce/inertia/types.h"
#include "tactforce/v1/inertia.pb.h"

namespace tactforce::cli {

inline constexpr int kDefaultInertiaBatch = 500;  // samples per message

class FitInertiaMessages {
 public:
  // `samples` and `options` must outlive this; `batch` < 1 counts as 1.
  FitInertiaMessages(const inertia::InertiaSamples& samples, const v1::InertiaFitOptions& options,
                     size_t batch);

  // The next message of the stream into `message` (cleared first); false
  // when the stream is complete.
  bool Next(v1::FitInertiaRequest* message);

  // Samples in the messages given so far, and in all.
  size_t samples_sent() const { return sent_; }
  size_t samples_total() const { return samples_.samples.size(); }

 private:
  const inertia::InertiaSamples& samples_;
  const v1::InertiaFitOptions& options_;
  size_t batch_;
  size_t sent_ = 0;
  bool options_sent_ = false;
  bool done_ = false;
};

// The whole stream.
std::vector<v1::FitInertiaRequest> AllFitInertiaMessages(const inertia::InertiaSamples& samples,
                                                         const v1::InertiaFitOptions& options,
                                                         size_t batch);

}  // namespace tactforce::cli
