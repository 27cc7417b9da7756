// `tactforce load`: the flags to a LoadSpec, Ctrl-C and the progress line
// around RunLoad (load_generator.h), the report, and the exit code of the
// most frequent failure.
#include "load_command.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <iostream>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"
#include "cli_common.h"
#include "load_generator.h"
#include "tactforce/api/json.h"

namespace tactforce::cli {
namespace {

constexpr int kOpenLoopDefaultInFlight = 1000;
constexpr double kDefaultDurationS = 10.0;
constexpr double kProgressAfterS = 2.0;

volatile std::sig_atomic_t g_interrupted = 0;

void OnInterrupt(int) {
  g_interrupted = 1;
  std::signal(SIGINT, SIG_DFL);  // a second Ctrl-C ends the process
}

// Prints the progress line on stderr: rewritten in place on a terminal, one
// line per update otherwise (--progress into a file or pipe).
class ProgressPrinter {
 public:
  explicit ProgressPrinter(bool tty) : tty_(tty) {}

  void Update(const LoadProgress& p) {
    if (p.elapsed_s < kProgressAfterS) return;
    const std::string line =
        absl::StrFormat("load: %.0f s, %d calls (%d failed), %.0f calls/s", p.elapsed_s,
                        p.completed, p.failed, p.recent_qps);
    if (tty_) {
      std::cerr << "\r" << line << "\x1b[K" << std::flush;
      shown_ = true;
    } else {
      std::cerr << line << std::endl;
    }
  }

  void Finish() {
    if (tty_ && shown_) std::cerr << "\r\x1b[K" << std::flush;
  }

