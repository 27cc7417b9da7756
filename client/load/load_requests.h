// What `tactforce load` sends: the request file of each --rpc, or a built-in
// example when there is none.
//
//   plan, stream  a PlanRequest JSON object or a JSON list of them (used
//                 round-robin), or the seeded random mix (RandomRequestMix,
//                 load_generator.h)
//   estimate      an EstimateRequest JSON object, or a JSON list of them
//                 (used round-robin); built in: the 3-finger wrench grasp
//                 (planner::BuiltInGrasps "wrench-3f") with readings 2, 1.5,
//                 3.5 N
//   audit         an AuditRequest JSON object or list; built in: 10 s at
//                 100 Hz of a simulated press-release run of a sensor with a
//                 0.3 N threshold and 0.02 N noise (1,000 samples)
//   fit-inertia   one call's stream: a JSON list of FitInertiaRequest
//                 messages (or one message), or an inertia CSV log (as
//                 `tactforce inertia --csv`) sent with default options
//                 (CONSTRAINED) in messages of --batch samples (default
//                 500), built as `tactforce inertia --server` builds its
//                 stream (inertia_stream.h); built in: 3 s at 100 Hz of the
//                 simulated seed-table1 object held by 4 fingertips,
//                 CONSTRAINED, 3 messages of 100 samples
// Everything built in is deterministic.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "inertia_stream.h"
#include "load_spec.h"
#include "tactforce/v1/audit.pb.h"
#include "tactforce/v1/estimator.pb.h"
#include "tactforce/v1/inertia.pb.h"

namespace tactforce::cli {

struct LoadRequestSource {
  std::string path;   // --request: a file, "-" = stdin; empty = built in / the mix
  uint64_t seed = 1;  // plan/stream mix
  int mix_size = 256;
  int batch = kDefaultInertiaBatch;  // fit-inertia from a CSV log: samples per message
};

// Fills the requests `spec->rpc` sends (nothing for health). Errors are
// InvalidArgument naming the file ("FILE:3:5: ...", "FILE[2]: ..." for an
// element of a list) or --request.
absl::Status SetLoadRequests(const LoadRequestSource& source, LoadSpec* spec);

v1::EstimateRequest ExampleEstimateRequest();
v1::AuditRequest ExampleAuditRequest();
std::vector<v1::FitInertiaRequest> ExampleFitInertiaStream();

}  // namespace tactforce::cli
