#!/usr/bin/env bash
# Installs the web viewer's npm packages (client/web/node_modules) with
# `npm ci`, exactly as pinned in client/web/package-lock.json.
# Idempotent: skips when node_modules was installed from this very lockfile
# and package.json (a stamp in node_modules holds their SHA-256).
#   scripts/install-web.sh           install if needed
#   scripts/install-web.sh --check   exit 1, saying why, unless installed and current
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
web="$root/client/web"
stamp="$web/node_modules/.vpm-lockfile.sha256"

for tool in node npm; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "install-web: $tool is not installed (scripts/install-deps.sh installs it)" >&2
    exit 1
  fi
done
node_major=$(node -p 'process.versions.node.split(".")[0]')
if [ "$node_major" -lt 20 ]; then
  echo "install-web: Node.js $(node --version) is too old; the gateway and playwright-core need 20 or newer" >&2
  exit 1
fi

want=$(cat "$web/package.json" "$web/package-lock.json" | sha256sum | cut -d' ' -f1)
have=$(cat "$stamp" 2>/dev/null || true)
if [ "$have" = "$want" ] && [ -d "$web/node_modules/playwright-core" ]; then
  [ "${1:-}" = "--check" ] || echo "install-web: client/web/node_modules matches package-lock.json"
  exit 0
fi
if [ "${1:-}" = "--check" ]; then
  if [ -d "$web/node_modules" ]; then
    echo "install-web: client/web/node_modules does not match package-lock.json; run 'make web-deps' (scripts/install-web.sh)" >&2
  else
    echo "install-web: client/web/node_modules is missing; run 'make web-deps' (scripts/install-web.sh)" >&2
  fi
  exit 1
fi

echo "install-web: npm ci in client/web (versions from package-lock.json)"
# playwright-core never downloads a browser; the tests drive /usr/bin/chromium.
# Every package is plain JavaScript: no install script is needed, none runs.
(cd "$web" && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --ignore-scripts --no-audit --no-fund)
echo "$want" > "$stamp"
