#include "health_command.h"

#include <chrono>
#include <iostream>
#include <memory>
#include <thread>

#include "absl/strings/str_cat.h"
#include "cli_common.h"
#include "grpc/health/v1/health.grpc.pb.h"

namespace tactforce::cli {
namespace {

using HealthResponse = grpc::health::v1::HealthCheckResponse;

std::string ServingName(HealthResponse::ServingStatus status) {
  switch (status) {
    case HealthResponse::SERVING:
      return "SERVING";
    case HealthResponse::NOT_SERVING:
      return "NOT_SERVING";
    case HealthResponse::SERVICE_UNKNOWN:
      return "SERVICE_UNKNOWN";
    default:
      return "UNKNOWN";
  }
}

}  // namespace

absl::StatusOr<std::string> CheckHealth(const std::shared_ptr<grpc::Channel>& channel,
                                        const std::string& target,
                                        const std::string& service, int deadline_ms) {
  std::unique_ptr<grpc::health::v1::Health::Stub> stub =
      grpc::health::v1::Health::NewStub(channel);
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  HealthResponse response;
  grpc::ClientContext context;
  SetDeadline(&context, deadline_ms);
  const grpc::Status status = stub->Check(&context, request, &response);
  if (status.error_code() == grpc::StatusCode::NOT_FOUND) return std::string("SERVICE_UNKNOWN");
  if (!status.ok()) return RpcError(status, target, deadline_ms, channel.get());
  return ServingName(response.status());
}

CLI::App* AddHealthCommand(CLI::App& app, HealthArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "health", "Ask tactforce-server whether it is serving (grpc.health.v1)");
  AddConnectionFlags(cmd, &args.connection, "--server", /*default_deadline_ms=*/5'000);
  cmd->add_option("--service", args.service,
                  "Service to ask about, e.g. tactforce.v1.Planner (default: the whole server)")
      ->type_name("NAME");
  cmd->add_option("--wait", args.wait_s,
                  "Ask again every 0.2 s until SERVING, for up to this many seconds")
      ->type_name("SECONDS")
      ->check(CLI::Range(0.0, 3600.0));
  cmd->footer(
      "Prints SERVING, NOT_SERVING, UNKNOWN or SERVICE_UNKNOWN on stdout.\n"
      "Exit status: 0 only when SERVING; 3 when not serving or the server cannot be\n"
      "reached; 2 for an unknown --service; 4 when it did not answer within\n"
      "--deadline-ms; 1 otherwise.");
  return cmd;
}

int RunHealth(const HealthArgs& args) {
  const ConnectionArgs& connection = args.connection;
  grpc::ChannelArguments channel_args;
  if (args.wait_s > 0) {
    // Waiting for a server that is starting: retry the connection quickly
    // instead of gRPC's default backoff (1 s, growing to 2 min).
    channel_args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 100);
    channel_args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 100);
    channel_args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 500);
  }
  absl::StatusOr<std::shared_ptr<grpc::Channel>> channel =
      MakeChannel(connection, connection.server, channel_args);
  if (!channel.ok()) return ReportError(channel.status());

  using Clock = std::chrono::steady_clock;
  const Clock::time_point give_up =
      Clock::now() + std::chrono::milliseconds(static_cast<int64_t>(args.wait_s * 1000));
  absl::StatusOr<std::string> state;
  for (;;) {
    state = CheckHealth(*channel, connection.server, args.service, connection.deadline_ms);
    const bool retry = state.ok() ? (*state != "SERVING" && *state != "SERVICE_UNKNOWN")
                                  : (state.status().code() == absl::StatusCode::kUnavailable ||
                                     state.status().code() ==
                                         absl::StatusCode::kDeadlineExceeded);
    if (!retry || Clock::now() >= give_up) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  if (!state.ok()) return ReportError(state.status());

  std::cout << *state << std::endl;
  if (*state == "SERVING") return kExitOk;
  if (*state == "SERVICE_UNKNOWN") {
    std::cerr << "error: " << connection.server << " does not know service '" << args.service
              << "' (--service)" << std::endl;
    return kExitBadInput;
  }
  return kExitUnavailable;
}

}  // namespace tactforce::cli
