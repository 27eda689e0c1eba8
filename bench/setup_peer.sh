#!/usr/bin/env bash
# Installs what bench/peer_vtk.py needs and nothing else: Debian's VTK 9.1
# Python bindings and a virtual X server to give its OpenGL mappers a
# context (llvmpipe). Bench-only: `make test` and scripts/install-deps.sh's
# own list do not include these. Idempotent: installs only what dpkg lacks.
set -euo pipefail
exec "$(dirname "$0")/../scripts/install-deps.sh" --only python3-vtk9 xvfb xauth python3-numpy
