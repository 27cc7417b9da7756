"""Plan against the gRPC floor (issue 29): how much more a Plan call costs
than a health check on one local tactforce-server. scripts/plan_floor.sh
documents the modes and the output. Standard library only (and valgrind's
callgrind_control / callgrind_annotate for `instructions`)."""

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from procs import Load, Server, SetupError, read_cpu_times  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RPCS = ("health", "plan")
# What `tactforce load --rpc plan` sends without --request: its random mix,
# 256 distinct seeded grasps (seed 1) of 2-6 contacts, SOLVER_GEOMETRIC,
# default options (12-sided pyramids, kappa 1), sent in turn.
PLAN_REQUEST = "the load tester's default --mix: 256 seeded random grasps (seed 1), 2-6 " \
               "contacts, SOLVER_GEOMETRIC, 12-sided pyramids, no parameter uncertainty"
# Server functions whose inclusive instructions split a Plan call (the
# first match of each prefix in callgrind_annotate's inclusive listing).
HANDLER = "tactforce::server::PlannerService::Plan("
SOLVE = "tactforce::planner::Plan("
SPLIT = {
    "handler": HANDLER,
    "solve": SOLVE,
    "prepare": "tactforce::api::PreparePlan(",
    "to_proto": "tactforce::api::ToProto(tactforce::planner::PlanResult const&, "
                "tactforce::v1::PlanResponse*)",
    "request_parse": "tactforce::v1::PlanRequest::_InternalParse(",
    "response_serialize": "tactforce::v1::PlanResponse::_InternalSerialize(",
}


def load_run(cfg, address, rpc, concurrency, args, name, prefix=()):
    argv = ["--rpc", rpc, "-c", str(concurrency), *args]
    result = Load(cfg.tactforce, address, argv, name, cfg.workdir, prefix).result(cfg.timeout_s)
    report = result["report"]
    if result["exit_code"] != 0 or report is None or report["ok"] != report["requests"]:
        raise SetupError(f"load {name} failed (exit {result['exit_code']}): {result['stderr']}")
    return report


def children_cpu():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime, usage.ru_stime


def timed_run(cfg, server, rpc, concurrency, name):
    """One load run with QPS, load average and the CPU time per call of the
    server and of the load tester (user and system, microseconds)."""
    load_average = os.getloadavg()[0]
    server0, client0 = read_cpu_times(server.pid), children_cpu()
    report = load_run(cfg, server.address, rpc, concurrency, ["--duration", str(cfg.duration)],
                      name)
    server1, client1 = read_cpu_times(server.pid), children_cpu()
    calls = report["ok"]
    per_call = [1e6 * (b - a) / calls for a, b in zip(server0 + client0, server1 + client1)]
    return {"rpc": rpc, "concurrency": concurrency, "qps": report["qps"],
            "p50_us": report["latency_us"]["p50"], "calls": calls,
            "load_average": load_average,
            "server_user_us": per_call[0], "server_sys_us": per_call[1],
            "client_user_us": per_call[2], "client_sys_us": per_call[3]}


def qps_mode(cfg):
    """Health and plan alternated `rounds` times at each concurrency, on one
    server; best of the rounds per RPC."""
    server = Server(cfg.server_bin, ["--log-level", "warn"], os.path.join(cfg.workdir, "server.log"))
    out = {}
    try:
        for c in cfg.concurrency:
            runs = []
            for r in range(cfg.rounds):
                for rpc in RPCS:
                    runs.append(timed_run(cfg, server, rpc, c, f"{rpc}-c{c}-{r}"))
            out[f"c{c}"] = summarize_runs(runs)
    finally:
        server.stop()
    return out


