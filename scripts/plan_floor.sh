#!/usr/bin/env bash
# Plan against the gRPC floor (issue 29): what a Plan call costs next to a
# grpc.health.v1 Check on the same local tactforce-server.
#
#   scripts/plan_floor.sh all|qps|instructions [--bin DIR] [--rounds 3] [--duration 3]
#                         [--concurrency 8,1] [--calls 2000] [--callgrind-concurrency 8]
#                         [--server-bin DIR] [--out FILE.json]
#
#   qps           one server (--log-level warn); at each concurrency, `tactforce
#                 load --rpc health` and `--rpc plan` alternated --rounds times,
#                 --duration s each: QPS, p50, the load average before the run and
#                 the CPU time per call (user + system) of the server (/proc) and
#                 of the load tester (its rusage). Prints the best-of-rounds
#                 Plan/health ratio, the per-round ratios and the ratio of the
#                 median CPU time per call (server + load tester), which is the
#                 QPS ratio a CPU-bound box converges to.
#   instructions  callgrind: the server under valgrind (counters zeroed and
#                 dumped around each run with callgrind_control), then the load
#                 tester under valgrind against a plain server; instructions per
#                 call = (I(--calls) - I(--calls/10)) / (0.9 --calls), so start-up,
#                 connection and warm-up cancel. Plan's server cost is split into
#                 gRPC + protobuf (everything outside PlannerService::Plan), ours
#                 (the handler minus the solve), the solve (planner::Plan), with
#                 the request parse, response serialization, PreparePlan and
#                 the answer's ToProto shown. User-space instructions only: the
#                 kernel's share (loopback TCP, epoll, futex) is in `qps`'s
#                 system time.
#   all           both.
#
# --server-bin DIR measures the tactforce-server in DIR (a copy of an earlier
# build, to compare before and after) with --bin's load tester.
#
# What `--rpc plan` sends: the load tester's default --mix, 256 seeded random
# grasps (seed 1) of 2-6 contacts, SOLVER_GEOMETRIC, 12-sided pyramids, no
# parameter uncertainty; all solved inline on the gRPC thread. Needs
# build/bin/tactforce-server and build/bin/tactforce (--bin), python3 and,
# for `instructions`, valgrind. Exit 0, or 2 for a run that failed.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
if [[ $# -lt 1 || "$1" == "-h" || "$1" == "--help" ]]; then
  sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d' | sed 's/^# \{0,1\}//'
  [[ $# -ge 1 ]] && exit 0 || exit 2
fi
exec python3 "$here/soak/plan_floor.py" "$@"
