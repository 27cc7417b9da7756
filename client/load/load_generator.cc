// The load generator's front: checking a LoadSpec, choosing the engine
// (load_callback_engine.cc, load_sync_engine.cc), the report from the run's
// counters, latency histogram and timeline; connecting and warming up the
// channels (load_rpcs.h); the seeded request mix; the text and JSON
// reports.
#include "load_generator.h"

#include <algorithm>
#include <random>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "load_rpcs.h"
#include "remote_call.h"
#include "tactforce/api/convert.h"
#include "tactforce/io/json.h"
#include "tactforce/planner/random_grasps.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {
namespace {

using load_engine::Run;

constexpr int kMaxSyncThreads = 1024;
constexpr int kMinWarmUpDeadlineMs = 10'000;

// Whether `spec` has what its RPC sends.
bool HasRequests(const LoadSpec& spec) {
  switch (spec.rpc) {
    case LoadRpc::kPlan:
    case LoadRpc::kStream:
      return !spec.requests.empty();
    case LoadRpc::kHealth:
      return true;
    case LoadRpc::kEstimate:
      return !spec.estimate_requests.empty();
    case LoadRpc::kFitInertia:
      return !spec.fit_inertia_stream.empty();
    case LoadRpc::kAudit:
      return !spec.audit_requests.empty();
  }
  return false;
}

// InvalidArgument naming the flag when `spec` cannot run.
absl::Status CheckSpec(const LoadSpec& spec, size_t channels) {
  if (channels == 0) return absl::InvalidArgumentError("load: no target");
  if (spec.concurrency < 1) return absl::InvalidArgumentError("--concurrency: must be >= 1");
  if (spec.max_requests <= 0 && spec.duration_s <= 0) {
    return absl::InvalidArgumentError("load: give --requests and/or --duration");
  }
  if (!HasRequests(spec)) return absl::InvalidArgumentError("load: no request to send");
  const bool open_loop = spec.rate > 0;
  if (open_loop && spec.rpc == LoadRpc::kStream) {
    return absl::InvalidArgumentError(
        "--rate: open loop is for one call per request (not --rpc stream); streams run closed "
        "loop");
  }
  if (open_loop && spec.engine == LoadEngine::kSync) {
    return absl::InvalidArgumentError("--rate: open loop needs --engine callback");
  }
  if (spec.engine == LoadEngine::kSync && spec.concurrency > kMaxSyncThreads) {
    return absl::InvalidArgumentError(absl::StrCat("--concurrency: at most ", kMaxSyncThreads,
                                                   " with --engine sync (one thread each)"));
  }
  return absl::OkStatus();
}

// The run's counters and latency histogram as a report.
LoadReport MakeReport(const LoadSpec& spec, const Run& run, int channels, bool interrupted) {
  LoadReport report;
  report.rpc = ToString(spec.rpc);
  report.mode = spec.rate > 0 ? "open" : "closed";
  report.engine = ToString(spec.engine);
  report.concurrency = spec.concurrency;
  report.rate = spec.rate;
  report.channels = channels;
  report.requests = run.completed.load();
  report.ok = run.ok.load();
  const int64_t last = run.last_done_ns.load();
  const int64_t end_ns = last > 0 ? last : load_engine::NowNs();
  report.duration_s = (end_ns - run.start_ns) * 1e-9;
  report.qps = report.duration_s > 0 ? report.ok / report.duration_s : 0.0;
  const LatencyHistogram& h = run.histogram;
  report.p50_us = h.Quantile(0.50) * 1e-3;
  report.p90_us = h.Quantile(0.90) * 1e-3;
  report.p99_us = h.Quantile(0.99) * 1e-3;
  report.p999_us = h.Quantile(0.999) * 1e-3;
  report.max_us = h.max() * 1e-3;
  const LatencyHistogram& all = run.all_histogram;
  report.all_p50_us = all.Quantile(0.50) * 1e-3;
  report.all_p90_us = all.Quantile(0.90) * 1e-3;
  report.all_p99_us = all.Quantile(0.99) * 1e-3;
  report.all_max_us = all.max() * 1e-3;
  for (int code = 0; code < load_engine::kCodeSlots; ++code) {
    const int64_t count = run.errors[code].load();
    if (count > 0) {
      report.errors[StatusCodeName(static_cast<grpc::StatusCode>(code))] += count;
    }
  }
  report.interrupted = interrupted;
  report.latency_bins = h.LogBins(kLatencyBinsPerDecade);
  report.timeline = run.timeline.Counts(end_ns - run.start_ns);
  return report;
}

// One unmeasured call of the kind `spec` makes (load_rpcs.h).
absl::Status WarmUpCall(const RemoteServer& server, const LoadSpec& spec) {
  return load_engine::VisitRpc(spec.rpc,
                               [&](auto rpc) { return decltype(rpc)::WarmUp(server, spec); });
}

std::string Number(double value) {
  // Latencies and rates: one decimal is plenty and keeps JSON readable.
  return absl::StrFormat("%.1f", value);
}

}  // namespace