def summarize_runs(runs):
    best = {rpc: max(r["qps"] for r in runs if r["rpc"] == rpc) for rpc in RPCS}
    cpu = {}
    for rpc in RPCS:
        mine = [r for r in runs if r["rpc"] == rpc]
        cpu[rpc] = {k: sorted(r[k] for r in mine)[len(mine) // 2]
                    for k in ("server_user_us", "server_sys_us", "client_user_us",
                              "client_sys_us")}
        cpu[rpc]["total_us"] = sum(cpu[rpc].values())
    pairs = [p["qps"] / h["qps"] for h, p in zip(runs[0::2], runs[1::2])]
    return {"runs": runs, "best_qps": best, "ratio_best_of_rounds": best["plan"] / best["health"],
            "ratio_per_round": pairs, "median_cpu_per_call": cpu,
            "ratio_cpu_bound": cpu["health"]["total_us"] / cpu["plan"]["total_us"]}


def callgrind_totals(path):
    for line in open(path):
        if line.startswith(("summary:", "totals:")):
            return int(line.split()[1])
    raise SetupError(f"{path}: no totals line")


def inclusive_costs(path, prefixes):
    """Inclusive instructions of the first function matching each prefix."""
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", path],
                          capture_output=True, text=True, check=True).stdout
    costs = {name: 0 for name in prefixes}
    for line in text.splitlines():
        m = re.match(r"^\s*([\d,]+)\s+(?:\([^)]*\)\s+)?(?:\S*?:)?(.*)$", line)
        if not m:
            continue
        for name, prefix in prefixes.items():
            if costs[name] == 0 and prefix in m.group(2):
                costs[name] = int(m.group(1).replace(",", ""))
    return costs


def newest_dump(directory, stem):
    dumps = [os.path.join(directory, f) for f in os.listdir(directory) if f.startswith(stem)]
    return max(dumps, key=os.path.getmtime)


def server_counts(cfg, server, rpc, calls):
    """Server instructions over `calls` calls: zeroed, run, dumped."""
    subprocess.run(["callgrind_control", "-z", str(server.pid)], capture_output=True, check=True)
    load_run(cfg, server.address, rpc, cfg.callgrind_concurrency, ["-n", str(calls)],
             f"cg-server-{rpc}-{calls}")
    subprocess.run(["callgrind_control", "-d", str(server.pid)], capture_output=True, check=True)
    time.sleep(0.5)
    path = newest_dump(cfg.workdir, f"server.{server.pid}")
    counts = inclusive_costs(path, SPLIT) if rpc == "plan" else {}
    counts["total"] = callgrind_totals(path)
    return counts


def client_counts(cfg, address, rpc, calls):
    """Load tester instructions of a whole run of `calls` calls."""
    path = os.path.join(cfg.workdir, f"client.{rpc}.{calls}")
    load_run(cfg, address, rpc, cfg.callgrind_concurrency, ["-n", str(calls)],
             f"cg-client-{rpc}-{calls}",
             prefix=["valgrind", "--tool=callgrind", f"--callgrind-out-file={path}"])
    return {"total": callgrind_totals(path)}


def per_call(small, large, calls):
    """Instructions per call: the difference of a short and a long run, so
    start-up, connection and warm-up cancel."""
    return {k: (large[k] - small[k]) / (calls[1] - calls[0]) for k in large}


