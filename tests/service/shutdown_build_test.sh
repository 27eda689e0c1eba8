#!/usr/bin/env bash
# SIGTERM while a 60^3 BuildMesh runs (about 20 s uncancelled, target 4000):
# vpm-server's shutdown ends within its --shutdown-grace-s (2 s here, plus
# 0.5 s for the build to notice), because running work polls the call's
# CancelToken and stops once the grace period is over (the issue's case 5:
# 19 s with a 5 s grace), and the process exits 0. The call is checked to
# be in flight when the signal is sent.
#
# Usage: shutdown_build_test.sh BUILD_DIR
set -uo pipefail
build=$(cd "${1:?usage: $0 BUILD_DIR}" && pwd)
server_bin="$build/server/service/vpm-server"
vpm="$build/client/vpm"
for b in "$server_bin" "$vpm"; do
  [ -x "$b" ] || { echo "FAIL: $b is not built"; exit 1; }
done
tmp=$(mktemp -d)
server_pid=""
build_pid=""
cleanup() {
  [ -n "$server_pid" ] && kill -KILL "$server_pid" 2>/dev/null
  [ -n "$build_pid" ] && kill -KILL "$build_pid" 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
grace_s=2

"$server_bin" --listen 127.0.0.1:0 --metrics-listen 127.0.0.1:0 --token secret \
  --shutdown-grace-s "$grace_s" > "$tmp/server.log" 2>&1 &
server_pid=$!
port=""
for _ in $(seq 1 200); do
  port=$(sed -n 's/^vpm-server listening on port \([0-9]*\).*/\1/p' "$tmp/server.log")
  [ -n "$port" ] && break
  sleep 0.05
done
[ -n "$port" ] || { echo "FAIL: vpm-server did not start:"; cat "$tmp/server.log"; exit 1; }
metrics_port=$(sed -n "s/.* metrics on port \([0-9]*\).*/\1/p" "$tmp/server.log" | head -1)
addr="127.0.0.1:$port"

"$vpm" --server "$addr" --token secret volume load "phantom:abdomen?size=96" > "$tmp/load.json" ||
  { echo "FAIL: could not load the phantom"; exit 1; }
volume_id=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["volume_id"])' \
  "$tmp/load.json")
"$vpm" --server "$addr" --token secret mesh-build --volume-id "$volume_id" --grid 60 60 60 --target 4000 \
  > "$tmp/build.out" 2>&1 &
build_pid=$!

in_flight() {  # BuildMesh calls started and not answered
  python3 - "$metrics_port" <<'EOF2'
import re, sys, urllib.request
text = urllib.request.urlopen(f"http://127.0.0.1:{sys.argv[1]}/metrics", timeout=5).read().decode()
m = re.search(r'^vpm_unary_calls_in_flight\{method="BuildMesh"\} (\S+)$', text, re.M)
print(int(float(m.group(1))) if m else 0)
EOF2
}
for _ in $(seq 1 200); do [ "$(in_flight)" = 1 ] && break; sleep 0.05; done
sleep 0.5
if [ "$(in_flight)" != 1 ]; then
  echo "FAIL: the build was not running when SIGTERM was to be sent: $(cat "$tmp/build.out")"
  exit 1
fi

start=$(date +%s.%N)
kill -TERM "$server_pid"
status=""
stopped=""
for _ in $(seq 1 600); do
  if [ -z "$stopped" ] && grep -q '^vpm-server: stopped' "$tmp/server.log"; then
    stopped=$(date +%s.%N)
  fi
  if ! kill -0 "$server_pid" 2>/dev/null; then wait "$server_pid"; status=$?; break; fi
  sleep 0.02
done
now=$(date +%s.%N)
[ -n "$stopped" ] || stopped=$now
secs() { python3 -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.2f}')" "$1" "$2"; }
stopped_s=$(secs "$start" "$stopped")
exited_s=$(secs "$start" "$now")
server_pid=""
wait "$build_pid" 2>/dev/null
build_pid=""
echo "SIGTERM during a 60^3 build (grace ${grace_s} s): work stopped and the server shut down" \
  "after ${stopped_s} s; the process exited (status ${status:-none}) after ${exited_s} s"
echo "the build's client saw: $(tr '\n' ' ' < "$tmp/build.out" | cut -c1-200)"
if [ -z "$status" ]; then
  echo "FAIL: vpm-server still running 12 s after SIGTERM"; exit 1
fi
[ "$status" -eq 0 ] || { echo "FAIL: exit status $status"; cat "$tmp/server.log"; exit 1; }
failed=0
# Shutdown (the pools joined, the build stopped) within the grace, with
# 0.5 s for the build to notice and the calls to be answered.
if python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) < float(sys.argv[2]) + 0.5 else 1)" \
  "$stopped_s" "$grace_s"; then
  echo "ok:   the running build ended within the grace period"
else
  echo "FAIL: shutdown took ${stopped_s} s, past the ${grace_s} s grace (+0.5 s)"; failed=1
fi
# The process's own teardown after that (GPU, gRPC) as service_process_test
# allows it: the grace plus 5 s.
if python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) < float(sys.argv[2]) + 5 else 1)" \
  "$exited_s" "$grace_s"; then
  echo "ok:   exited 0"
else
  echo "FAIL: the process took ${exited_s} s to exit"; failed=1
fi
exit $failed
