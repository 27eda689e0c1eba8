#!/usr/bin/env bash
# The service part of `make demo`: starts vpm-server on loopback (ephemeral
# port, a random token, the phantom), plays scripts/demo_play.json through
# `vpm play` (camera moves, grab, drag path, release), saves the frames and
# the timing report in out/play/, runs a short vpm-load, and stops the server
# with SIGTERM.
set -euo pipefail
build=${1:-build}
server="$build/server/service/vpm-server"
vpm="$build/client/vpm"
load="$build/client/vpm-load"
mkdir -p out/play
token=$(head -c 16 /dev/urandom | od -An -tx1 | tr -d ' \n')
export VPM_TOKEN="$token"
"$server" --listen 127.0.0.1:0 --metrics-listen 127.0.0.1:0 > out/server.log 2>&1 &
pid=$!
trap 'kill -TERM $pid 2>/dev/null || true; wait $pid 2>/dev/null || true' EXIT
port=""
for _ in $(seq 1 100); do
  port=$(sed -n 's/^vpm-server listening on port \([0-9]*\).*/\1/p' out/server.log)
  [ -n "$port" ] && break
  sleep 0.1
done
[ -n "$port" ] || { echo "vpm-server did not start:"; cat out/server.log; exit 1; }
echo "== vpm-server on 127.0.0.1:$port (token in VPM_TOKEN)"
echo
echo "== vpm play scripts/demo_play.json"
"$vpm" --server "127.0.0.1:$port" play scripts/demo_play.json --out-dir out/play
echo
echo "== vpm-load: 2 sessions for 5 s"
"$load" --server "127.0.0.1:$port" --sessions 2 --duration 5 --json out/load.json
kill -TERM $pid
wait $pid || true
trap - EXIT
echo
echo "service demo outputs in out/:"
echo "  play/frame_*.jpg, play/report.json   frames of the scripted interaction and their timings"
echo "  load.json                           the vpm-load report"
echo "  server.log                          the server's log"
