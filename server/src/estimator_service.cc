#include "tactforce/server/estimator_service.h"

#include "tactforce/api/services.h"
#include "tactforce/server/pooled_unary.h"

namespace tactforce::server {

grpc::ServerUnaryReactor* EstimatorService::EstimateForces(grpc::CallbackServerContext* context,
                                                           const v1::EstimateRequest* request,
                                                           v1::EstimateResponse* response) {
  api::CallLimits limits;
  limits.max_contacts = options_.max_contacts;
  return ServeOnPool<v1::EstimateRequest, v1::EstimateResponse>(
      "EstimateForces", context, request, response, pool_, limits, &api::HandleEstimate);
}

grpc::ServerUnaryReactor* EstimatorService::EstimateFriction(grpc::CallbackServerContext* context,
                                                             const v1::FrictionRequest* request,
                                                             v1::FrictionResponse* response) {
  return ServeOnPool<v1::FrictionRequest, v1::FrictionResponse>(
      "EstimateFriction", context, request, response, pool_, api::CallLimits{},
      [](const v1::FrictionRequest& r, const api::CallLimits&) { return api::HandleFriction(r); });
}

grpc::ServerUnaryReactor* AuditService::AuditModel(grpc::CallbackServerContext* context,
                                                   const v1::AuditRequest* request,
                                                   v1::AuditResponse* response) {
  return ServeOnPool<v1::AuditRequest, v1::AuditResponse>(
      "AuditModel", context, request, response, pool_, api::CallLimits{},
      [](const v1::AuditRequest& r, const api::CallLimits&) { return api::HandleAudit(r); });
}

}  // namespace tactforce::server
