#!/usr/bin/env bash
# Builds tactforce and runs its demo: the built-in grasps planned with the
# geometric planner and with Ipopt, side by side, in-process and through a
# local tactforce-server (health, the same plans checked against the local
# answers, and a 5-second load test with its latency table).
#
# The server is started on 127.0.0.1 with a free port (--listen 127.0.0.1:0;
# the port is read from its "listening on" line), stopped with SIGTERM at the
# end and must exit 0. It is killed if anything fails on the way.
# Extra arguments go to `tactforce demo` (e.g. --format json, --repeat 10,
# --load-seconds 10).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

./scripts/build.sh

bin=build/bin
work=$(mktemp -d "${TMPDIR:-/tmp}/tactforce-demo.XXXXXX")
server_pid=""

cleanup() {
  if [[ -n "$server_pid" ]] && kill -0 "$server_pid" 2>/dev/null; then
    kill -KILL "$server_pid" 2>/dev/null || true
    wait "$server_pid" 2>/dev/null || true
  fi
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

"$bin/tactforce-server" --listen 127.0.0.1:0 >"$work/server.out" 2>"$work/server.err" &
server_pid=$!

# The bound address, from "tactforce-server listening on HOST:PORT" (15 s).
address=""
for _ in $(seq 150); do
  address=$(sed -n 's/^tactforce-server listening on //p' "$work/server.out")
  [[ -n "$address" ]] && break
  if ! kill -0 "$server_pid" 2>/dev/null; then
    echo "demo: tactforce-server exited at startup:" >&2
    cat "$work/server.err" >&2
    exit 1
  fi
  sleep 0.1
done
if [[ -z "$address" ]]; then
  echo "demo: tactforce-server printed no address within 15 s" >&2
  exit 1
fi

"$bin/tactforce" health --server "$address" --wait 15 >/dev/null
echo "demo: tactforce-server is SERVING on $address (pid $server_pid)"
echo

"$bin/tactforce" demo --server "$address" "$@"

# Graceful stop: SIGTERM drains and must exit 0.
kill -TERM "$server_pid"
status=0
wait "$server_pid" || status=$?
server_pid=""
if [[ $status -ne 0 ]]; then
  echo "demo: tactforce-server exited with status $status after SIGTERM" >&2
  cat "$work/server.err" >&2
  exit 1
fi
echo
echo "demo: tactforce-server stopped cleanly (SIGTERM, exit 0)"
