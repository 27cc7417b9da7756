#!/usr/bin/env bash
# Reliability runs of a local tactforce-server, driven by `tactforce load`:
#
#   scripts/soak.sh overload|soak|deadlines|all|lane|memory|stops [--duration-scale X] [--bin DIR] [--out FILE.json]
#                   [--keep-logs DIR]
#
#   overload   server --workers 1 --queue 4; Ipopt and cross-check Plans
#              (scripts/soak/overload_requests.json) at concurrency 64 for
#              60 s: calls, accepted, RESOURCE_EXHAUSTED, other errors, p50/p99
#              of the accepted calls. Pass: no other errors, some accepted,
#              health SERVING every second, server alive and exits 0 on SIGTERM.
#   soak       Plan (scripts/soak/soak_plan_requests.json), PlanStream (random
#              mix), EstimateForces, FitInertia (built-in stream), each at
#              concurrency 4, for 120 s: calls per RPC, errors, RSS at 10 s
#              and at the end. Pass: zero errors, RSS growth < 10 %, health,
#              alive, clean exit.
#   deadlines  1, 10, 100 ms deadlines on 200 Ipopt plans each of the
#              4-finger cylinder (scripts/soak/cylinder_4f_ipopt.json) at
#              concurrency 4: max and p99 time to completion of every call
#              (failed ones included). Pass: every call done by deadline + 5 ms.
#   all        the three in turn, one JSON {overload, soak, deadlines, machine, pass}.
#   lane       geometric Plans of 16 contacts (scripts/soak/lane_geometric_16.json,
#              one caller, 20 s, on the worker pool) alone, then beside two
#              callers of slow Ipopt plans (lane_ipopt_64.json: 64 contacts,
#              exact cones). Pass: geometric p99 beside Ipopt <= 3x its p99
#              alone, no errors (the Ipopt lane, --ipopt-workers). Not in `all`.
#   memory     peak RSS one request makes a fresh server hold: PLY header
#              counts of 1e8, a 4 MB closed STL fitted with DENSITY, a 4 MB OBJ
#              of tiny faces (scripts/soak/attack.py). Not in `all`.
#   stops      a long DENSITY fit, Ipopt trajectory and Ipopt plan: how far past a
#              1 s deadline each ends, and SIGTERM (--grace-ms 1000) to exit.
#              Not in `all`.
#
# Each mode starts its own server on 127.0.0.1:0 (the port it prints), samples
# its VmRSS and runs `tactforce health` once a second. --duration-scale scales
# the durations and call counts (0.05: the whole `all` in ~20 s); --bin is the
# folder with tactforce and tactforce-server (default build/bin); --out the
# JSON summary (default $TMPDIR/tactforce-soak-MODE.json); --keep-logs DIR keeps
# the server logs and load outputs. A table is printed
# at the end. Exit 0 when every criterion passes, 1 when one fails, 2 for bad
# usage or a server that would not start.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
if [[ $# -lt 1 || "$1" == "-h" || "$1" == "--help" ]]; then
  sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d' | sed 's/^# \{0,1\}//'
  [[ $# -ge 1 ]] && exit 0 || exit 2
fi
# Debian's python3 first: memory and stops use its python3-grpcio (setup.sh).
python=/usr/bin/python3
[[ -x "$python" ]] || python="$(command -v python3)" || { echo "soak.sh: python3 is needed" >&2; exit 2; }
exec "$python" "$here/soak/soak.py" "$@"