absl::StatusOr<LoadReport> RunLoad(const LoadSpec& spec,
                                   const std::vector<std::shared_ptr<grpc::Channel>>& channels) {
  TF_RETURN_IF_ERROR(CheckSpec(spec, channels.size()));
  Run run(spec, channels);
  const int n = static_cast<int>(channels.size());
  bool interrupted = false;
  if (spec.rate > 0) {
    interrupted = load_engine::RunOpenLoop(run, n);
  } else if (spec.engine == LoadEngine::kSync) {
    interrupted = load_engine::RunSync(run, n);
  } else {
    interrupted = load_engine::RunClosedLoopCallback(run, n);
  }
  return MakeReport(spec, run, n, interrupted);
}

absl::StatusOr<std::vector<std::shared_ptr<grpc::Channel>>> ConnectLoadChannels(
    const ConnectionArgs& connection, const std::string& target_list, int per_target,
    const LoadSpec& spec) {
  TF_ASSIGN_OR_RETURN(std::vector<std::string> targets, SplitTargets(target_list));
  if (per_target < 1) return absl::InvalidArgumentError("--channels: must be >= 1");
  // The warm-up gets at least 10 s whatever --deadline-ms (0 = none), so a
  // run measuring short deadlines (--deadline-ms 1) still connects.
  const int deadline_ms = std::max(connection.deadline_ms, kMinWarmUpDeadlineMs);
  std::vector<std::shared_ptr<grpc::Channel>> channels;
  for (const std::string& target : targets) {
    // Addresses behind one target: the entries of an ipv4:/ipv6: list.
    const int addresses = HasUriScheme(target)
                              ? static_cast<int>(std::count(target.begin(), target.end(), ',')) + 1
                              : 1;
    for (int k = 0; k < per_target; ++k) {
      grpc::ChannelArguments args;
      // Without this, channels with equal arguments share one connection.
      args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
      if (HasUriScheme(target)) args.SetLoadBalancingPolicyName("round_robin");
      TF_ASSIGN_OR_RETURN(std::shared_ptr<grpc::Channel> channel,
                          MakeChannel(connection, target, args));
      // Warm-up, which also connects: the first call fails fast with the
      // reason (connection refused, TLS handshake) when the target cannot be
      // reached. round_robin connects to every address; a few calls make
      // sure each is used (and the request accepted) before measuring.
      const RemoteServer server(channel, target, deadline_ms);
      for (int i = 0; i < 2 * addresses; ++i) {
        TF_RETURN_IF_ERROR(WarmUpCall(server, spec));
      }
      channels.push_back(std::move(channel));
    }
  }
  return channels;
}

