#!/usr/bin/env bash
# ctest entry of the web viewer's end-to-end tests. Checks what they need
# and fails (never skips) naming the command that fixes it, then runs one
# scenario in headless Chromium.
# Usage: web_e2e.sh BUILD_DIR SOURCE_DIR SCENARIO     (viewer | server_down)
set -euo pipefail
build=$1
source=$2
scenario=$3
fail() { echo "web_e2e: FAIL: $*" >&2; exit 1; }

command -v node >/dev/null 2>&1 || fail "node is not installed: run scripts/install-deps.sh"
"$source/scripts/install-web.sh" --check || fail "the gateway's npm packages are not installed"
chromium=${VPM_CHROMIUM:-/usr/bin/chromium}
[ -x "$chromium" ] || fail "$chromium is missing: run scripts/install-deps.sh (Debian's chromium)"
[ -x "$build/server/service/vpm-server" ] || fail "$build/server/service/vpm-server is not built"
exec node "$source/tests/web/${scenario}_e2e.mjs" --build "$build" --source "$source"
