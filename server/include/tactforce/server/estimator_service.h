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
#include "tactforce/server/worker_pool.h"
#include "tactforce/v1/audit.grpc.pb.h"
#include "tactforce/v1/estimator.grpc.pb.h"

namespace tactforce::server {

struct EstimatorServiceOptions {
  int max_contacts = api::CallLimits{}.max_contacts;
  int64_t max_inertia_samples = api::kDefaultMaxInertiaSamples;  // per FitInertia stream
};

class EstimatorService final : public v1::Estimator::CallbackService, public HostedService {
 public:
  EstimatorService(WorkerPool* pool, EstimatorServiceOptions options)
      : pool_(pool), options_(options) {}

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
  grpc::ServerReadReactor<v1::FitInertiaRequest>* FitInertia(grpc::CallbackServerContext* context,
                                                             v1::FitInertiaResponse* response) override;

 private:
  WorkerPool* pool_;
  EstimatorServiceOptions options_;
};

// tactforce.v1.Audit: AuditModel on the pool (an audit fits many candidate
// models: tens of milliseconds to seconds).
class AuditService final : public v1::Audit::CallbackService, public HostedService {
 public:
  explicit AuditService(WorkerPool* pool) : pool_(pool) {}
  std::string service_name() const override { return std::string(v1::Audit::service_full_name()); }
  grpc::Service* grpc_service() override { return this; }
  grpc::ServerUnaryReactor* AuditModel(grpc::CallbackServerContext* context,
                                       const v1::AuditRequest* request,
                                       v1::AuditResponse* response) override;

 private:
  WorkerPool* pool_;
};

}  // namespace tactforce::server
