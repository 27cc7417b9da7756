#!/usr/bin/env python3
"""Overload, soak and deadline runs of a local tactforce-server driven by
`tactforce load`, with the server's RSS sampled and its health checked every
second; a JSON summary and a short table. Called by scripts/soak.sh (which
documents the flags). Exit 0 when every pass criterion holds, 1 when one
fails, 2 when the run could not be set up."""

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from procs import Load, Monitor, Server, SetupError  # noqa: E402
from table import format_table  # noqa: E402
from attack import run_memory, run_stops  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
OVERLOAD_REQUESTS = os.path.join(HERE, "overload_requests.json")
SOAK_PLAN_REQUESTS = os.path.join(HERE, "soak_plan_requests.json")
CYLINDER_IPOPT = os.path.join(HERE, "cylinder_4f_ipopt.json")

OVERLOAD_S, OVERLOAD_CONCURRENCY = 60.0, 64
OVERLOAD_FLAGS = ["--workers", "1", "--queue", "4", "--log-level", "warn"]
SOAK_S, SOAK_REF_S, SOAK_GROWTH_LIMIT_PCT = 120.0, 10.0, 10.0
SOAK_LOADS = [  # name, load arguments (each at concurrency 4)
    ("plan", ["--rpc", "plan", "--request", SOAK_PLAN_REQUESTS]),
    ("stream", ["--rpc", "stream", "--mix"]),
    ("estimate", ["--rpc", "estimate"]),
    ("fit-inertia", ["--rpc", "fit-inertia"]),
]
SOAK_CONCURRENCY = 4
LANE_GEOMETRIC = os.path.join(HERE, "lane_geometric_16.json")
LANE_IPOPT = os.path.join(HERE, "lane_ipopt_64.json")
LANE_S, LANE_IPOPT_CALLERS, LANE_RATIO_LIMIT = 20.0, 2, 3.0
DEADLINES_MS, DEADLINE_CALLS, DEADLINE_CONCURRENCY, DEADLINE_SLACK_MS = (1, 10, 100), 200, 4, 5.0
MIN_CALLS = 10


def ms(us):
    return round(us / 1000.0, 3)


def latency_ms(latency):
    """load's latency_us {p50, ..., max} in ms."""
    return {k: ms(v) for k, v in (latency or {}).items()}


def load_failure(result):
    """A load run that printed no report: the reason."""
    return f"load exit {result['exit_code']}: {result['stderr']}"


def stop_server(server, monitor):
    """Monitor stopped, liveness and peak RSS read, then SIGTERM: the
    server's part of every summary."""
    monitor.stop()
    alive = server.alive()
    peak = max([server.peak_rss_kb() or 0] + [kb for _, kb in monitor.rss])
    exit_code = server.stop()
    return {"server_alive_at_end": alive, "server_exit_code": exit_code,
            "clean_exit": exit_code == 0, "rss_peak_kb": peak,
            "health": monitor.health_summary(), "server_log_tail": server.log_tail(3)}


def run_overload(cfg):
    """Workers 1, queue 4; Ipopt and cross-check Plans at concurrency 64."""
    duration = OVERLOAD_S * cfg.scale
    server = Server(cfg.bin, OVERLOAD_FLAGS, os.path.join(cfg.work, "overload-server.log"))
    monitor = Monitor(server, cfg.tactforce).start()
    load = Load(cfg.tactforce, server.address,
                ["--rpc", "plan", "--request", OVERLOAD_REQUESTS, "-c", str(OVERLOAD_CONCURRENCY),
                 "--duration", f"{duration:g}"], "overload", cfg.work)
    result = load.result(duration + 120)
    out = {"server_flags": OVERLOAD_FLAGS, "concurrency": OVERLOAD_CONCURRENCY,
           "duration_s": duration, "requests_file": os.path.relpath(OVERLOAD_REQUESTS, cfg.root)}
    out.update(stop_server(server, monitor))
    report = result["report"]
    if report is None:
        out.update({"load_error": load_failure(result), "pass": False})
        return out
    errors = dict(report.get("errors", {}))
    exhausted = errors.pop("RESOURCE_EXHAUSTED", 0)
    out.update({"calls": report["requests"], "accepted": report["ok"],
                "resource_exhausted": exhausted, "other_errors": errors,
                "accepted_qps": report["qps"], "load_duration_s": report["duration_s"],
                "accepted_latency_ms": latency_ms(report["latency_us"]),
                "all_latency_ms": latency_ms(report.get("latency_all_us"))})
    out["pass"] = (out["server_alive_at_end"] and out["clean_exit"] and
                   out["health"]["all_serving"] and out["accepted"] > 0 and not errors)
    return out


