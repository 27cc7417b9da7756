#!/usr/bin/env python3
"""Checks the JSON summary of scripts/soak.sh: every field present with a
sane type and range (counts >= 0, accepted > 0, p50 <= p99 <= max, RSS samples
non-empty and positive, each deadline present), the servers survived and
exited cleanly, health was SERVING throughout and the soak had no errors.
Timings and RSS growth are NOT checked (a short run is noisy) unless
--strict, which also requires every pass criterion of the script.

  check_summary.py SUMMARY.json [--modes overload,soak,deadlines] [--strict]

Exit 0 when all checks hold; otherwise each failed check on stderr, exit 1."""

import argparse
import json
import sys

DEADLINES = ("1ms", "10ms", "100ms")


class Checker:
    def __init__(self):
        self.failures = []

    def that(self, condition, what):
        if not condition:
            self.failures.append(what)
        return bool(condition)

    def count(self, value, what, positive=False):
        low = 1 if positive else 0
        ok = isinstance(value, int) and not isinstance(value, bool) and value >= low
        return self.that(ok, f"{what}: expected an integer >= {low}, got {value!r}")

    def number(self, value, what, low=0.0):
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and value >= low
        return self.that(ok, f"{what}: expected a number >= {low}, got {value!r}")

    def ordered(self, latency, what, keys=("p50", "p99", "max")):
        if not self.that(isinstance(latency, dict), f"{what}: expected an object"):
            return
        values = [latency.get(k) for k in keys]
        if all(self.number(v, f"{what}.{k}") for k, v in zip(keys, values)):
            self.that(values == sorted(values), f"{what}: {keys} not ordered: {values}")


def check_server(c, s, mode):
    c.that(s.get("server_alive_at_end") is True, f"{mode}: server not alive at the end")
    c.that(s.get("server_exit_code") == 0, f"{mode}: server exit code {s.get('server_exit_code')}")
    c.count(s.get("rss_peak_kb"), f"{mode}.rss_peak_kb", positive=True)
    health = s.get("health", {})
    c.count(health.get("checks"), f"{mode}.health.checks", positive=True)
    c.that(health.get("all_serving") is True,
           f"{mode}: health not SERVING throughout: {health.get('not_serving')}")
    c.that(isinstance(s.get("pass"), bool), f"{mode}.pass: expected a boolean")


def check_overload(c, s):
    check_server(c, s, "overload")
    c.count(s.get("calls"), "overload.calls", positive=True)
    c.count(s.get("accepted"), "overload.accepted", positive=True)
    c.count(s.get("resource_exhausted"), "overload.resource_exhausted")
    other = s.get("other_errors")
    if c.that(isinstance(other, dict), "overload.other_errors: expected an object"):
        for code, n in other.items():
            c.count(n, f"overload.other_errors.{code}")
        c.that(not other, f"overload: errors other than RESOURCE_EXHAUSTED: {other}")
    if all(isinstance(s.get(k), int) for k in ("calls", "accepted", "resource_exhausted")):
        c.that(s["accepted"] + s["resource_exhausted"] <= s["calls"],
               "overload: accepted + RESOURCE_EXHAUSTED > calls")
    c.ordered(s.get("accepted_latency_ms"), "overload.accepted_latency_ms")


def check_soak(c, s):
    check_server(c, s, "soak")
    calls = s.get("calls_per_rpc", {})
    for rpc in ("plan", "stream", "estimate", "fit-inertia"):
        c.count(calls.get(rpc), f"soak.calls_per_rpc.{rpc}", positive=True)
    c.that(s.get("errors") == 0, f"soak: errors {s.get('errors')} (must be 0): "
           f"{ {k: v.get('errors') for k, v in s.get('rpcs', {}).items()} }")
    for key in ("rss_at_ref_kb", "rss_end_kb"):
        c.count(s.get(key), f"soak.{key}", positive=True)
    c.that(isinstance(s.get("rss_growth_pct"), (int, float)), "soak.rss_growth_pct: not a number")
    samples = s.get("rss_samples")
    if c.that(isinstance(samples, list) and samples, "soak.rss_samples: empty"):
        for i, sample in enumerate(samples):
            ok = (isinstance(sample, list) and len(sample) == 2 and
                  isinstance(sample[0], (int, float)) and sample[0] >= 0 and
                  isinstance(sample[1], int) and sample[1] > 0)
            c.that(ok, f"soak.rss_samples[{i}]: expected [t >= 0, kB > 0], got {sample!r}")
        times = [x[0] for x in samples if isinstance(x, list) and x]
        c.that(times == sorted(times), "soak.rss_samples: times not increasing")


def check_deadlines(c, s):
    check_server(c, s, "deadlines")
    runs = s.get("deadlines", {})
    for name in DEADLINES:
        r = runs.get(name)
        if not c.that(isinstance(r, dict), f"deadlines.{name}: missing"):
            continue
        c.that("load_error" not in r, f"deadlines.{name}: {r.get('load_error')}")
        c.that(r.get("deadline_ms") == int(name[:-2]), f"deadlines.{name}.deadline_ms")
        c.count(r.get("calls"), f"deadlines.{name}.calls", positive=True)
        c.count(r.get("ok"), f"deadlines.{name}.ok")
        c.ordered(r.get("completion_ms"), f"deadlines.{name}.completion_ms")
        c.that(isinstance(r.get("worst_overshoot_ms"), (int, float)),
               f"deadlines.{name}.worst_overshoot_ms: not a number")
        for code, n in r.get("errors", {}).items():
            c.count(n, f"deadlines.{name}.errors.{code}")
            c.that(code in ("DEADLINE_EXCEEDED", "CANCELLED", "RESOURCE_EXHAUSTED"),
                   f"deadlines.{name}: unexpected error code {code}")


def check_machine(c, m):
    c.count(m.get("cores"), "machine.cores", positive=True)
    c.number(m.get("duration_scale"), "machine.duration_scale")


CHECKS = {"overload": check_overload, "soak": check_soak, "deadlines": check_deadlines}


def check(summary, modes, strict):
    c = Checker()
    check_machine(c, summary.get("machine", {}))
    for mode in modes:
        if c.that(isinstance(summary.get(mode), dict), f"{mode}: missing"):
            CHECKS[mode](c, summary[mode])
            if strict:
                c.that(summary[mode].get("pass") is True, f"{mode}: pass is not true (--strict)")
    if strict:
        c.that(summary.get("pass") is True, "pass is not true (--strict)")
    return c.failures


def main(argv):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("summary")
    p.add_argument("--modes", default=",".join(CHECKS))
    p.add_argument("--strict", action="store_true")
    args = p.parse_args(argv)
    with open(args.summary) as f:
        summary = json.load(f)
    failures = check(summary, [m for m in args.modes.split(",") if m], args.strict)
    for failure in failures:
        print(f"check_summary: {failure}", file=sys.stderr)
    print(f"check_summary: {args.summary}: {'OK' if not failures else f'{len(failures)} failed'}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
