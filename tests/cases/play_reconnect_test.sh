#!/usr/bin/env bash
# `vpm play` comes back into its case by itself: vpm-server (--state-dir)
# is killed (SIGKILL) in the middle of a scripted drag and restarted on the
# same port and state directory; vpm play reopens the same case (OpenCase),
# goes on after the last manipulation the case holds and finishes. The case
# then holds the script's manipulations in order, none twice, ending with
# its last drag and its kept release (drags the server replaced in its
# queue aside).
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
sessions=$(python3 -c "import json,sys; print(len(json.load(open('$tmp/report.json'))['sessions']))")
[ "$sessions" = 2 ] || fail "$sessions sessions in the report, not 2"
"$vpm" --server "127.0.0.1:$port" case export "$case_id" "$tmp/case.json" > /dev/null ||
  fail "vpm case export $case_id failed"
# The script: a grab, drags to (0, 0, 0.2 k) mm for k = 1..60, a kept
# release. The server replaces a queued drag with the next one when drags
# come faster than it applies them, so the case holds the grab, drags whose
# k rise strictly to 60 (a k twice or going back: a drag sent again after
# the restart), and the kept release; a refinement's REMESH may follow the
# grab.
verdict=$(python3 - "$tmp/case.json" <<'EOF2'
import itertools, json, sys
events = [e for e in json.load(open(sys.argv[1])).get("events", [])
          if e.get("kind") != "CASE_EVENT_REMESH"]
kinds = [e.get("kind", "?").replace("CASE_EVENT_", "").lower() for e in events]
runs = " ".join(f"{k} x{len(list(g))}" for k, g in itertools.groupby(kinds))
drags = [e.get("vector", {}) for e in events if e.get("kind") == "CASE_EVENT_DRAG"]
steps = [round(d.get("z", 0) / 0.2) for d in drags]
off_grid = [d for d, k in zip(drags, steps)
            if abs(d.get("z", 0) - 0.2 * k) > 1e-6 or abs(d.get("x", 0)) > 1e-6 or
            abs(d.get("y", 0)) > 1e-6]
problems = []
if kinds[:1] != ["grab"] or kinds[-1:] != ["release"] or set(kinds[1:-1]) - {"drag"}:
    problems.append(f"kinds {runs}, not a grab, drags, a release")
if not events or not events[-1].get("keep"):
    problems.append("the release is not kept")
if off_grid:
    problems.append(f"drags off the script's path: {off_grid[:3]}")
if any(b <= a for a, b in zip(steps, steps[1:])) or steps[-1:] != [60]:
    problems.append("drag steps k (offset / 0.2 mm) not rising strictly to 60: " +
                    " ".join(map(str, steps)))
print(f"{len(events)} events ({runs}; {60 - len(drags)} drags replaced in the queue)")
for p in problems:
    print("PROBLEM:", p)
EOF2
)
echo "$verdict"
if grep -q PROBLEM <<< "$verdict"; then
  echo "--- vpm-server (both runs)"; cat "$tmp/server.log"
  fail "the case is not the script's manipulations in order, each once"
fi
echo "ok: $(grep 'reopened case' "$tmp/play.err"); the case holds the script's manipulations in order, none twice"