def rss_growth(samples, ref_s):
    """RSS at the first sample at or after `ref_s`, at the end, and the
    growth (end - ref) / ref in %."""
    ref = next((s for s in samples if s[0] >= ref_s), samples[-1] if samples else None)
    end = samples[-1] if samples else None
    if not ref or not end or ref[1] <= 0:
        return {"rss_ref_s": ref_s, "rss_at_ref_kb": None, "rss_end_kb": None,
                "rss_growth_pct": None}
    return {"rss_ref_s": ref_s, "rss_ref_sample_s": ref[0], "rss_at_ref_kb": ref[1],
            "rss_end_kb": end[1], "rss_growth_pct": round(100.0 * (end[1] - ref[1]) / ref[1], 2)}


def soak_rpc_summary(name, result):
    """One soak load's calls, ok and errors (a load that printed no report
    counts as one error)."""
    report = result["report"]
    if report is None:
        return {"calls": 0, "ok": 0, "errors": {"LOAD_FAILED": 1}, "error_count": 1,
                "load_error": load_failure(result)}
    errors = report.get("errors", {})
    return {"calls": report["requests"], "ok": report["ok"], "errors": errors,
            "error_count": report["requests"] - report["ok"], "qps": report["qps"],
            "latency_ms": latency_ms(report["latency_us"])}


def run_soak(cfg):
    """Plan, PlanStream, EstimateForces, FitInertia at 4 x concurrency 4."""
    duration = SOAK_S * cfg.scale
    ref_s = max(1.0, SOAK_REF_S * cfg.scale)
    server = Server(cfg.bin, ["--log-level", "warn"], os.path.join(cfg.work, "soak-server.log"))
    monitor = Monitor(server, cfg.tactforce).start()
    loads = [Load(cfg.tactforce, server.address,
                  [*args, "-c", str(SOAK_CONCURRENCY), "--duration", f"{duration:g}"],
                  f"soak-{name}", cfg.work) for name, args in SOAK_LOADS]
    rpcs = {name: soak_rpc_summary(name, load.result(duration + 120))
            for (name, _), load in zip(SOAK_LOADS, loads)}
    out = {"duration_s": duration, "concurrency_per_rpc": SOAK_CONCURRENCY,
           "calls_per_rpc": {n: r["calls"] for n, r in rpcs.items()}, "rpcs": rpcs,
           "errors": sum(r["error_count"] for r in rpcs.values())}
    out.update(stop_server(server, monitor))
    out.update(rss_growth(monitor.rss, ref_s))
    out["rss_samples"] = monitor.rss
    out["growth_limit_pct"] = SOAK_GROWTH_LIMIT_PCT
    growth = out["rss_growth_pct"]
    out["rss_ok"] = growth is not None and growth < SOAK_GROWTH_LIMIT_PCT
    out["pass"] = (out["errors"] == 0 and out["rss_ok"] and out["server_alive_at_end"] and
                   out["clean_exit"] and out["health"]["all_serving"])
    return out


PLAN_LOG = re.compile(r"rpc=Plan .*?code=(\w+).*? total_us=(\d+)(.*)")
SOLVING = re.compile(r"after (\d+) us of solving")


def percentile(values, q):
    values = sorted(values)
    return values[min(len(values) - 1, int(q * len(values)))] if values else None


def server_side_times(log_path, offset, deadline_ms):
    """The server's own `rpc=Plan ... total_us=` log lines after byte
    `offset` (the run's calls and load's warm-up calls): codes, and for the
    calls that failed (deadline exceeded, cancelled) how long the server
    held them and how long their solve ran before it noticed. (summary, new
    offset)."""
    with open(log_path, errors="replace") as f:
        f.seek(offset)
        text = f.read()
        offset = f.tell()
    codes, failed_ms, solving_ms, before_solve = {}, [], [], 0
    for code, total_us, rest in PLAN_LOG.findall(text):
        codes[code] = codes.get(code, 0) + 1
        if code == "OK":
            continue
        failed_ms.append(int(total_us) / 1000.0)
        solving = SOLVING.search(rest)
        if solving:
            solving_ms.append(int(solving.group(1)) / 1000.0)
        before_solve += "before the solve started" in rest
    worst = max(failed_ms, default=None)
    return {"codes": codes, "failed_calls": len(failed_ms),
            "failed_before_solve": before_solve,
            "failed_max_ms": worst, "failed_p99_ms": percentile(failed_ms, 0.99),
            "failed_overrun_ms": None if worst is None else round(worst - deadline_ms, 3),
            "solving_before_stop_max_ms": max(solving_ms, default=None),
            "solving_before_stop_p50_ms": percentile(solving_ms, 0.5)}, offset


