// `tactforce health`: CheckHealth (health_check.h) and the --wait loop
// that asks again until SERVING.
#include "health_command.h"

#include <chrono>
#include <iostream>
#include <thread>

#include "absl/strings/str_cat.h"
#include "cli_common.h"
#include "health_check.h"
#include "tactforce/io/json.h"

namespace tactforce::cli {
CLI::App* AddHealthCommand(CLI::App& app, HealthArgs& args) {
  CLI::App* cmd =
      app.add_subcommand("health", "Ask tactforce-server whether it is serving (grpc.health.v1)");
  AddConnectionFlags(cmd, &args.connection, "--server", /*default_deadline_ms=*/5'000);
  cmd->add_option("--service", args.service,
                  "Service to ask about, e.g. tactforce.v1.Planner (default: the whole server)")
      ->type_name("NAME");
  cmd->add_option("--wait", args.wait_s,
                  "Ask again every 0.2 s until SERVING, for up to this many seconds")
      ->type_name("SECONDS")
      ->check(CLI::Range(0.0, 3600.0));
  AddOutputFlags(cmd, &args.output, "{\"service\": ..., \"status\": ...}");
  cmd->footer(
      "Prints SERVING, NOT_SERVING, UNKNOWN or SERVICE_UNKNOWN on stdout.\n"
      "Examples:\n"
      "  tactforce health --server localhost:50051\n"
      "  tactforce health --server localhost:50051 --service tactforce.v1.Planner --wait 10 "
      "--json\n"
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
  absl::StatusOr<RemoteServer> server = RemoteServer::Open(connection, channel_args);
  if (!server.ok()) return ReportError(server.status());

  using Clock = std::chrono::steady_clock;
  const Clock::time_point give_up =
      Clock::now() + std::chrono::milliseconds(static_cast<int64_t>(args.wait_s * 1000));
  absl::StatusOr<std::string> state;
  for (;;) {
    state = CheckHealth(*server, args.service);
    const bool retry = state.ok() ? (*state != "SERVING" && *state != "SERVICE_UNKNOWN")
                                  : (state.status().code() == absl::StatusCode::kUnavailable ||
                                     state.status().code() == absl::StatusCode::kDeadlineExceeded);
    if (!retry || Clock::now() >= give_up) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  if (!state.ok()) return ReportError(state.status());

  if (args.output.json()) {
    std::cout << io::IndentJson(absl::StrCat("{\"service\": ", io::JsonEscape(args.service),
                                             ", \"status\": ", io::JsonEscape(*state), "}"))
              << std::flush;
  } else {
    std::cout << *state << std::endl;
  }
  if (*state == "SERVING") return kExitOk;
  if (*state == "SERVICE_UNKNOWN")
    return ReportError(UnknownServiceError(connection.server, args.service));
  return kExitUnavailable;
}

}  // namespace tactforce::cli
