#!/usr/bin/env bash
# ctest entry of the balancer tests: checks what they need, failing (never
# skipping) with the command that fixes it, then runs one scenario
# (SCENARIO_test.mjs).
# Usage: balancer_test.sh BUILD_DIR SOURCE_DIR SCENARIO
set -euo pipefail
build=$1
source=$2
scenario=$3
fail() { echo "balancer_test: FAIL: $*" >&2; exit 1; }

command -v haproxy >/dev/null 2>&1 || fail "haproxy is not installed: run scripts/install-deps.sh"
command -v node >/dev/null 2>&1 || fail "node is not installed: run scripts/install-deps.sh"
for binary in "$build/server/service/vpm-server" "$build/client/vpm" "$build/client/vpm-view"; do
  [ -x "$binary" ] || fail "$binary is not built"
done
case "$scenario" in
  failover)
    for tool in Xvfb xdpyinfo; do
      command -v "$tool" >/dev/null 2>&1 || fail "$tool is missing: run scripts/install-deps.sh"
    done ;;
  failover_web)
    "$source/scripts/install-web.sh" --check || fail "the gateway's npm packages are not installed"
    chromium=${VPM_CHROMIUM:-/usr/bin/chromium}
    [ -x "$chromium" ] || fail "$chromium is missing: run scripts/install-deps.sh" ;;
esac
exec node "$source/tests/balancer/${scenario}_test.mjs" --build "$build" --source "$source"