def deadline_run(cfg, server, deadline_ms, calls, offset):
    """`calls` Ipopt cylinder plans with --deadline-ms `deadline_ms`."""
    load = Load(cfg.tactforce, server.address,
                ["--rpc", "plan", "--request", CYLINDER_IPOPT, "--deadline-ms", str(deadline_ms),
                 "-n", str(calls), "-c", str(DEADLINE_CONCURRENCY)],
                f"deadline-{deadline_ms}ms", cfg.work)
    result = load.result(calls * (deadline_ms / 1000.0 + 1) + 120)
    cpu_before = server.cpu_s() or 0.0
    time.sleep(0.5)  # does the server keep solving abandoned calls?
    cpu_after = server.cpu_s() or 0.0
    server_side, offset = server_side_times(server.log_path, offset, deadline_ms)
    out = {"deadline_ms": deadline_ms, "server": server_side,
           "server_cpu_ms_in_0.5s_after": round((cpu_after - cpu_before) * 1000, 1)}
    report = result["report"]
    if report is None:
        out.update({"load_error": load_failure(result), "pass": False})
        return out, offset
    done = latency_ms(report.get("latency_all_us"))
    out.update({"calls": report["requests"], "ok": report["ok"], "errors": report["errors"],
                "completion_ms": done, "max_ms": done.get("max"), "p99_ms": done.get("p99"),
                "worst_overshoot_ms": round(done.get("max", 0) - deadline_ms, 3)})
    out["pass"] = out["worst_overshoot_ms"] <= DEADLINE_SLACK_MS and out["calls"] == calls
    return out, offset


def run_deadlines(cfg):
    """1, 10 and 100 ms deadlines on Ipopt solves of the 4-finger cylinder."""
    calls = max(MIN_CALLS, round(DEADLINE_CALLS * cfg.scale))
    log_path = os.path.join(cfg.work, "deadlines-server.log")
    server = Server(cfg.bin, ["--log-level", "info"], log_path)
    monitor = Monitor(server, cfg.tactforce).start()
    runs, offset = {}, 0
    for deadline_ms in DEADLINES_MS:
        runs[f"{deadline_ms}ms"], offset = deadline_run(cfg, server, deadline_ms, calls, offset)
    out = {"calls_per_deadline": calls, "concurrency": DEADLINE_CONCURRENCY,
           "slack_ms": DEADLINE_SLACK_MS, "deadlines": runs,
           "requests_file": os.path.relpath(CYLINDER_IPOPT, cfg.root)}
    out.update(stop_server(server, monitor))
    out["worst_overshoot_ms"] = max((r.get("worst_overshoot_ms", float("inf"))
                                     for r in runs.values()), default=None)
    out["pass"] = (all(r["pass"] for r in runs.values()) and out["server_alive_at_end"] and
                   out["clean_exit"] and out["health"]["all_serving"])
    return out


def geometric_load(cfg, server, duration, name):
    return Load(cfg.tactforce, server.address,
                ["--rpc", "plan", "--request", LANE_GEOMETRIC, "-c", "1", "--duration",
                 f"{duration:g}"], name, cfg.work)


def run_lane(cfg):
    """Pooled geometric plans (16 contacts, one caller) alone, then beside
    two callers of slow Ipopt plans (64 contacts, exact cones): the Ipopt
    lane keeps the geometric p99 within LANE_RATIO_LIMIT of its p99 alone."""
    duration = max(1.0, LANE_S * cfg.scale)
    server = Server(cfg.bin, ["--log-level", "warn"], os.path.join(cfg.work, "lane-server.log"))
    monitor = Monitor(server, cfg.tactforce).start()
    alone = soak_rpc_summary("alone", geometric_load(cfg, server, duration, "lane-alone")
                             .result(duration + 120))
    ipopt = Load(cfg.tactforce, server.address,
                 ["--rpc", "plan", "--request", LANE_IPOPT, "-c", str(LANE_IPOPT_CALLERS),
                  "--duration", f"{duration + 2:g}"], "lane-ipopt", cfg.work)
    time.sleep(1.0)  # both Ipopt callers busy before the measurement starts
    beside = soak_rpc_summary("beside", geometric_load(cfg, server, duration, "lane-beside")
                              .result(duration + 120))
    slow = soak_rpc_summary("ipopt", ipopt.result(duration + 120))
    out = {"duration_s": duration, "geometric_alone": alone, "geometric_beside_ipopt": beside,
           "ipopt": slow, "ipopt_callers": LANE_IPOPT_CALLERS, "ratio_limit": LANE_RATIO_LIMIT,
           "requests": [os.path.relpath(f, cfg.root) for f in (LANE_GEOMETRIC, LANE_IPOPT)]}
    out.update(stop_server(server, monitor))
    p99_alone = alone.get("latency_ms", {}).get("p99")
    p99_beside = beside.get("latency_ms", {}).get("p99")
    out["p99_ratio"] = (round(p99_beside / p99_alone, 2) if p99_alone and p99_beside else None)
    out["pass"] = (out["p99_ratio"] is not None and out["p99_ratio"] <= LANE_RATIO_LIMIT and
                   alone["error_count"] == 0 and beside["error_count"] == 0 and
                   slow["error_count"] == 0 and out["server_alive_at_end"] and out["clean_exit"])
    return out


