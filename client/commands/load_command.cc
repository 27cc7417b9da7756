// `tactforce load`: the flags (each numeric one checked with its name and
// range) to a LoadSpec (requests: load_requests.h), Ctrl-C and the progress
// line around RunLoad (load_generator.h), the report, the --plot SVG
// (load_plot.h), and the exit code of the most frequent failure.
#include "load_command.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "cli_common.h"
#include "load/load_generator.h"
#include "load/load_plot.h"
#include "load/load_requests.h"
#include "tactforce/io/status_macros.h"

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
    const std::string line = absl::StrFormat("load: %.0f s, %d calls (%d failed), %.0f calls/s",
                                             p.elapsed_s, p.completed, p.failed, p.recent_qps);
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

// "plan, stream, ..." (every --rpc value, joined by `separator`).
std::string RpcNames(const std::string& separator) {
  std::vector<std::string> names;
  for (LoadRpc rpc : kAllLoadRpcs) names.emplace_back(ToString(rpc));
  return absl::StrJoin(names, separator);
}

absl::StatusOr<LoadRpc> ParseRpc(const std::string& name) {
  for (LoadRpc rpc : kAllLoadRpcs) {
    if (name == ToString(rpc)) return rpc;
  }
  return absl::InvalidArgumentError(absl::StrCat("--rpc: expected ", RpcNames(", ")));
}

// Flags that only some RPCs use: InvalidArgument naming the flag when given
// with another.
absl::Status CheckFlagsForRpc(const LoadArgs& args, LoadRpc rpc) {
  const bool plan = rpc == LoadRpc::kPlan || rpc == LoadRpc::kStream;
  if (args.mix && !plan) {
    return absl::InvalidArgumentError(
        absl::StrCat("--mix: the random grasp mix is for --rpc plan or stream, not ", args.rpc));
  }
  if (!args.request_path.empty() && rpc == LoadRpc::kHealth) {
    return absl::InvalidArgumentError("--request: --rpc health sends no request");
  }
  if (args.batch > 0 && rpc != LoadRpc::kFitInertia) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--batch: for --rpc fit-inertia (a CSV log's samples per message), not ", args.rpc));
  }
  if (args.rate > 0 && rpc == LoadRpc::kStream) {
    return absl::InvalidArgumentError(
        "--rate: open loop is for one call per request (not --rpc stream); streams run closed "
        "loop");
  }
  if (args.rate > 0 && args.engine == "sync") {
    return absl::InvalidArgumentError("--rate: open loop needs --engine callback");
  }
  return absl::OkStatus();
}

