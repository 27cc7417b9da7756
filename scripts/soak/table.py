"""The short human-readable table at the end of scripts/soak.sh."""


def _mb(kb):
    return "-" if kb is None else f"{kb / 1024:.1f} MB"


def _num(value, fmt="{:.1f}"):
    return "-" if value is None else fmt.format(value)


def _verdict(section):
    return "PASS" if section.get("pass") else "FAIL"


def _server_line(s):
    health = s["health"]
    return (f"    server alive at end {'yes' if s['server_alive_at_end'] else 'NO'}, exit "
            f"{s['server_exit_code']}, health {health['serving']}/{health['checks']} SERVING "
            f"(slowest {health['max_ms']:.0f} ms), peak RSS {_mb(s['rss_peak_kb'])}")


def _overload(s):
    if "load_error" in s:
        return [f"overload   {_verdict(s)}  {s['load_error']}", _server_line(s)]
    lat = s["accepted_latency_ms"]
    other = ", ".join(f"{k}={v}" for k, v in s["other_errors"].items()) or "none"
    return [f"overload   {_verdict(s)}  {s['calls']} calls in {s['duration_s']:g} s at c="
            f"{s['concurrency']}: {s['accepted']} accepted, {s['resource_exhausted']} "
            f"RESOURCE_EXHAUSTED, other errors {other}",
            f"    accepted latency p50 {_num(lat.get('p50'))} ms, p99 {_num(lat.get('p99'))} ms, "
            f"max {_num(lat.get('max'))} ms ({s['accepted_qps']:.1f} accepted/s)",
            _server_line(s)]


def _soak(s):
    calls = ", ".join(f"{k} {v}" for k, v in s["calls_per_rpc"].items())
    return [f"soak       {_verdict(s)}  {s['duration_s']:g} s: {calls}; errors {s['errors']}",
            f"    RSS at {s['rss_ref_s']:g} s {_mb(s['rss_at_ref_kb'])}, at end "
            f"{_mb(s['rss_end_kb'])}, growth {_num(s['rss_growth_pct'], '{:+.2f}')} % "
            f"(limit {s['growth_limit_pct']:g} %), {len(s['rss_samples'])} samples",
            _server_line(s)]


def _deadlines(s):
    lines = [f"deadlines  {_verdict(s)}  {s['calls_per_deadline']} Ipopt cylinder plans per "
             f"deadline at c={s['concurrency']}, pass = done by deadline + {s['slack_ms']:g} ms"]
    for name, r in s["deadlines"].items():
        if "load_error" in r:
            lines.append(f"    {name:>6}: {r['load_error']}")
            continue
        codes = ", ".join(f"{k}={v}" for k, v in r["errors"].items())
        codes = f"OK={r['ok']}" + (f", {codes}" if codes else "")
        lines.append(f"    {name:>6}: completion max {r['max_ms']:.2f} ms, p99 {r['p99_ms']:.2f} "
                     f"ms, overshoot {r['worst_overshoot_ms']:+.2f} ms ({codes})")
        srv = r["server"]
        if srv["failed_calls"]:
            held = _num(srv["failed_max_ms"], "{:.2f}")
            solving = _num(srv["solving_before_stop_max_ms"], "{:.2f}")
            lines.append(f"            server held failed calls up to {held} ms "
                         f"({srv['failed_before_solve']} of {srv['failed_calls']} stopped before "
                         f"the solve; solves ran up to {solving} ms before stopping)")
    lines.append(_server_line(s))
    return lines


def _lane(s):
    def p99(r):
        return _num(r.get("latency_ms", {}).get("p99"), "{:.2f}")
    a, b = s["geometric_alone"], s["geometric_beside_ipopt"]
    return [f"lane       {_verdict(s)}  geometric p99 alone {p99(a)} ms ({a['calls']} calls), beside "
            f"{s['ipopt_callers']} Ipopt callers {p99(b)} ms ({b['calls']} calls): ratio "
            f"{_num(s['p99_ratio'], '{:.2f}')} (limit {s['ratio_limit']:g}); Ipopt calls "
            f"{s['ipopt']['calls']}, p50 {_num(s['ipopt'].get('latency_ms', {}).get('p50'))} ms",
            _server_line(s)]


def _memory(s):
    lines = [f"memory     {_verdict(s)}  peak RSS above the server's start, fresh server per request"]
    for r in s["cases"]:
        lines.append(f"    {r['case']}: {r['code']} in {r['seconds']:.2f} s, peak +"
                     f"{_mb(r['peak_above_start_kb'])}")
    return lines


def _stops(s):
    lines = [f"stops      {_verdict(s)}  pass = answered within 1 s of the deadline, < 0.5 s of "
             f"server CPU in the 1 s after it, exit within grace + 1 s of SIGTERM"]
    for r in s["cases"]:
        lines.append(f"    {r['case']}: {r['code']} {r['after_deadline_s']:+.3f} s after its "
                     f"{r['deadline_s']:g} s deadline, then {r['server_cpu_s_in_1s_after']:.3f} s of "
                     f"server CPU in 1 s; SIGTERM (grace {r['grace_ms']} ms) to exit "
                     f"{r['sigterm_to_exit_s']:.3f} s, exit {r['sigterm_exit_code']}")
    return lines


def format_table(summary):
    m = summary["machine"]
    lines = [f"tactforce soak: {m['cores']} cores ({m['cpu_model']}), duration scale "
             f"{m['duration_scale']:g}, {summary['wall_s']:.0f} s"]
    for name, fn in (("overload", _overload), ("soak", _soak), ("deadlines", _deadlines),
                     ("lane", _lane), ("memory", _memory), ("stops", _stops)):
        if name in summary:
            lines += fn(summary[name])
    lines.append("overall    " + ("PASS" if summary["pass"] else "FAIL"))
    return "\n".join(lines)
