#!/usr/bin/env bash
# Instructions per call of a bench's out-of-line timed function, by callgrind
# (for machines where perf_event_open is refused, as in containers).
#   scripts/count_instructions.sh [CONTACTS] [SOLVES] [qp|dispatch|cross]
# defaults: 4 contacts, 640 solves (each of planner_bench's 64 grasps 10
# times, after a warm-up pass) through the workspace path; with "qp", only
# the FE-plane QPs of the same grasps (TimedQpSolve); "dispatch": Plan
# requests through api::PlanDispatcher inline (TimedDispatchPlan); "cross":
# CROSS_CHECK solves (TimedCrossCheckSolve). Below the total: the preparation
# (PrepareInPlace) and the QP (SolveDenseQp) per solve, from the same run.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
contacts="${1:-4}"
solves="${2:-640}"
function=TimedWorkspaceSolve
run="$solves,$contacts"
case "${3:-}" in
  qp) function=TimedQpSolve; run="$run,qp" ;;
  dispatch) function=TimedDispatchPlan; run="$run,dispatch" ;;
  cross) function=TimedCrossCheckSolve; run="$run,cross" ;;
esac
out="$(mktemp -d)"
valgrind --tool=callgrind --callgrind-out-file="$out/cg.out" \
  --toggle-collect="*${function}*" build/bin/planner_bench \
  --callgrind-run="$run" >/dev/null 2>&1
python3 - "$out/cg.out" "$function" "$solves" <<'PY'
import sys
path, function, solves = sys.argv[1], sys.argv[2], int(sys.argv[3])
total = 0
for line in open(path):
    if line.startswith(('summary:', 'totals:')):
        total = int(line.split()[1])
print(f"{function}: {solves} solves, {total} instructions, {total / solves:.0f} per solve")
PY
# The split inside the same run: preparation and QP per solve (inclusive).
callgrind_annotate --inclusive=yes "$out/cg.out" 2>/dev/null |
  awk -v solves="$solves" '
    /PrepareInPlace\(/ && !p { gsub(",", "", $1); printf "  PrepareInPlace: %.0f per solve\n", $1 / solves; p = 1 }
    /SolveDenseQp\(/ && !q { gsub(",", "", $1); printf "  SolveDenseQp: %.0f per solve\n", $1 / solves; q = 1 }'
rm -rf "$out"