 private:
  bool tty_;
  bool shown_ = false;
};

absl::StatusOr<LoadRpc> ParseRpc(const std::string& name) {
  for (LoadRpc rpc : {LoadRpc::kPlan, LoadRpc::kStream, LoadRpc::kHealth}) {
    if (name == ToString(rpc)) return rpc;
  }
  return absl::InvalidArgumentError("--rpc: expected plan, stream or health");
}

// The run the flags ask for (requests read or generated); InvalidArgument
// naming the flag for combinations that cannot run.
absl::StatusOr<LoadSpec> LoadSpecFromFlags(const LoadArgs& args) {
  LoadSpec spec;
  absl::StatusOr<LoadRpc> rpc = ParseRpc(args.rpc);
  if (!rpc.ok()) return rpc.status();
  spec.rpc = *rpc;
  spec.engine = args.engine == "sync" ? LoadEngine::kSync : LoadEngine::kCallback;
  spec.rate = args.rate;
  spec.concurrency =
      args.concurrency > 0 ? args.concurrency : (args.rate > 0 ? kOpenLoopDefaultInFlight : 1);
  spec.max_requests = args.requests;
  spec.duration_s = args.duration_s > 0 ? args.duration_s
                                        : (args.requests > 0 ? 0.0 : kDefaultDurationS);
  spec.deadline_ms = args.connection.deadline_ms;
  spec.health_service = args.service;

  if (spec.rpc != LoadRpc::kHealth) {
    if (!args.request_path.empty()) {
      absl::StatusOr<std::string> text = ReadInput(args.request_path);
      if (!text.ok()) return text.status();
      absl::StatusOr<v1::PlanRequest> request = api::ParsePlanRequestJson(*text);
      if (!request.ok()) return request.status();
      spec.requests.push_back(*std::move(request));
    } else {
      spec.requests = RandomRequestMix(args.seed, args.mix_size);
    }
  }
  if (spec.rate > 0 && spec.rpc == LoadRpc::kStream) {
    return absl::InvalidArgumentError(
        "--rate: open loop is for --rpc plan or health; streams run closed loop");
  }
  if (spec.rate > 0 && spec.engine == LoadEngine::kSync) {
    return absl::InvalidArgumentError("--rate: open loop needs --engine callback");
  }
  return spec;
}

// 0 when every call succeeded; otherwise one line on stderr and the exit
// code of the most frequent failure (cli_common.h).
int ExitCodeForFailedCalls(const LoadReport& report) {
  if (report.ok == report.requests) return kExitOk;
  auto worst = std::max_element(report.errors.begin(), report.errors.end(),
                                [](const auto& a, const auto& b) { return a.second < b.second; });
  std::cerr << "error: " << (report.requests - report.ok) << " of " << report.requests
            << " calls failed, most with " << worst->first << std::endl;
  for (int code = 0; code <= static_cast<int>(absl::StatusCode::kUnauthenticated); ++code) {
    if (StatusCodeName(static_cast<grpc::StatusCode>(code)) == worst->first) {
      return ExitCodeFor(static_cast<absl::StatusCode>(code));
    }
  }
  return kExitFailure;
}

}  // namespace

CLI::App* AddLoadCommand(CLI::App& app, LoadArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "load", "Load-test tactforce-server: throughput and latency percentiles");
  AddConnectionFlags(cmd, &args.connection, "--target,--server", /*default_deadline_ms=*/10'000);
  cmd->add_option("--rpc", args.rpc,
                  "plan (unary Plan), stream (PlanStream, one stream per concurrency slot, "
                  "next request after each response) or health (grpc.health.v1 Check: "
                  "transport-only baseline)")
      ->check(CLI::IsMember({"plan", "stream", "health"}))
      ->capture_default_str();
  cmd->add_option("--concurrency,-c", args.concurrency,
                  "Calls in flight (closed loop; default 1), or the most calls in flight "
                  "with --rate (default 1000)")
      ->check(CLI::Range(1, 100'000));
  cmd->add_option("--rate", args.rate,
                  "Open loop: start this many calls per second on a fixed schedule; latency "
                  "counts from the scheduled start (plan and health only)")
      ->check(CLI::Range(0.0, 10'000'000.0));
  cmd->add_option("--requests,-n", args.requests, "Stop after this many calls")
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 40));
  cmd->add_option("--duration", args.duration_s,
                  "Stop starting calls after this many seconds (default 10 without "
                  "--requests; with both, whichever comes first)")
      ->type_name("SECONDS")
      ->check(CLI::Range(0.001, 86'400.0));
  CLI::Option* request =
      cmd->add_option("--request", args.request_path,
                      "Send this PlanRequest (JSON file, - for stdin) in every call")
          ->type_name("FILE");
  CLI::Option* mix = cmd->add_flag(
      "--mix", args.mix,
      "Send a mix of seeded random grasps (2-6 contacts, SOLVER_GEOMETRIC); the default");
  request->excludes(mix);
  cmd->add_option("--seed", args.seed, "Seed of --mix")->capture_default_str();
  cmd->add_option("--mix-size", args.mix_size, "Distinct requests in --mix")
      ->check(CLI::Range(1, 1'000'000))
      ->capture_default_str();
  cmd->add_option("--service", args.service, "--rpc health: service to ask about")
      ->type_name("NAME");
  cmd->add_option("--engine", args.engine,
                  "callback: gRPC's callback API (all slots on gRPC's threads); sync: one "
                  "thread per slot with blocking calls (closed loop only)")
      ->check(CLI::IsMember({"callback", "sync"}))
      ->capture_default_str();
  cmd->add_option("--channels", args.channels,
                  "Channels (TCP connections) per target; calls are spread over them")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  cmd->add_flag("--json", args.json,
                "Print one JSON object: {rpc, concurrency, requests, duration_s, qps, "
                "latency_us: {p50, p90, p99, p999, max}, errors: {CODE: n}, ...}");
  cmd->add_flag("--progress", args.progress,
                "Progress line on stderr every second after 2 s even when stderr is not a "
                "terminal (on a terminal it is always shown)");
  cmd->footer(
      "--target takes one address, a comma-separated list of HOST:PORT (one channel\n"
      "each, calls spread round-robin by this client), or a gRPC URI such as\n"
      "ipv4:127.0.0.1:50051,127.0.0.1:50052 (one channel, gRPC's round_robin policy).\n"
      "Latency is measured per call (per response on streams) over successful calls,\n"
      "in microseconds; qps counts successful calls. Ctrl-C ends the run early and\n"
      "still prints the report.\n"
      "Exit status: 0 when every call succeeded; otherwise the code of the most\n"
      "frequent failure (3 unavailable, 4 deadline exceeded, 2 invalid request, 1\n"
      "other); 3 when a target cannot be reached before the run.");
  return cmd;
}

int RunLoadCommand(const LoadArgs& args) {
  absl::StatusOr<LoadSpec> spec = LoadSpecFromFlags(args);
  if (!spec.ok()) return ReportError(spec.status());
  absl::StatusOr<std::vector<std::shared_ptr<grpc::Channel>>> channels =
      ConnectLoadChannels(args.connection, args.connection.server, args.channels, *spec);
  if (!channels.ok()) return ReportError(channels.status());

  const bool tty = isatty(STDERR_FILENO) == 1;
  ProgressPrinter printer(tty);
  if (tty || args.progress) {
    spec->progress = [&printer](const LoadProgress& p) { printer.Update(p); };
  }
  g_interrupted = 0;
  spec->interrupted = [] { return g_interrupted != 0; };
  const auto previous = std::signal(SIGINT, OnInterrupt);
  absl::StatusOr<LoadReport> report = RunLoad(*spec, *channels);
  std::signal(SIGINT, previous);
  printer.Finish();
  if (!report.ok()) return ReportError(report.status());

  std::cout << (args.json ? FormatLoadJson(*report, args.connection.server)
                          : FormatLoadText(*report, args.connection.server));
  std::cout.flush();
  if (!std::cout) return kExitFailure;
  return ExitCodeForFailedCalls(*report);
}

}  // namespace tactforce::cli
