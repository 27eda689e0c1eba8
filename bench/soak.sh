#!/usr/bin/env bash
# The service soak (a benchmark, not part of `make test`): one
# vpm-server on loopback, vpm-load at 1, 2, 4, 8 and 16 concurrent sessions
# for DURATION seconds each, then the goals checked and printed:
#   - zero errors (every status code OK);
#   - no growth in server memory after the run: resident memory (VmRSS)
#     after the sweep against after a warm-up sweep (the same levels, 2 s
#     each, so that the allocator's and the driver's pools have reached their
#     size), both read once the sessions are closed and idle; allowed growth
#     10%;
#   - aggregate frame rate at 16 sessions at least 80% of that at 2;
#   - fairness: the slowest session's fps against the average, per level.
#
# Usage: bench/soak.sh [BUILD_DIR] [DURATION_S] [SOURCE]
#        bench/soak.sh --churn MINUTES [BUILD_DIR] [SOURCE]
# Writes out/soak.json (the vpm-load report) and out/soak-server.log.
set -euo pipefail
# bench/soak.sh --churn MINUTES [BUILD_DIR] [SOURCE]: the churn soak
# (bench/soak_churn.py: 16 users, sessions opening and closing, uploads,
# cancelled calls, Watch clients killed, one user hammering Render).
if [ "${1:-}" = "--churn" ]; then
  exec /usr/bin/python3 "$(dirname "$0")/soak_churn.py" "${3:-build}" "${2:?--churn MINUTES}" ${4:+"$4"}
fi
build=${1:-build}
duration=${2:-10}
source=${3:-phantom:abdomen?size=128}
server="$build/server/service/vpm-server"
load="$build/client/vpm-load"
mkdir -p out
token=$(head -c 16 /dev/urandom | od -An -tx1 | tr -d ' \n')
export VPM_TOKEN="$token"
# Sessions are closed by vpm-load; idle eviction and the session cap are set
# so that neither interferes with the sweep.
"$server" --listen 127.0.0.1:0 --metrics-listen 127.0.0.1:0 --max-sessions 64 \
  --max-streams-per-user 64 > out/soak-server.log 2>&1 &
pid=$!
trap 'kill -TERM $pid 2>/dev/null || true; wait $pid 2>/dev/null || true' EXIT
port=""
for _ in $(seq 1 200); do
  port=$(sed -n 's/^vpm-server listening on port \([0-9]*\).*/\1/p' out/soak-server.log)
  [ -n "$port" ] && break
  sleep 0.05
done
[ -n "$port" ] || { echo "vpm-server did not start:"; cat out/soak-server.log; exit 1; }
rss_kib() { awk '/^VmRSS:/ {print $2}' "/proc/$pid/status"; }
script=$(mktemp)
# A script that loads the soak's source (vpm-load's built-in one uses the
# default phantom): camera moves, a grab, a drag path, a release.
python3 - "$source" > "$script" <<'EOF'
import json, sys
print(json.dumps({
    "volume": sys.argv[1],
    "settings": {"width": 256, "height": 256},
    "interval_ms": 33,
    "steps": [{"camera": {"azimuth_deg": 0, "elevation_deg": 10}},
               {"orbit": {"to_azimuth_deg": 60, "steps": 6}},
               {"grab": {"landmark": "left_renal_artery"}},
               {"drag": {"to_mm": [0, 0, 12], "steps": 8}},
               {"release": {}}],
}))
EOF
echo "== warm-up: 1, 2, 4, 8, 16 sessions, 2 s each"
"$load" --server "127.0.0.1:$port" --script "$script" --sweep 1,2,4,8,16 --duration 2 \
  > out/soak-warmup.txt
sleep 2
rss_warm=$(rss_kib)
echo "== sweep 1,2,4,8,16 sessions, ${duration} s each ($source)"
"$load" --server "127.0.0.1:$port" --script "$script" --sweep 1,2,4,8,16 \
  --duration "$duration" --json out/soak.json | sed -n '/^  *conc/,$p'
sleep 2
rss_after=$(rss_kib)
rm -f "$script"
python3 - out/soak.json "$rss_warm" "$rss_after" <<'EOF'
import json, sys
report = json.load(open(sys.argv[1]))
rss_warm, rss_after = int(sys.argv[2]), int(sys.argv[3])
levels = {l["concurrency"]: l for l in report["levels"]}
errors = sum(n for l in report["levels"] for code, n in l["status_codes"].items() if code != "OK")
print()
print(f"{'sessions':>8} {'fps':>8} {'fps/session avg':>16} {'min':>6} {'min/avg':>8} {'p50 ms':>8} {'p99 ms':>8}")
for c, l in sorted(levels.items()):
    f = l["fps_per_session"]
    fairness = f["fastest"] / f["average"] if f.get("average") else 0.0
    lat = l["latency_ms"]
    print(f"{c:>8} {l['rate_fps']:>8.1f} {f.get('average', 0):>16.1f} {f.get('fastest', 0):>6.1f} "
          f"{fairness:>8.2f} {lat.get('p50', 0):>8.1f} {lat.get('p99', 0):>8.1f}")
ratio = levels[16]["rate_fps"] / levels[2]["rate_fps"] if levels[2]["rate_fps"] else 0.0
growth = (rss_after - rss_warm) / rss_warm
checks = [
    ("zero errors", errors == 0, f"{errors} errors"),
    ("aggregate fps at 16 >= 80% of 2", ratio >= 0.8, f"{ratio:.2f}"),
    ("server memory after the run within 10% of after warm-up", growth <= 0.10,
     f"{rss_warm / 1024:.0f} MiB -> {rss_after / 1024:.0f} MiB ({growth:+.1%})"),
]
print()
for name, ok, detail in checks:
    print(f"{'met    ' if ok else 'NOT MET'}  {name}: {detail}")
sys.exit(0 if all(ok for _, ok, _ in checks) else 1)
EOF
