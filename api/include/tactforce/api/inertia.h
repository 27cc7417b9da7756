// Estimator.FitInertia: conversions between inertia.proto and the inertia
// library, and the request stream as the server and the CLI consume it.
// Field paths in errors: "options.hull", "samples[12].orientation", ...
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "tactforce/api/services.h"
#include "tactforce/io/mesh.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/types.h"
#include "tactforce/v1/inertia.pb.h"

namespace tactforce::api {

inline constexpr int64_t kDefaultMaxInertiaSamples = 1'000'000;

// Converts and validates the options. options.mesh: the bytes are read
// (ReadMeshBytes; format from `format` or the name's extension), the
// placement checked ("options.mesh.scale: must be > 0 (got -1)") and the
// mesh mapped to the object frame; errors of the file itself start with
// "options.mesh: <name>: ...". INERTIA_METHOD_UNSPECIFIED is DENSITY when a
// mesh is given, else CONSTRAINED.
absl::StatusOr<inertia::InertiaOptions> InertiaOptionsFromProto(
    const v1::InertiaFitOptions& options);
v1::InertiaMethod InertiaMethodToProto(inertia::InertiaMethod method);
// Wire spelling, "INERTIA_METHOD_DENSITY" (v1::InertiaMethod_Name); the
// library's inertia::ToString is the CLI spelling ("density").
std::string InertiaMethodName(inertia::InertiaMethod method);
v1::RegionScheme RegionSchemeToProto(inertia::RegionScheme scheme);
v1::FactorGraphVariant FactorGraphVariantToProto(inertia::FactorGraphVariant variant);

// The mesh of a MeshInput in the object frame (m), and its name for
// messages ("mesh" when unnamed). `field` starts the error messages.
struct ObjectMesh {
  io::TriangleMesh mesh;
  std::string name;
};
absl::StatusOr<ObjectMesh> MeshFromProto(const v1::MeshInput& input,
                                         std::string_view field = "options.mesh");

// A MeshInput carrying a mesh file's `bytes` with the placement applied by
// io::LoadMesh (so that MeshFromProto gives the same mesh as LoadMesh).
v1::MeshInput MeshInputToProto(std::string bytes, const std::string& format,
                               const std::string& name, const io::MeshPlacement& placement);

inertia::InertialParameters InertialParametersFromProto(const v1::InertialParameters& params);
v1::InertialParameters InertialParametersToProto(const inertia::InertialParameters& params);

// One sample as streamed (the force source and kinematics as in `samples`).
v1::InertiaSample InertiaSampleToProto(const inertia::InertiaSample& sample,
                                       inertia::ForceSource source);

v1::FitInertiaResponse InertiaFitToProto(const inertia::InertiaFit& fit);
// Inverse of InertiaFitToProto (for printing a server's answer with
// inertia::DescribeFit); `standard` is recomputed from the parameters.
inertia::InertiaFit InertiaFitFromProto(const v1::FitInertiaResponse& response);

// Fits `samples` (validated here; none: "samples: the stream carried no
// samples", after the options' errors) with `options` under `limits`
// (max_fit_bytes), polling `state.interrupt`; the response carries the
// error metrics when options.truth is set. Used by the CLI's local mode and
// by the server on an InertiaStream's samples and options. `progress`
// receives the fraction done (may be empty).
// `fit`, when not null, receives the library's result as well (with the
// region model of a DENSITY fit, e.g. for inertia::DensityPlotSvg).
absl::StatusOr<v1::FitInertiaResponse> FitInertiaSamples(const inertia::InertiaSamples& samples,
                                                         const v1::InertiaFitOptions& options,
                                                         const CallLimits& limits = {},
                                                         std::function<void(double)> progress = {},
                                                         inertia::InertiaFit* fit = nullptr,
                                                         const CallState& state = {});

// The FitInertia request stream, one message at a time. Samples are
// converted as they arrive (the proto messages are not kept). Add() fails
// on the first inconsistent message; the stream is then unusable.
class InertiaStream {
 public:
  explicit InertiaStream(int64_t max_samples = kDefaultMaxInertiaSamples)
      : max_samples_(max_samples) {}

  absl::Status Add(const v1::FitInertiaRequest& message);
  int64_t samples_received() const { return static_cast<int64_t>(samples_.samples.size()); }
  int messages_received() const { return messages_; }

  // Memory the stream holds (bytes): its samples at their vector's
  // capacity, their contacts, the options (the mesh's bytes included).
  int64_t held_bytes() const;
  // What held_bytes() will be after Add(message) succeeds, known before
  // anything is allocated: a server reserves it from its budget first.
  int64_t held_bytes_after(const v1::FitInertiaRequest& message) const;

  // After the last message, what FitInertiaSamples fits (it validates them).
  const inertia::InertiaSamples& samples() const { return samples_; }
  const v1::InertiaFitOptions& options() const { return options_; }

 private:
  int64_t max_samples_;
  int messages_ = 0;
  int64_t contacts_held_ = 0;  // ContactReadings across samples
  v1::InertiaFitOptions options_;
  inertia::InertiaSamples samples_;
};

}  // namespace tactforce::api
