// CheckHealth: one Health/Check through CallUnary, the serving status by
// its wire name.
#include "health_check.h"

#include "absl/strings/str_cat.h"
#include "grpc/health/v1/health.grpc.pb.h"

namespace tactforce::cli {
namespace {

using HealthResponse = grpc::health::v1::HealthCheckResponse;

// The status's name in health.proto; "UNKNOWN" for a value newer than it.
std::string ServingName(HealthResponse::ServingStatus status) {
  const std::string& name = HealthResponse::ServingStatus_Name(status);
  return name.empty() ? "UNKNOWN" : name;
}

}  // namespace

absl::StatusOr<std::string> CheckHealth(const RemoteServer& server, const std::string& service) {
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  absl::StatusOr<HealthResponse> response =
      CallUnary(server, &grpc::health::v1::Health::Stub::Check, request);
  if (response.status().code() == absl::StatusCode::kNotFound)
    return std::string("SERVICE_UNKNOWN");
  if (!response.ok()) return response.status();
  return ServingName(response->status());
}

absl::Status UnknownServiceError(const std::string& target, const std::string& service) {
  return absl::InvalidArgumentError(
      absl::StrCat(target, " does not know service '", service, "' (--service)"));
}

}  // namespace tactforce::cli
