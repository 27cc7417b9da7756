// tactforce.v1.Estimator and tactforce.v1.Audit.
// Estimator: EstimateForces, EstimateFriction and the client-streaming
// FitInertia, thin adapters over tactforce::api (which calls the estimator
// libraries). All run on the WorkerPool (friction requests carry whole time
// series; an inertia fit takes tens to hundreds of milliseconds). FitInertia
// converts each message as it arrives on the gRPC thread (cheap) and fits on
// the pool once the client half-closes.
#pragma once

#include <cstdint>
#include <string>

#include "tactforce/api/inertia.h"
#include "tactforce/api/services.h"
#include "tactforce/server/server_host.h"
#include "tactforce/server/stream_registry.h"
#include "tactforce/server/worker_pool.h"
#include "tactforce/v1/audit.grpc.pb.h"
#include "tactforce/v1/estimator.grpc.pb.h"

namespace tactforce::server {

// Limits of the Estimator and Audit services (the server's flags).
struct EstimatorServiceOptions {
  int max_contacts = api::CallLimits{}.max_contacts;
  int64_t max_inertia_samples = api::kDefaultMaxInertiaSamples;  // per FitInertia stream
  int64_t max_audit_samples = api::CallLimits{}.max_audit_samples;  // per AuditModel request
  int solve_timeout_ms = 10'000;  // work budget of every call (CallLimits::max_call_seconds); 0 = none
  // Working memory of one FitInertia fit (CallLimits::max_fit_bytes); 0 = none.
  int64_t max_fit_bytes = int64_t{256} << 20;

  api::CallLimits Limits() const;
};

// FitInertia is registered raw (its reactor parses each message itself:
// see estimator_service.cc); the unary RPCs are typed.
using EstimatorBase = v1::Estimator::WithCallbackMethod_EstimateForces<
    v1::Estimator::WithCallbackMethod_EstimateFriction<
        v1::Estimator::WithRawCallbackMethod_FitInertia<v1::Estimator::Service>>>;

class EstimatorService final : public EstimatorBase, public HostedService {
 public:
  // `pool` and `streams` must outlive the service.
  EstimatorService(WorkerPool* pool, StreamRegistry* streams, EstimatorServiceOptions options)
      : pool_(pool), streams_(streams), options_(options) {}

  std::string service_name() const override {
    return std::string(v1::Estimator::service_full_name());
  }
  grpc::Service* grpc_service() override { return this; }

  grpc::ServerUnaryReactor* EstimateForces(grpc::CallbackServerContext* context,
                                           const v1::EstimateRequest* request,
                                           v1::EstimateResponse* response) override;
  grpc::ServerUnaryReactor* EstimateFriction(grpc::CallbackServerContext* context,
                                             const v1::FrictionRequest* request,
                                             v1::FrictionResponse* response) override;
  grpc::ServerReadReactor<grpc::ByteBuffer>* FitInertia(grpc::CallbackServerContext* context,
                                                        grpc::ByteBuffer* response) override;

 private:
  WorkerPool* pool_;
  StreamRegistry* streams_;  // FitInertia's admission, idle timeout and sample budget
  EstimatorServiceOptions options_;
};

// tactforce.v1.Audit: AuditModel on the pool (an audit fits many candidate
// models: tens of milliseconds to seconds).
class AuditService final : public v1::Audit::CallbackService, public HostedService {
 public:
  AuditService(WorkerPool* pool, EstimatorServiceOptions options) : pool_(pool), options_(options) {}
  std::string service_name() const override { return std::string(v1::Audit::service_full_name()); }
  grpc::Service* grpc_service() override { return this; }
  grpc::ServerUnaryReactor* AuditModel(grpc::CallbackServerContext* context,
                                       const v1::AuditRequest* request,
                                       v1::AuditResponse* response) override;

 private:
  WorkerPool* pool_;
  EstimatorServiceOptions options_;
};

}  // namespace tactforce::server
