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

#include <google/protobuf/descriptor.h>
#include <grpcpp/grpcpp.h>

#include "tactforce/api/inertia.h"
#include "tactforce/api/services.h"
#include "tactforce/server/server_host.h"
#include "tactforce/server/stream_registry.h"
#include "tactforce/server/worker_pool.h"
#include "tactforce/v1/audit.grpc.pb.h"
#include "tactforce/v1/estimator.grpc.pb.h"

namespace tactforce::server {

// FitInertia with raw reads and a typed response. Its reads must be raw
// (gRPC's typed reader reports a message it cannot parse like the end of the
// stream: admitted_stream.h), its answer need not be: gRPC serializes the
// FitInertiaResponse the reactor fills. protoc's WithRawCallbackMethod_
// mixin makes both sides raw, so this one registers the method as protoc's
// mixins do (Service::MarkMethodRawCallback with gRPC's callback handler,
// Debian 12's gRPC 1.51), at the method's index in the service descriptor.
template <class Base>
class WithRawReadsCallbackMethod_FitInertia : public Base {
 public:
  WithRawReadsCallbackMethod_FitInertia() {
    this->MarkMethodRawCallback(
        MethodIndex(),
        new grpc::internal::CallbackClientStreamingHandler<grpc::ByteBuffer,
                                                           v1::FitInertiaResponse>(
            [this](grpc::CallbackServerContext* context, v1::FitInertiaResponse* response) {
              return FitInertia(context, response);
            }));
  }
  // The synchronous method is never registered (the callback one replaces it).
  grpc::Status FitInertia(grpc::ServerContext*, grpc::ServerReader<v1::FitInertiaRequest>*,
                          v1::FitInertiaResponse*) final {
    return grpc::Status(grpc::StatusCode::UNIMPLEMENTED, "FitInertia is served by callback");
  }
  virtual grpc::ServerReadReactor<grpc::ByteBuffer>* FitInertia(
      grpc::CallbackServerContext* context, v1::FitInertiaResponse* response) = 0;

 private:
  // The index protoc's mixins hard-code (the rpc's place in estimator.proto).
  static int MethodIndex() {
    return google::protobuf::DescriptorPool::generated_pool()
        ->FindMethodByName(std::string(v1::Estimator::service_full_name()) + ".FitInertia")
        ->index();
  }
};

// The unary RPCs are typed; FitInertia's reactor parses each message itself
// (estimator_service.cc).
using EstimatorBase = v1::Estimator::WithCallbackMethod_EstimateForces<
    v1::Estimator::WithCallbackMethod_EstimateFriction<
        WithRawReadsCallbackMethod_FitInertia<v1::Estimator::Service>>>;

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
  using EstimatorBase::FitInertia;
  grpc::ServerReadReactor<grpc::ByteBuffer>* FitInertia(grpc::CallbackServerContext* context,
                                                        v1::FitInertiaResponse* response) override;

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
