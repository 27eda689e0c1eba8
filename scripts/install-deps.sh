#!/usr/bin/env bash
# Installs the Debian 12 packages vpm needs to build, test and run.
# Idempotent: asks dpkg which packages are missing and installs only those.
# Needs root (or sudo) only when something is missing.
# `install-deps.sh --only PKG...` installs those packages instead of vpm's
# list, the same way (bench/setup_peer.sh uses it for bench-only packages).
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake pkg-config ninja-build clang libclang-rt-14-dev
  # Vulkan on lavapipe, shaders, validation
  libvulkan-dev mesa-vulkan-drivers glslang-tools vulkan-validationlayers
  # maths, geometry
  libglm-dev libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev
  # volume formats and images
  libnifti2-dev libdcmtk-dev zlib1g-dev libturbojpeg0-dev libpng-dev libopenjp2-7-dev
  # the reference DICOM converter the DICOM reader is tested against
  dcm2niix
  # service
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  prometheus-cpp-dev libssl-dev
  # utilities and tests
  nlohmann-json3-dev libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev
  python3
  # a real MRI volume (Colin27 T1) for the mesh tests on MRI
  mricron-data
  # web viewer end-to-end test: Debian's Chromium driven by playwright-core
  chromium
  # workstation viewer (vpm-view) and its test under a virtual X server
  libsdl2-dev xvfb xdotool x11-utils imagemagick
  # PACS: the DICOMweb client's HTTP (libcurl); the live tests' PACS
  # (Orthanc with its DICOMweb and GDCM plugins, run unprivileged on
  # loopback by tests/pacs), their DICOM reading (pydicom, numpy) and their
  # thumbnails' PNGs (PIL)
  libcurl4-openssl-dev orthanc orthanc-dicomweb orthanc-gdcm python3-pydicom python3-numpy
  python3-pil
  # the exported DICOM checked against its IODs (dciodvfy)
  dicom3tools
  # cases: the embedded SQLite database (--state-dir), PostgreSQL's client
  # library (--state) and its server for the tests (run unprivileged on a
  # Unix socket by scripts/pg-test-server.sh)
  libsqlite3-dev libpq-dev postgresql
  # a DICOM series uploaded as a zip or tar archive (libarchive)
  libarchive-dev
  # deployment checks: YAML parsing of the compose and Kubernetes files; the
  # balancer docker/ ships (HAProxy), run by `ctest -R balancer`
  python3-yaml haproxy
)
# Node.js and npm for the web gateway: Debian's packages unless a node and npm
# are already on the PATH (a machine may carry a newer Node.js of its own).
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  packages+=(nodejs npm)
fi
if [ "${1:-}" = "--only" ]; then
  shift
  packages=("$@")
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${#missing[@]} missing packages: ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then sudo_cmd=(sudo); else
    echo "install-deps: need root to install: ${missing[*]}" >&2; exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
