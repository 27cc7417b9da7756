// One grpc.health.v1.Health/Check on tactforce-server, shared by `health`,
// `demo` and the warm-up of `load --rpc health`.
#pragma once

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "remote_call.h"

namespace tactforce::cli {

// One grpc.health.v1.Health/Check of `service`: "SERVING", "NOT_SERVING",
// "UNKNOWN", or "SERVICE_UNKNOWN" when the server does not know the service
// (NOT_FOUND). Other failures as CallUnary reports them (remote_call.h).
absl::StatusOr<std::string> CheckHealth(const RemoteServer& server, const std::string& service);

// InvalidArgument "TARGET does not know service 'NAME' (--service)".
absl::Status UnknownServiceError(const std::string& target, const std::string& service);

}  // namespace tactforce::cli
