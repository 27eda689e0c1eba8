#!/usr/bin/env bash
# `make serve`: vpm-server and the web viewer's gateway on this machine.
# Prints the URL to open; Ctrl-C (or either process dying) stops both.
#   scripts/serve.sh [BUILD_DIR]
# Environment: VPM_WEB_LISTEN   the gateway's HOST:PORT (default 127.0.0.1:8080)
#              VPM_LISTEN       vpm-server's HOST:PORT (default 127.0.0.1:0, a free port)
#              VPM_TOKEN        the server's token (default: a random one); the
#                               gateway's viewer token too: the printed link carries
#                               it in its fragment (/login#token=), which never
#                               reaches the gateway's logs; the sign-in page posts it
#                               and swaps it out of the address bar and history
#              VPM_USERS        a users file (vpm-server --hash-token) for both, when set
#              VPM_DATA_ROOT    passed to vpm-server --data-root when set
#              VPM_STATE_DIR    vpm-server --state-dir: where cases are kept (default
#                               out/state: every session is a case that outlives a restart)
# Logs: out/serve-server.log, out/serve-gateway.log; the gateway's record of
# its open sessions (--sessions-file): out/serve-gateway-sessions.json.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${1:-build}" && pwd)
server="$build/server/service/vpm-server"
[ -x "$server" ] || { echo "serve: $server is not built (make build)" >&2; exit 1; }
"$root/scripts/install-web.sh" --check
mkdir -p "$root/out"
server_log="$root/out/serve-server.log"
gateway_log="$root/out/serve-gateway.log"
export VPM_TOKEN=${VPM_TOKEN:-$(head -c 16 /dev/urandom | od -An -tx1 | tr -d ' \n')}

server_args=(--listen "${VPM_LISTEN:-127.0.0.1:0}")
gateway_args=(--sessions-file "$root/out/serve-gateway-sessions.json")
[ -n "${VPM_DATA_ROOT:-}" ] && server_args+=(--data-root "$VPM_DATA_ROOT")
server_args+=(--state-dir "${VPM_STATE_DIR:-$root/out/state}")
if [ -n "${VPM_USERS:-}" ]; then
  server_args+=(--users "$VPM_USERS")
  gateway_args+=(--users "$VPM_USERS")
fi
server_pid="" gateway_pid=""
# Each process in its own process group: Ctrl-C reaches this script only,
# which stops both in order (gateway first) with SIGTERM.
set -m
stop() {
  trap - INT TERM EXIT
  for pid in $gateway_pid $server_pid; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in $gateway_pid $server_pid; do wait "$pid" 2>/dev/null || true; done
  echo "serve: stopped vpm-server and the gateway"
}
trap 'stop; exit 0' INT TERM
trap stop EXIT

# Waits for a line matching a sed expression in a log; prints the capture.
wait_for() {
  local log=$1 expr=$2 pid=$3 what=$4 value=""
  for _ in $(seq 1 300); do
    value=$(sed -n "$expr" "$log" | head -n 1)
    [ -n "$value" ] && { echo "$value"; return 0; }
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  echo "serve: $what did not start; its log ($log):" >&2
  cat "$log" >&2
  return 1
}

"$server" "${server_args[@]}" > "$server_log" 2>&1 &
server_pid=$!
port=$(wait_for "$server_log" 's/^vpm-server listening on port \([0-9]*\).*/\1/p' "$server_pid" vpm-server)
host=${VPM_LISTEN:-127.0.0.1:0}
host=${host%:*}
[ "$host" = "0.0.0.0" ] && host=127.0.0.1

node "$root/client/web/gateway.js" --listen "${VPM_WEB_LISTEN:-127.0.0.1:8080}" \
  --server "$host:$port" "${gateway_args[@]}" > "$gateway_log" 2>&1 &
gateway_pid=$!
url=$(wait_for "$gateway_log" 's/^vpm-web listening on \(https*:[^ ]*\).*/\1/p' "$gateway_pid" "the gateway")

echo "vpm-server on $host:$port (log $server_log)"
echo "web viewer:  ${url}login#token=$VPM_TOKEN"
echo "             (paste it into the address bar: signs this browser in as 'viewer';"
echo "             a link followed from another site does not; log $gateway_log)"
echo "Open the URL, pick phantom:abdomen?size=128 and press Open. Ctrl-C stops both."
wait -n "$server_pid" "$gateway_pid" || true
echo "serve: vpm-server or the gateway exited on its own; see $server_log and $gateway_log" >&2
exit 1
