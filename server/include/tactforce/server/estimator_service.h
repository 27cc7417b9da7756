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
#include <utility>

#include "tactforce/api/inertia.h"
#include "tactforce/api/services.h"
#include "tactforce/server/server_host.h"
#include "tactforce/server/stream_registry.h"
#include "tactforce/server/worker_pool.h"
#include "tactforce/v1/audit.grpc.pb.h"
#include "tactforce/v1/estimator.grpc.pb.h"

namespace tactforce::server {

// FitInertia is registered raw (its reactor parses each message itself:
// see estimator_service.cc); the unary RPCs are typed.
using EstimatorBase = v1::Estimator::WithCallbackMethod_EstimateForces<
    v1::Estimator::WithCallbackMethod_EstimateFriction<
        v1::Estimator::WithRawCallbackMethod_FitInertia<v1::Estimator::Service>>>;

class EstimatorService final : public EstimatorBase, public HostedService {
 public:
  // `pool` and `streams` must outlive the service. `limits` hold for every
  // call; `max_inertia_samples`: most samples one FitInertia stream may carry.
  EstimatorService(WorkerPool* pool, StreamRegistry* streams, api::CallLimits limits,
                   int64_t max_inertia_samples = api::kDefaultMaxInertiaSamples)
      : pool_(pool),
        streams_(streams),
        limits_(std::move(limits)),
        max_inertia_samples_(max_inertia_samples) {}

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
  api::CallLimits limits_;
  int64_t max_inertia_samples_;
};

// tactforce.v1.Audit: AuditModel on the pool (an audit fits many candidate
// models: tens of milliseconds to seconds).
class AuditService final : public v1::Audit::CallbackService, public HostedService {
 public:
  AuditService(WorkerPool* pool, api::CallLimits limits)
      : pool_(pool), limits_(std::move(limits)) {}
  std::string service_name() const override { return std::string(v1::Audit::service_full_name()); }
  grpc::Service* grpc_service() override { return this; }
  grpc::ServerUnaryReactor* AuditModel(grpc::CallbackServerContext* context,
                                       const v1::AuditRequest* request,
                                       v1::AuditResponse* response) override;

 private:
  WorkerPool* pool_;
  api::CallLimits limits_;
};

}  // namespace tactforce::server