// The run the flags ask for (requests read, built in or generated);
// InvalidArgument naming the flag for combinations that cannot run.
absl::StatusOr<LoadSpec> LoadSpecFromFlags(const LoadArgs& args) {
  LoadSpec spec;
  TF_ASSIGN_OR_RETURN(LoadRpc rpc, ParseRpc(args.rpc));
  TF_RETURN_IF_ERROR(CheckFlagsForRpc(args, rpc));
  spec.rpc = rpc;
  spec.engine = args.engine == "sync" ? LoadEngine::kSync : LoadEngine::kCallback;
  spec.rate = args.rate;
  spec.concurrency =
      args.concurrency > 0 ? args.concurrency : (args.rate > 0 ? kOpenLoopDefaultInFlight : 1);
  spec.max_requests = args.requests;
  spec.duration_s =
      args.duration_s > 0 ? args.duration_s : (args.requests > 0 ? 0.0 : kDefaultDurationS);
  spec.deadline_ms = args.connection.deadline_ms;
  spec.health_service = args.service;
  LoadRequestSource source;
  source.path = args.request_path;
  source.seed = args.seed;
  source.mix_size = args.mix_size;
  if (args.batch > 0) source.batch = args.batch;
  TF_RETURN_IF_ERROR(SetLoadRequests(source, &spec));
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

// A check that a flag's value is an integer in [lo, hi]; CLI11 prefixes the
// message with the flag: "--concurrency: must be an integer from 1 to
// 100000 (got '0')".
template <class Int>
CLI::Validator IntegerIn(Int lo, Int hi) {
  const std::string rule = hi == std::numeric_limits<Int>::max()
                               ? absl::StrCat("an integer >= ", lo)
                               : absl::StrCat("an integer from ", lo, " to ", hi);
  return CLI::Validator(
      [lo, hi, rule](std::string& text) -> std::string {
        Int value{};
        const char* end = text.data() + text.size();
        const auto [at, error] = std::from_chars(text.data(), end, value);
        if (error != std::errc() || at != end || value < lo || value > hi) {
          return absl::StrCat("must be ", rule, " (got '", text, "')");
        }
        return "";
      },
      rule);
}

// A check that a flag's value is a finite number above `lo` (or at least
// `lo` when `lo_inclusive`) and at most `hi`: "--duration: must be a number
// > 0 and <= 86400 (got 'nan')".
CLI::Validator NumberIn(double lo, bool lo_inclusive, double hi) {
  const std::string rule =
      absl::StrFormat("a number %s %.10g and <= %.10g", lo_inclusive ? ">=" : ">", lo, hi);
  return CLI::Validator(
      [lo, lo_inclusive, hi, rule](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        const bool parsed = !text.empty() && end == text.c_str() + text.size();
        const bool above = lo_inclusive ? value >= lo : value > lo;
        if (!parsed || !std::isfinite(value) || !above || value > hi) {
          return absl::StrCat("must be ", rule, " (got '", text, "')");
        }
        return "";
      },
      rule);
}

// --rpc, --concurrency, --rate, --requests, --duration, --engine, --channels.
void AddWorkloadFlags(CLI::App* cmd, LoadArgs& args) {
  cmd->add_option("--rpc", args.rpc,
                  "plan (unary Plan), stream (PlanStream, one stream per concurrency slot, "
                  "next request after each response), health (grpc.health.v1 Check: "
                  "transport-only baseline), estimate (Estimator.EstimateForces), fit-inertia "
                  "(Estimator.FitInertia: one call streams the whole request stream) or audit "
                  "(Audit.AuditModel)")
      ->check(CLI::IsMember({"plan", "stream", "health", "estimate", "fit-inertia", "audit"}))
      ->capture_default_str();
  cmd->add_option("--concurrency,-c", args.concurrency,
                  "Calls in flight (closed loop; default 1), or the most calls in flight "
                  "with --rate (default 1000)")
      ->check(IntegerIn(1, 100'000));
  cmd->add_option("--rate", args.rate,
                  "Open loop: start this many calls per second on a fixed schedule; latency "
                  "counts from the scheduled start (every RPC but stream); 0 = closed loop")
      ->type_name("CALLS/S")
      ->check(NumberIn(0.0, true, 10'000'000.0));
  cmd->add_option("--requests,-n", args.requests, "Stop after this many calls")
      ->check(IntegerIn<int64_t>(1, int64_t{1} << 40));
  cmd->add_option("--duration", args.duration_s,
                  "Stop starting calls after this many seconds (default 10 without "
                  "--requests; with both, whichever comes first)")
      ->type_name("SECONDS")
      ->check(NumberIn(0.0, false, 86'400.0));
  cmd->add_option("--engine", args.engine,
                  "callback: gRPC's callback API (all slots on gRPC's threads); sync: one "
                  "thread per slot with blocking calls (closed loop only)")
      ->check(CLI::IsMember({"callback", "sync"}))
      ->capture_default_str();
  cmd->add_option("--channels", args.channels,
                  "Channels (TCP connections) per target; calls are spread over them")
      ->check(IntegerIn(1, 1024))
      ->capture_default_str();
}

// --request, --mix, --seed, --mix-size, --batch, --service.
void AddRequestFlags(CLI::App* cmd, LoadArgs& args) {
  CLI::Option* request =
      cmd->add_option("--request", args.request_path,
                      "What every call sends (- for stdin): plan/stream a PlanRequest JSON (or "
                      "a list, used in turn); "
                      "estimate an EstimateRequest JSON (or a JSON list, used in turn); audit "
                      "an AuditRequest JSON (or a list); fit-inertia a JSON list of "
                      "FitInertiaRequest messages (one call's stream) or an inertia CSV log. "
                      "Default: the random mix (plan/stream) or a built-in example")
          ->type_name("FILE");
  CLI::Option* mix = cmd->add_flag(
      "--mix", args.mix,
      "plan/stream: send a mix of seeded random grasps (2-6 contacts, SOLVER_GEOMETRIC); the "
      "default");
  request->excludes(mix);
  cmd->add_option("--seed", args.seed, "Seed of --mix")
      ->check(IntegerIn<uint64_t>(0, std::numeric_limits<uint64_t>::max()))
      ->capture_default_str();
  cmd->add_option("--mix-size", args.mix_size, "Distinct requests in --mix")
      ->check(IntegerIn(1, 1'000'000))
      ->capture_default_str();
  cmd->add_option("--batch", args.batch,
                  "fit-inertia with a CSV log: samples per streamed message (default 500, as "
                  "tactforce inertia)")
      ->check(IntegerIn(1, 1'000'000));
  cmd->add_option("--service", args.service, "--rpc health: service to ask about")
      ->type_name("NAME");
}

}  // namespace

CLI::App* AddLoadCommand(CLI::App& app, LoadArgs& args) {
  CLI::App* cmd =
      app.add_subcommand("load", "Load-test tactforce-server: throughput and latency percentiles");
  AddConnectionFlags(cmd, &args.connection, "--target,--server", /*default_deadline_ms=*/10'000);
  AddWorkloadFlags(cmd, args);
  AddRequestFlags(cmd, args);
  AddOutputFlags(
      cmd, &args.output,
      "one object {rpc, concurrency, requests, duration_s, qps, latency_us: {p50, p90, p99, p999, "
      "max}, latency_all_us: {p50, p90, p99, max}, errors: {CODE: n}, ...}");
  cmd->add_option("--plot", args.plot_path,
                  "Also write an SVG: the latency histogram (log scale) and calls/s over "
                  "time (0.1 s intervals; 1 s for runs over 20 s); the directory must exist")
      ->type_name("FILE.svg");
  cmd->add_flag("--progress", args.progress,
                "Progress line on stderr every second after 2 s even when stderr is not a "
                "terminal (on a terminal it is always shown)");
  cmd->footer(
      "--target takes one address, a comma-separated list of HOST:PORT (one channel\n"
      "each, calls spread round-robin by this client), or a gRPC URI such as\n"
      "ipv4:127.0.0.1:50051,127.0.0.1:50052 (one channel, gRPC's round_robin policy).\n"
      "Latency is measured per call (per response on streams; per whole stream for\n"
      "fit-inertia) over successful calls, in microseconds; qps counts successful calls;\n"
      "--json's latency_all_us is over every call, failed ones included.\n"
      "Ctrl-C ends the run early and still prints the report (and the plot).\n"
      "Exit status: 0 when every call succeeded; otherwise the code of the most\n"
      "frequent failure (3 unavailable, 4 deadline exceeded, 2 invalid request, 1\n"
      "other); 2 for a bad flag (the message names it); 3 when a target cannot be\n"
      "reached before the run. Examples:\n"
      "  tactforce load --target localhost:50051 --rpc plan --mix -c 8 --duration 5\n"
      "  tactforce load --target localhost:50051 --rpc estimate -c 4 --duration 3 --plot "
      "latency.svg --json\n"
      "  tactforce load --target localhost:50051 --rpc fit-inertia --request "
      "client/examples/inertia_log.csv -n 20");
  return cmd;
}

int RunLoadCommand(const LoadArgs& args) {
  absl::StatusOr<LoadSpec> spec = LoadSpecFromFlags(args);
  if (!spec.ok()) return ReportError(spec.status());
  if (!args.plot_path.empty()) {
    if (absl::Status s = CheckPlotPath(args.plot_path); !s.ok()) return ReportError(s);
  }
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

  std::cout << (args.output.json() ? FormatLoadJson(*report, args.connection.server)
                                   : FormatLoadText(*report, args.connection.server));
  std::cout.flush();
  if (!std::cout) return kExitFailure;
  if (!args.plot_path.empty()) {
    absl::Status s = WriteLoadPlot(*report, args.connection.server, args.plot_path);
    if (!s.ok()) return ReportError(s);
  }
  return ExitCodeForFailedCalls(*report);
}

}  // namespace tactforce::cli
