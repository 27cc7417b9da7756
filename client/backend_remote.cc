// The Backend on tactforce-server: each unary method one CallUnary on a
// stub kept for the backend's life; FitInertia the client stream of
// inertia_stream.h written in batches; AuditModel the measured data as an
// AuditRequest.
#include <algorithm>
#include <utility>

#include "absl/strings/str_cat.h"
#include "backend.h"
#include "inertia_stream.h"
#include "progress.h"
#include "remote_call.h"
#include "tactforce/api/inertia.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/v1/audit.grpc.pb.h"
#include "tactforce/v1/estimator.grpc.pb.h"
#include "tactforce/v1/planner.grpc.pb.h"

namespace tactforce::cli {
namespace {

// Writes the FitInertia stream (the options, alone first when they carry
// the mesh, then the samples in messages of `batch`). Stops early when the
// server ends the call (Finish() says why).
void WriteFitStream(grpc::ClientWriter<v1::FitInertiaRequest>& writer, const InertiaCall& call,
                    ProgressBar& upload) {
  FitInertiaMessages stream(*call.samples, call.options,
                            static_cast<size_t>(std::max(1, call.batch)));
  const size_t n = stream.samples_total();
  v1::FitInertiaRequest message;
  while (stream.Next(&message)) {
    if (!writer.Write(message)) break;
    if (message.samples_size() == 0 && n > 0) continue;  // the options alone
    upload.Update(
        static_cast<double>(stream.samples_sent()) / static_cast<double>(std::max<size_t>(n, 1)),
        absl::StrCat(stream.samples_sent(), "/", n, " samples"));
  }
  writer.WritesDone();
}

// RESOURCE_EXHAUSTED of a stream whose first message carries the mesh:
// names the limit, the message's size and how to raise it.
absl::Status MeshTooLargeError(const std::string& target, const grpc::Status& status,
                               const v1::InertiaFitOptions& options) {
  v1::FitInertiaRequest first;
  *first.mutable_options() = options;
  return absl::ResourceExhaustedError(absl::StrCat(
      target, ": ", status.error_message(), " (the first FitInertia message, ",
      first.ByteSizeLong(), " bytes, carries the mesh ", options.mesh().name(), " of ",
      options.mesh().data().size(),
      " bytes: start tactforce-server with a larger --max-message-bytes, or give a smaller mesh)"));
}

// The measured data and options as the wire carries them. AuditRequest has
// no clock offset: two aligned streams (whose offset the audit refines and
// whose 'delay' candidate depends on it) are audited locally only.
absl::StatusOr<v1::AuditRequest> AuditRequestFor(const AuditCall& call) {
  const audit::MeasuredData& data = call.data;
  if (data.clock_offset_source != audit::MeasuredData::ClockOffset::kNone) {
    return absl::InvalidArgumentError(
        "--server: Audit.AuditModel takes one CSV (--csv); two streams (--reference, --reading) "
        "carry a clock "
        "offset the request cannot: audit them in this process (without --server)");
  }
  v1::AuditRequest request;
  request.set_source(data.source);
  for (size_t i = 0; i < data.t.size(); ++i) {
    v1::AuditSample* s = request.add_samples();
    s->set_t(data.t[i]);
    s->set_reference(data.reference[i]);
    s->set_reading(data.reading[i]);
    if (i < data.shear.size()) s->set_shear(data.shear[i]);
    if (i < data.trial.size()) s->set_trial(data.trial[i]);
    for (const std::vector<double>& taxel : data.taxels) s->add_taxels(taxel[i]);
  }
  request.set_model_json(call.model_json);
  request.set_heldout_fraction(call.options.heldout_fraction);
  request.set_max_causes(call.options.max_causes);
  request.set_blocks(call.options.blocks);
  request.set_reading_units(call.options.reading_units);
  return request;
}

class RemoteBackend final : public Backend {
 public:
  explicit RemoteBackend(RemoteServer server)
      : server_(std::move(server)),
        planner_(server_.channel()),
        estimator_(server_.channel()),
        audit_(server_.channel()) {}

  absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) override {
    return CallUnary(server_, planner_, &v1::Planner::Stub::Plan, request);
  }
  absl::StatusOr<v1::TrajectoryResponse> PlanTrajectory(
      const v1::TrajectoryRequest& request) override {
    return CallUnary(server_, planner_, &v1::Planner::Stub::PlanTrajectory, request);
  }
  absl::StatusOr<v1::FrictionProbeResponse> PlanFrictionProbe(
      const v1::FrictionProbeRequest& request) override {
    return CallUnary(server_, planner_, &v1::Planner::Stub::PlanFrictionProbe, request);
  }
  absl::StatusOr<v1::EstimateResponse> EstimateForces(const v1::EstimateRequest& request) override {
    return CallUnary(server_, estimator_, &v1::Estimator::Stub::EstimateForces, request);
  }
  absl::StatusOr<v1::FrictionResponse> EstimateFriction(
      const v1::FrictionRequest& request) override {
    return CallUnary(server_, estimator_, &v1::Estimator::Stub::EstimateFriction, request);
  }
  absl::StatusOr<InertiaAnswer> FitInertia(const InertiaCall& call) override;
  absl::StatusOr<AuditAnswer> AuditModel(const AuditCall& call) override;
  std::string Describe() const override { return server_.target(); }
  bool local() const override { return false; }

 private:
  RemoteServer server_;
  v1::Planner::Stub planner_;
  v1::Estimator::Stub estimator_;
  v1::Audit::Stub audit_;
};

absl::StatusOr<InertiaAnswer> RemoteBackend::FitInertia(const InertiaCall& call) {
  ProgressBar upload("upload", call.show_progress);
  grpc::ClientContext context;
  server_.SetDeadline(&context);
  InertiaAnswer answer;
  std::unique_ptr<grpc::ClientWriter<v1::FitInertiaRequest>> writer =
      estimator_.FitInertia(&context, &answer.response);
  WriteFitStream(*writer, call, upload);
  const grpc::Status status = writer->Finish();
  upload.Finish();
  if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED && call.options.has_mesh())
    return MeshTooLargeError(server_.target(), status, call.options);
  if (!status.ok()) return server_.Error(status);
  answer.fit = api::InertiaFitFromProto(answer.response);
  return answer;
}

absl::StatusOr<AuditAnswer> RemoteBackend::AuditModel(const AuditCall& call) {
  TF_ASSIGN_OR_RETURN(v1::AuditRequest request, AuditRequestFor(call));
  TF_ASSIGN_OR_RETURN(v1::AuditResponse response,
                      CallUnary(server_, audit_, &v1::Audit::Stub::AuditModel, request));
  AuditAnswer answer;
  answer.report_json = response.report_json();
  answer.summary = response.summary();
  answer.extended_model_json = response.extended_model_json();
  return answer;
}

}  // namespace

absl::StatusOr<std::unique_ptr<Backend>> MakeRemoteBackend(const ConnectionArgs& args) {
  TF_ASSIGN_OR_RETURN(RemoteServer server, RemoteServer::Open(args));
  return std::make_unique<RemoteBackend>(std::move(server));
}

}  // namespace tactforce::cli