std::vector<v1::PlanRequest> RandomRequestMix(uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  std::vector<v1::PlanRequest> requests;
  requests.reserve(static_cast<size_t>(std::max(count, 0)));
  for (int i = 0; i < count; ++i) {
    const planner::RandomGrasp grasp = planner::MakeRandomGrasp(rng);
    requests.push_back(
        api::ToRequest(grasp.problem, planner::PlanOptions(), planner::SolverKind::kGeometric));
  }
  return requests;
}

std::string FormatLoadText(const LoadReport& r, const std::string& target) {
  std::string out =
      absl::StrFormat("tactforce load: %s -> %s, %s loop, %s %d", r.rpc, target, r.mode,
                      r.mode == "open" ? "at most" : "concurrency", r.concurrency);
  if (r.mode == "open") absl::StrAppendFormat(&out, " in flight, rate %g/s", r.rate);
  absl::StrAppendFormat(&out, ", %s API, %d channel%s%s\n", r.engine, r.channels,
                        r.channels == 1 ? "" : "s", r.interrupted ? " (interrupted)" : "");
  absl::StrAppendFormat(&out, "  calls       %d (%d ok, %d failed) in %.3f s\n", r.requests, r.ok,
                        r.requests - r.ok, r.duration_s);
  absl::StrAppendFormat(&out, "  throughput  %.1f calls/s\n", r.qps);
  absl::StrAppendFormat(&out, "  latency [us] %9s %9s %9s %9s %9s\n", "p50", "p90", "p99", "p99.9",
                        "max");
  absl::StrAppendFormat(&out, "               %9.1f %9.1f %9.1f %9.1f %9.1f\n", r.p50_us, r.p90_us,
                        r.p99_us, r.p999_us, r.max_us);
  if (r.ok < r.requests) {
    absl::StrAppendFormat(&out, "  all calls    %9.1f %9.1f %9.1f %9s %9.1f (failed included)\n",
                          r.all_p50_us, r.all_p90_us, r.all_p99_us, "", r.all_max_us);
  }
  if (r.errors.empty()) {
    out += "  errors      none\n";
  } else {
    out += "  errors     ";
    for (const auto& [code, count] : r.errors) absl::StrAppendFormat(&out, " %s=%d", code, count);
    out += "\n";
  }
  return out;
}

std::string FormatLoadJson(const LoadReport& r, const std::string& target) {
  std::string errors = "{";
  bool first = true;
  for (const auto& [code, count] : r.errors) {
    absl::StrAppendFormat(&errors, "%s%s: %d", first ? "" : ", ", io::JsonEscape(code), count);
    first = false;
  }
  errors += "}";
  std::string out = absl::StrFormat(
      "{\"rpc\": %s, \"target\": %s, \"mode\": %s, \"engine\": %s, \"concurrency\": %d, ",
      io::JsonEscape(r.rpc), io::JsonEscape(target), io::JsonEscape(r.mode),
      io::JsonEscape(r.engine), r.concurrency);
  if (r.mode == "open") absl::StrAppendFormat(&out, "\"rate\": %g, ", r.rate);
  absl::StrAppendFormat(&out,
                        "\"channels\": %d, \"requests\": %d, \"ok\": %d, \"duration_s\": %.4f, "
                        "\"qps\": %s, \"latency_us\": {\"p50\": %s, \"p90\": %s, \"p99\": %s, "
                        "\"p999\": %s, \"max\": %s}, \"errors\": %s",
                        r.channels, r.requests, r.ok, r.duration_s, Number(r.qps), Number(r.p50_us),
                        Number(r.p90_us), Number(r.p99_us), Number(r.p999_us), Number(r.max_us),
                        errors);
  absl::StrAppendFormat(&out,
                        ", \"latency_all_us\": {\"p50\": %s, \"p90\": %s, \"p99\": %s, "
                        "\"max\": %s}",
                        Number(r.all_p50_us), Number(r.all_p90_us), Number(r.all_p99_us),
                        Number(r.all_max_us));
  if (r.interrupted) out += ", \"interrupted\": true";
  out += "}";
  return io::IndentJson(out);
}

}  // namespace tactforce::cli
