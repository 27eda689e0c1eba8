#!/usr/bin/env bash
# Installs what bench/peer_vtk.py needs and nothing else: Debian's VTK 9.1
# Python bindings and a virtual X server to give its OpenGL mappers a
# context (llvmpipe). Bench-only: `make test` and scripts/install-deps.sh do
# not install these. Idempotent: installs only what dpkg lacks.
set -euo pipefail
packages=(python3-vtk9 xvfb xauth python3-numpy)
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup_peer: ${packages[*]} present"
  exit 0
fi
echo "setup_peer: installing ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then sudo_cmd=(sudo); else
    echo "setup_peer: need root to install: ${missing[*]}" >&2; exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