def machine(cfg):
    model = ""
    try:
        with open("/proc/cpuinfo") as f:
            model = next((l.split(":", 1)[1].strip() for l in f if l.startswith("model name")), "")
    except OSError:
        pass
    mem_kb = None
    try:
        with open("/proc/meminfo") as f:
            mem_kb = int(next(l for l in f if l.startswith("MemTotal")).split()[1])
    except (OSError, StopIteration, ValueError):
        pass
    try:
        head = subprocess.run(["git", "-C", cfg.root, "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        head = ""
    return {"cores": os.cpu_count(), "cpu_model": model, "mem_total_kb": mem_kb,
            "git_head": head,
            "kernel": platform.release(), "load_avg_at_start": list(os.getloadavg()),
            "duration_scale": cfg.scale, "bin_dir": cfg.bin}


MODES = {"overload": run_overload, "soak": run_soak, "deadlines": run_deadlines, "lane": run_lane,
         "memory": run_memory, "stops": run_stops}
ALL_MODES = ("overload", "soak", "deadlines")  # `all`; the others run on their own


def parse_args(argv):
    root = os.path.dirname(os.path.dirname(HERE))
    p = argparse.ArgumentParser(prog="scripts/soak.sh", description=__doc__)
    p.add_argument("mode", choices=[*MODES, "all"])
    p.add_argument("--duration-scale", dest="scale", type=float, default=1.0,
                   help="multiplies the 60 s / 120 s durations and the 200 calls per deadline")
    p.add_argument("--bin", default=os.path.join(root, "build", "bin"),
                   help="folder with tactforce and tactforce-server (default build/bin)")
    p.add_argument("--out", help="JSON summary (default $TMPDIR/tactforce-soak-MODE.json)")
    p.add_argument("--keep-logs", metavar="DIR",
                   help="write the server logs and load outputs into DIR and keep them")
    cfg = p.parse_args(argv)
    if not 0 < cfg.scale <= 100:
        p.error("--duration-scale: must be > 0 and <= 100")
    cfg.root = root
    cfg.bin = os.path.abspath(cfg.bin)
    cfg.tactforce = os.path.join(cfg.bin, "tactforce")
    if not os.access(cfg.tactforce, os.X_OK):
        p.error(f"--bin: {cfg.tactforce} not found or not executable")
    cfg.out = cfg.out or os.path.join(tempfile.gettempdir(), f"tactforce-soak-{cfg.mode}.json")
    return cfg


def main(argv):
    cfg = parse_args(argv)
    summary = {"machine": machine(cfg)}
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="tactforce-soak-") as work:
        cfg.work = work
        if cfg.keep_logs:
            cfg.work = cfg.keep_logs
            os.makedirs(cfg.work, exist_ok=True)
        for mode in ALL_MODES if cfg.mode == "all" else [cfg.mode]:
            try:
                summary[mode] = MODES[mode](cfg)
            except SetupError as error:
                print(f"soak: {mode}: {error}", file=sys.stderr)
                return 2
    summary["wall_s"] = round(time.monotonic() - start, 1)
    summary["machine"]["load_avg_at_end"] = list(os.getloadavg())
    summary["pass"] = all(summary[m]["pass"] for m in MODES if m in summary)
    with open(cfg.out + ".tmp", "w") as f:
        json.dump(summary, f, indent=1)
        f.write("\n")
    os.replace(cfg.out + ".tmp", cfg.out)
    print(format_table(summary))
    print(f"summary: {cfg.out}")
    return 0 if summary["pass"] else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
