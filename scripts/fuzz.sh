#!/usr/bin/env bash
# Fuzzes the parsers and request paths with clang's libFuzzer (tests/fuzz).
#   scripts/fuzz.sh TARGET SECONDS [libFuzzer args...]    one target
#   scripts/fuzz.sh all SECONDS [libFuzzer args...]       every target in turn
#   scripts/fuzz.sh --merge TARGET|all SECONDS [...]      the same, then the new
#       finds are minimised (-merge=1) into tests/fuzz/corpus/TARGET/
# Targets: plan_json plan_binary csv mesh sensor_model.
# Builds build-fuzz/ with clang (the libraries with -fsanitize=fuzzer-no-link,
# address,undefined; see tests/fuzz/fuzz_flags.cmake), only the fuzz targets.
# Each run starts from a fresh work corpus build-fuzz/work/TARGET seeded from
# the checked-in one (which is only read, unless --merge) and uses
# tests/fuzz/dict/TARGET.dict when there is one; crash-*, timeout-*,
# leak-* and oom-* files go to build-fuzz/artifacts/TARGET/, the log to
# build-fuzz/logs/TARGET.log. Prints one summary line per target and writes
# build-fuzz/fuzz_summary.json. Exit status 1 on any crash, hang (> 1 s per
# input), leak, out-of-memory or sanitizer report.
# Reproduce: build-fuzz/bin/TARGET_fuzzer FILE (or the gcc replay binary,
# build/tests/TARGET_fuzz_replay FILE). Env: JOBS (build jobs, default 2).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
root=$PWD
dir=$root/build-fuzz
targets=(plan_json plan_binary csv mesh sensor_model)

usage() {
  awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0" >&2
  exit 2
}

configure_and_build() {  # the fuzz targets named in "$@"
  ./scripts/setup.sh
  CC=clang CXX=clang++ cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DTACTFORCE_BUILD_BENCH=OFF -DTACTFORCE_FUZZ=ON \
    -DCMAKE_PROJECT_INCLUDE="$root/tests/fuzz/fuzz_flags.cmake" >/dev/null
  local t build_targets=()
  for t in "$@"; do build_targets+=("${t}_fuzzer"); done
  cmake --build "$dir" --target "${build_targets[@]}" -j"${JOBS:-2}"
}

# Value of the last libFuzzer status field NAME ("cov: 123") in the log.
last_field() {
  grep -oE "$1: [0-9]+" "$2" | tail -n 1 | awk '{print $2}' || true
}

stat_value() {
  grep -E "^stat::$1:" "$2" | tail -n 1 | awk '{print $2}' || true
}

# One target: fuzz, then (--merge) minimise into the checked-in corpus.
# Appends a JSON object to $summary_entries and prints the summary line.
run_target() {
  local name=$1 seconds=$2; shift 2
  local bin=$dir/bin/${name}_fuzzer work=$dir/work/$name art=$dir/artifacts/$name log=$dir/logs/$name.log
  local seed=$root/tests/fuzz/corpus/$name
  rm -rf "$work" "$art"
  mkdir -p "$work" "$art" "$dir/logs"
  local start=$SECONDS rc=0 dict=()
  [[ -f $root/tests/fuzz/dict/$name.dict ]] && dict=(-dict="$root/tests/fuzz/dict/$name.dict")
  ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:symbolize=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}" \
  UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}" \
  LSAN_OPTIONS="suppressions=$root/tests/fuzz/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}" \
    "$bin" "$work" "$seed" -max_total_time="$seconds" -timeout=1 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$art/" "${dict[@]}" "$@" >"$log" 2>&1 || rc=$?
  local wall=$((SECONDS - start))
  local found result=ok
  found=$(find "$art" -type f | wc -l)
  if ((rc != 0 || found > 0)) || grep -qE "ERROR: (Address|Leak|Undefined)Sanitizer|runtime error:" "$log"; then
    result=FAILED
  fi
  if [[ $merge == 1 && $result == ok ]]; then
    "$bin" -merge=1 -timeout=1 -rss_limit_mb=2048 "$seed" "$work" >>"$log" 2>&1 || result=FAILED
  fi
  record "$name" "$seconds" "$wall" "$rc" "$result" "$log" "$art" "$work"
  [[ $result == ok ]]
}

# Summary line + JSON object of one finished target.
record() {
  local name=$1 seconds=$2 wall=$3 rc=$4 result=$5 log=$6 art=$7 work=$8
  local execs rate cov ft corpus artifacts
  execs=$(stat_value number_of_executed_units "$log")
  rate=$(stat_value average_exec_per_sec "$log")
  # -fork=N prints no final stats: the last status line's numbers instead.
  [[ -n $execs ]] || execs=$(grep -oE '^#[0-9]+' "$log" | tail -n 1 | tr -d '#' || true)
  [[ -n $rate ]] || rate=$(last_field exec/s "$log")
  cov=$(last_field cov "$log")
  ft=$(last_field ft "$log")
  corpus=$(last_field corp "$log")  # units in libFuzzer's corpus at the end
  [[ -n $corpus ]] || corpus=$(find "$work" -type f | wc -l)
  artifacts=$(find "$art" -type f -printf '"%p",' | sed 's/,$//')
  printf '%-13s %10s execs %7s/s  cov %6s  ft %7s  corpus %5s  %-6s (rc %s, %ss)%s\n' \
    "$name" "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" "$corpus" "$result" "$rc" "$wall" \
    "$([[ -n $artifacts ]] && echo " artifacts: ${artifacts//\"/}")"
  [[ $result == ok ]] || tail -n 40 "$log" | sed "s/^/  $name| /" >&2
  summary_entries+=("$(printf '{"target": "%s", "seconds": %s, "wall_seconds": %s, "executions": %s, "execs_per_second": %s, "cov": %s, "ft": %s, "corpus_units": %s, "result": "%s", "exit_code": %s, "log": "%s", "artifacts": [%s]}' \
    "$name" "$seconds" "$wall" "${execs:-null}" "${rate:-null}" "${cov:-null}" "${ft:-null}" "$corpus" \
    "$result" "$rc" "$log" "$artifacts")")
}

write_summary() {
  local IFS=','
  printf '[%s]\n' "${summary_entries[*]}" | python3 -m json.tool >"$dir/fuzz_summary.json"
  echo "fuzz: summary in $dir/fuzz_summary.json"
}

main() {
  merge=0
  if [[ ${1:-} == --merge ]]; then merge=1; shift; fi
  (($# >= 2)) || usage
  local which=$1 seconds=$2; shift 2
  [[ $seconds =~ ^[0-9]+$ ]] || usage
  local run=()
  if [[ $which == all ]]; then run=("${targets[@]}"); else
    [[ " ${targets[*]} " == *" $which "* ]] || { echo "fuzz: unknown target '$which'" >&2; usage; }
    run=("$which")
  fi
  configure_and_build "${run[@]}"
  summary_entries=()
  local t failed=0
  for t in "${run[@]}"; do
    run_target "$t" "$seconds" "$@" || failed=1
  done
  write_summary
  if ((failed)); then echo "fuzz: FAILED (see the artifacts and logs above)" >&2; fi
  return "$failed"
}

main "$@"
