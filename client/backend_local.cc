// The Backend in this process: plan, estimate and friction requests through
// the api layer's handlers; FitInertia on the inertia library (the options
// converted once, the library's fit returned as it is, with its region
// model); AuditModel on the audit library.
#include <utility>

#include "backend.h"
#include "progress.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/services.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {
namespace {

class LocalBackend final : public Backend {
 public:
  absl::StatusOr<v1::PlanResponse> Plan(const v1::PlanRequest& request) override {
    return api::HandlePlan(request);
  }
  absl::StatusOr<v1::TrajectoryResponse> PlanTrajectory(
      const v1::TrajectoryRequest& request) override {
    return api::HandleTrajectory(request);
  }
  absl::StatusOr<v1::FrictionProbeResponse> PlanFrictionProbe(
      const v1::FrictionProbeRequest& request) override {
    return api::HandleFrictionProbe(request);
  }
  absl::StatusOr<v1::EstimateResponse> EstimateForces(const v1::EstimateRequest& request) override {
    return api::HandleEstimate(request);
  }
  absl::StatusOr<v1::FrictionResponse> EstimateFriction(
      const v1::FrictionRequest& request) override {
    return api::HandleFriction(request);
  }
  absl::StatusOr<InertiaAnswer> FitInertia(const InertiaCall& call) override;
  absl::StatusOr<AuditAnswer> AuditModel(const AuditCall& call) override;
  std::string Describe() const override { return "local"; }
  bool local() const override { return true; }
};

absl::StatusOr<InertiaAnswer> LocalBackend::FitInertia(const InertiaCall& call) {
  ProgressBar bar("fit", call.show_progress);
  InertiaAnswer answer;
  TF_ASSIGN_OR_RETURN(answer.response,
                      api::FitInertiaSamples(
                          *call.samples, call.options, {},
                          [&bar](double fraction) { bar.Update(fraction); }, &answer.fit));
  return answer;
}

absl::StatusOr<AuditAnswer> LocalBackend::AuditModel(const AuditCall& call) {
  AuditAnswer answer;
  TF_ASSIGN_OR_RETURN(answer.report, audit::RunAudit(call.data, call.options));
  answer.report_json = audit::AuditReportJson(*answer.report);
  answer.summary = audit::FormatAuditSummary(*answer.report);
  return answer;
}

}  // namespace

std::unique_ptr<Backend> MakeLocalBackend() { return std::make_unique<LocalBackend>(); }

}  // namespace tactforce::cli
