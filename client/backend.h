// Where a `tactforce` command's work is done: one interface with a method
// per RPC, implemented in this process over the libraries (MakeLocalBackend)
// and on tactforce-server over gRPC (MakeRemoteBackend). Commands build
// their request, call the one method and print the answer; which backend
// answers is the --local / --server ADDR choice (BackendArgs), the same in
// every command: in this process unless --server is given.
//
// Requests whose input is a proto message (plan, estimate and friction
// requests read as JSON) are passed as that message; the local backend
// hands them to the api layer's handler. FitInertia and AuditModel take the
// library's own types (samples, measured data) and the local backend calls
// the inertia and audit libraries directly, returning the library's result;
// the remote one converts to the wire and back.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "CLI/CLI.hpp"
#include "absl/status/statusor.h"
#include "connection.h"
#include "tactforce/audit/audit.h"
#include "tactforce/audit/measured_data.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/types.h"
#include "tactforce/v1/estimator.pb.h"
#include "tactforce/v1/inertia.pb.h"
#include "tactforce/v1/planner.pb.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {

// One FitInertia: the samples and the options as the wire carries them
// (the one form both backends take; the mesh travels as its file's bytes).
struct InertiaCall {
  const inertia::InertiaSamples* samples = nullptr;  // outlives the call
  v1::InertiaFitOptions options;
  int batch = 500;             // remote: samples per streamed message
  bool show_progress = false;  // a "fit" (local) or "upload" (remote) bar on stderr
};

// Its answer: the library's fit (local: as computed, with the region model
// of a DENSITY fit; remote: converted from the response, without it) and
// the response (samples_received, notes, errors against options.truth).
struct InertiaAnswer {
  inertia::InertiaFit fit;
  v1::FitInertiaResponse response;
};

// One AuditModel: the measured data and the audit's options; `model_json`
// is the --model file's text (sent to a server; options.model holds it
// parsed for the local audit).
struct AuditCall {
  audit::MeasuredData data;
  audit::AuditOptions options;
  std::string model_json;
};

// Its answer. `report` is the library's report (local only: the report
// folder's plots need it); the strings are what both backends give.
struct AuditAnswer {
  std::optional<audit::AuditReport> report;
  std::string report_json;          // report.json (`--json` prints it)
  std::string summary;              // summary.txt
  std::string extended_model_json;  // extended_model.json
};

class Backend {
 public:
  virtual ~Backend() = default;
  // !ok(): the request was rejected (InvalidArgument names the field) or
  // the backend could not answer (remote: Unavailable "cannot reach ADDR:
  // ...", DeadlineExceeded, ...; RpcError in connection.h). ok(): a
  // computed answer, whatever its status.
  virtual absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) = 0;
  virtual absl::StatusOr<v1::TrajectoryResponse> PlanTrajectory(
      const v1::TrajectoryRequest& request) = 0;
  virtual absl::StatusOr<v1::FrictionProbeResponse> PlanFrictionProbe(
      const v1::FrictionProbeRequest& request) = 0;
  virtual absl::StatusOr<v1::EstimateResponse> EstimateForces(
      const v1::EstimateRequest& request) = 0;
  virtual absl::StatusOr<v1::FrictionResponse> EstimateFriction(
      const v1::FrictionRequest& request) = 0;
  virtual absl::StatusOr<InertiaAnswer> FitInertia(const InertiaCall& call) = 0;
  virtual absl::StatusOr<AuditAnswer> AuditModel(const AuditCall& call) = 0;
  // For messages: "local", "localhost:50051", ...
  virtual std::string Describe() const = 0;
  virtual bool local() const = 0;
};

// In this process: the api layer's handlers and the inertia and audit
// libraries, without limits.
std::unique_ptr<Backend> MakeLocalBackend();

// On tactforce-server at `args.server`: one call per method (FitInertia
// streamed in batches), each within `args.deadline_ms`. Fails only when the
// channel cannot be built (unreadable TLS files); connecting happens on
// the first call.
absl::StatusOr<std::unique_ptr<Backend>> MakeRemoteBackend(const ConnectionArgs& args);

// The --local / --server ADDR choice every command that makes an RPC takes.
struct BackendArgs {
  bool local = false;         // --local: explicit, the default
  bool remote = false;        // set when --server is given
  ConnectionArgs connection;  // --server, --tls-*, --deadline-ms
};

// Adds --local and --server ADDR (excluding each other) with the TLS and
// --deadline-ms flags; `what` ends the --server description ("Plan on
// tactforce-server ... (WHAT)"). Returns the --server option.
CLI::Option* AddBackendFlags(CLI::App* cmd, BackendArgs* args, const std::string& what,
                             int default_deadline_ms = 30'000);

// The backend `args` chose.
absl::StatusOr<std::unique_ptr<Backend>> MakeBackend(const BackendArgs& args);

// One call of `method` on the backend `args` chose (a command's single
// call): MakeBackend's errors first, then the call's.
template <class Answer, class Request>
absl::StatusOr<Answer> CallBackend(const BackendArgs& args,
                                   absl::StatusOr<Answer> (Backend::*method)(const Request&),
                                   const Request& request) {
  TF_ASSIGN_OR_RETURN(std::unique_ptr<Backend> backend, MakeBackend(args));
  return ((*backend).*method)(request);
}

}  // namespace tactforce::cli
