#!/usr/bin/env bash
# ctest entry of the web viewer's tests that need client/web/node_modules.
# Checks what they need and fails (never skips) naming the command that
# fixes it, then runs one scenario:
#   viewer, server_down,  end to end in headless Chromium (SCENARIO_e2e.mjs); workspace: the
#   workspace             page's layout at 1280 x 800 and 1920 x 1080, pan, zoom, presets, slices
#   gateway               the gateway against a stand-in server (gateway.test.mjs, the
#                         Studies panel's and Export's calls in gateway_pacs.test.mjs, and
#                         uploads from the desktop in gateway_upload.test.mjs)
#   gateway_fuzz          10,500 malformed HTTP requests and WebSocket frames (gateway_fuzz.mjs)
#   gateway_cycles        open/close cycles through the gateway on a real server (gateway_cycles.mjs)
#   attacker              issue 25's attacks through the gateway on a real server, two users,
#                         headless Chromium for the sign-in ones (attacker.mjs)
#   upload_page           the page's uploads in headless Chromium, through the gateway to the
#                         stand-in server (upload_page_e2e.mjs; no vpm-server needed)
# Usage: web_e2e.sh BUILD_DIR SOURCE_DIR SCENARIO
set -euo pipefail
build=$1
source=$2
scenario=$3
fail() { echo "web_e2e: FAIL: $*" >&2; exit 1; }

command -v node >/dev/null 2>&1 || fail "node is not installed: run scripts/install-deps.sh"
"$source/scripts/install-web.sh" --check || fail "the gateway's npm packages are not installed"
if [ "$scenario" = gateway ]; then
  exec node --test "$source/tests/web/gateway.test.mjs" "$source/tests/web/gateway_pacs.test.mjs" \
    "$source/tests/web/gateway_upload.test.mjs"
fi
if [ "$scenario" = gateway_fuzz ]; then
  exec node "$source/tests/web/gateway_fuzz.mjs"
fi
chromium=${VPM_CHROMIUM:-/usr/bin/chromium}
if [ "$scenario" = upload_page ]; then
  [ -x "$chromium" ] || fail "$chromium is missing: run scripts/install-deps.sh (Debian's chromium)"
  exec node "$source/tests/web/upload_page_e2e.mjs" --build "$build" --source "$source"
fi
[ -x "$build/server/service/vpm-server" ] || fail "$build/server/service/vpm-server is not built"
if [ "$scenario" = gateway_cycles ]; then
  exec node "$source/tests/web/gateway_cycles.mjs" --build "$build" --source "$source"
fi
[ -x "$chromium" ] || fail "$chromium is missing: run scripts/install-deps.sh (Debian's chromium)"
if [ "$scenario" = attacker ]; then
  exec node "$source/tests/web/attacker.mjs" --build "$build" --source "$source"
fi
exec node "$source/tests/web/${scenario}_e2e.mjs" --build "$build" --source "$source"
