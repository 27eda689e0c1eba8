#!/usr/bin/env bash
# `vpm play` comes back into its case by itself: vpm-server (--state-dir)
# is killed (SIGKILL) in the middle of a scripted drag and restarted on the
# same port and state directory; vpm play reopens the same case (OpenCase),
# goes on after the manipulations the case holds and finishes. Every one of
# the script's 62 manipulations (a grab, 60 drags, a kept release) is in the
# case exactly once.
# Usage: play_reconnect_test.sh BUILD_DIR SOURCE_DIR
set -uo pipefail
build=$(cd "${1:?usage: $0 BUILD_DIR SOURCE_DIR}" && pwd)
source_dir=$(cd "${2:?usage: $0 BUILD_DIR SOURCE_DIR}" && pwd)
server_bin="$build/server/service/vpm-server"
vpm="$build/client/vpm"
for b in "$server_bin" "$vpm"; do [ -x "$b" ] || { echo "FAIL: $b is not built"; exit 1; }; done
tmp=$(mktemp -d)
server_pid="" play_pid=""
cleanup() {
  for pid in $play_pid $server_pid; do kill -KILL "$pid" 2>/dev/null; done
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; echo "--- vpm play"; cat "$tmp/play.err" "$tmp/play.out"; exit 1; }
head -c 16 /dev/urandom | od -An -tx1 | tr -d ' \n' > "$tmp/token"
export VPM_TOKEN=$(cat "$tmp/token")

start_server() {  # LISTEN
  "$server_bin" --listen "$1" --token-file "$tmp/token" --state-dir "$tmp/state" \
    --still-delay-ms 50 >> "$tmp/server.log" 2>&1 &
  server_pid=$!
  for _ in $(seq 1 600); do
    port=$(sed -n 's/^vpm-server listening on port \([0-9]*\).*/\1/p' "$tmp/server.log" | tail -1)
    [ -n "$port" ] && [ "$(grep -c 'listening on port' "$tmp/server.log")" -ge "$2" ] && return 0
    kill -0 "$server_pid" 2>/dev/null || break
    sleep 0.1
  done
  echo "FAIL: vpm-server did not start"; cat "$tmp/server.log"; exit 1
}
start_server 127.0.0.1:0 1
"$vpm" --server "127.0.0.1:$port" play "$source_dir/tests/cases/play_script.json" \
  --report "$tmp/report.json" > "$tmp/play.out" 2> "$tmp/play.err" &
play_pid=$!
for _ in $(seq 1 300); do grep -q ', case case-' "$tmp/play.out" && break; sleep 0.1; done
case_id=$(sed -n 's/.*, case \(case-[0-9a-f]*\).*/\1/p' "$tmp/play.out")
[ -n "$case_id" ] || fail "vpm play opened no case"
sleep 1.2  # into the 2.4 s of drags
kill -KILL "$server_pid"; wait "$server_pid" 2>/dev/null
start_server "127.0.0.1:$port" 2
wait "$play_pid"; rc=$?; play_pid=""
[ "$rc" = 0 ] || fail "vpm play exited $rc"
grep -q "reopened case $case_id as session" "$tmp/play.err" || fail "vpm play did not reopen $case_id"
events=$("$vpm" --server "127.0.0.1:$port" case show "$case_id" --json |
         sed -n 's/.*"events": \([0-9]*\).*/\1/p')
sessions=$(python3 -c "import json,sys; print(len(json.load(open('$tmp/report.json'))['sessions']))")
if [ "$events" != 62 ]; then
  # What the case holds, kinds in order (runs counted), and both servers'
  # logs: which manipulation is missing or twice, and around which restart.
  "$vpm" --server "127.0.0.1:$port" case export "$case_id" "$tmp/case.json" > /dev/null 2>&1
  python3 - "$tmp/case.json" <<'EOF2' || true
import itertools, json, sys
events = json.load(open(sys.argv[1])).get("events", [])
kinds = [e.get("kind", "?").replace("CASE_EVENT_", "").lower() for e in events]
runs = (f"{k} x{len(list(g))}" for k, g in itertools.groupby(kinds))
print("--- the case's events:", " ".join(runs))
# Drags by their offset (mm): a drag missing or twice shows in the run.
drags = [e.get("vector", {}).get("z", 0) for e in events if e.get("kind") == "CASE_EVENT_DRAG"]
print("--- drag z offsets (mm):", " ".join(f"{z:.1f}" for z in drags))
EOF2
  echo "--- vpm-server (both runs)"; cat "$tmp/server.log"
  fail "the case holds $events events, not the script's 62"
fi
[ "$sessions" = 2 ] || fail "$sessions sessions in the report, not 2"
echo "ok: $(grep 'reopened case' "$tmp/play.err"); the case holds all 62 manipulations once"