def instructions_mode(cfg):
    calls = (cfg.calls // 10, cfg.calls)
    out = {"calls": list(calls), "concurrency": cfg.callgrind_concurrency}
    prefix = ["valgrind", "--tool=callgrind", "--dump-instr=no",
              f"--callgrind-out-file={cfg.workdir}/server.%p"]
    server = Server(cfg.server_bin, ["--log-level", "warn"], os.path.join(cfg.workdir, "cg-server.log"),
                    start_timeout_s=180, prefix=prefix)
    try:
        out["server"] = {rpc: per_call(*(server_counts(cfg, server, rpc, n) for n in calls), calls)
                         for rpc in RPCS}
    finally:
        server.stop(timeout_s=120)
    native = Server(cfg.server_bin, ["--log-level", "warn"], os.path.join(cfg.workdir, "server2.log"))
    try:
        out["client"] = {rpc: per_call(*(client_counts(cfg, native.address, rpc, n)
                                         for n in calls), calls) for rpc in RPCS}
    finally:
        native.stop()
    plan = out["server"]["plan"]
    plan["ours"] = plan["handler"] - plan["solve"]
    plan["grpc_protobuf"] = plan["total"] - plan["handler"]
    health = out["server"]["health"]["total"] + out["client"]["health"]["total"]
    both = plan["total"] + out["client"]["plan"]["total"]
    out["ratio_instructions"] = health / both
    out["ratio_instructions_free_solve"] = health / (both - plan["solve"])
    # The solve that the targets leave room for, with everything else as now.
    out["solve_budget"] = {str(t): health / t - (both - plan["solve"]) for t in (0.8, 0.9)}
    return out


def k(x):
    return f"{x / 1000:.1f}k"


def print_tables(result):
    cg = result.get("instructions")
    if cg:
        s, c = cg["server"], cg["client"]
        p = s["plan"]
        print(f"Instructions per call (callgrind, c={cg['concurrency']}, "
              f"({cg['calls'][1]} - {cg['calls'][0]}) calls):")
        print("| per call | health | Plan |\n|---|---:|---:|")
        print(f"| server: gRPC + protobuf | {k(s['health']['total'])} | {k(p['grpc_protobuf'])} |")
        print(f"|   of which request parse / response serialize | - | "
              f"{k(p['request_parse'])} / {k(p['response_serialize'])} |")
        print(f"| server: ours (handler minus solve) | - | {k(p['ours'])} |")
        print(f"|   of which PreparePlan / ToProto(result) | - | "
              f"{k(p['prepare'])} / {k(p['to_proto'])} |")
        print(f"| server: the solve (planner::Plan) | - | {k(p['solve'])} |")
        print(f"| server total | {k(s['health']['total'])} | {k(p['total'])} |")
        print(f"| load tester total | {k(c['health']['total'])} | {k(c['plan']['total'])} |")
        print(f"CPU-bound ratio from instructions: {cg['ratio_instructions']:.3f} "
              f"(with a free solve {cg['ratio_instructions_free_solve']:.3f}); solve budget "
              f"for 0.8: {k(cg['solve_budget']['0.8'])}, for 0.9: {k(cg['solve_budget']['0.9'])}")
    for key, q in result.get("qps", {}).items():
        print(f"\nQPS {key} (plan request: {PLAN_REQUEST}):")
        print("| run | rpc | qps | p50 us | load avg | server user+sys us/call | "
              "client user+sys us/call |\n|---|---|---:|---:|---:|---:|---:|")
        for i, r in enumerate(q["runs"]):
            print(f"| {i // 2 + 1} | {r['rpc']} | {r['qps']:.0f} | {r['p50_us']:.0f} | "
                  f"{r['load_average']:.2f} | {r['server_user_us']:.1f}+{r['server_sys_us']:.1f} "
                  f"| {r['client_user_us']:.1f}+{r['client_sys_us']:.1f} |")
        print(f"best of {len(q['runs']) // 2}: plan/health = {q['ratio_best_of_rounds']:.3f}; "
              f"per round {', '.join(f'{x:.2f}' for x in q['ratio_per_round'])}; "
              f"CPU-time ratio (server+client, medians) {q['ratio_cpu_bound']:.3f}")


def parse_args(argv):
    p = argparse.ArgumentParser(prog="plan_floor.sh")
    p.add_argument("mode", choices=("all", "qps", "instructions"))
    p.add_argument("--bin", default=os.path.join(REPO, "build", "bin"))
    p.add_argument("--server-bin", default=None,
                   help="folder of the tactforce-server to measure (default: --bin's)")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--duration", type=float, default=3.0)
    p.add_argument("--concurrency", default="8,1")
    p.add_argument("--calls", type=int, default=2000)
    p.add_argument("--callgrind-concurrency", type=int, default=8)
    p.add_argument("--out", default=None)
    cfg = p.parse_args(argv)
    cfg.concurrency = [int(c) for c in cfg.concurrency.split(",")]
    cfg.tactforce = os.path.join(cfg.bin, "tactforce")
    cfg.server_bin = cfg.server_bin or cfg.bin
    cfg.timeout_s = 600
    return cfg


def main(argv):
    cfg = parse_args(argv)
    result = {"plan_request": PLAN_REQUEST, "cpus": os.cpu_count()}
    with tempfile.TemporaryDirectory(prefix="plan-floor-") as workdir:
        cfg.workdir = workdir
        try:
            if cfg.mode in ("all", "instructions"):
                result["instructions"] = instructions_mode(cfg)
            if cfg.mode in ("all", "qps"):
                result["qps"] = qps_mode(cfg)
        except (SetupError, subprocess.CalledProcessError) as error:
            print(f"plan_floor: {error}", file=sys.stderr)
            return 2
    print_tables(result)
    if cfg.out:
        with open(cfg.out, "w") as f:
            json.dump(result, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
