#!/usr/bin/env bash
# Instructions per call of a bench's out-of-line timed function, by callgrind
# (for machines where perf_event_open is refused, as in containers).
#   scripts/count_instructions.sh [BENCH_FILTER] [FUNCTION]
# defaults: 'BM_Workspace/4$' and TimedWorkspaceSolve (planner_bench).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
filter="${1:-BM_Workspace/4\$}"
function="${2:-TimedWorkspaceSolve}"
out="$(mktemp -d)"
valgrind --tool=callgrind --callgrind-out-file="$out/cg.out" \
  --toggle-collect="*${function}*" build/bin/planner_bench \
  --benchmark_filter="$filter" --benchmark_min_time=0.01 >/dev/null 2>&1
python3 - "$out/cg.out" "$function" <<'PY'
import re, sys
path, function = sys.argv[1], sys.argv[2]
names, calls, total = {}, 0, 0
lines = open(path).read().split('\n')
for i, line in enumerate(lines):
    m = re.match(r'c?fn=\((\d+)\)(?: (.*))?', line)
    if m and m.group(2):
        names[m.group(1)] = m.group(2)
    if line.startswith('cfn='):
        name = names.get(re.match(r'cfn=\((\d+)\)', line).group(1), '')
        if function in name:
            calls += int(re.match(r'calls=(\d+)', lines[i + 1]).group(1))
    if line.startswith('summary:') or line.startswith('totals:'):
        total = int(line.split()[1])
print(f"{function}: {calls} calls, {total} instructions, {total / max(calls, 1):.0f} per call")
PY
rm -rf "$out"
