#!/usr/bin/env bash
# Runs vpm's GPU-vs-CPU test binaries (under the Khronos validation layer) and
# its Vulkan benchmarks on another x86-64 Linux machine that has a GPU driver
# but no vpm build dependencies and no network.
#
#   scripts/gpu-check.sh bundle BUILD_DIR [DEST]   (here; DEST defaults to .gpu)
#       Copies stripped test and bench binaries, the shared libraries they
#       load (all but glibc's own), the validation layer and vulkaninfo
#       (Debian packages) into DEST/bundle.tar.xz, the Vulkan loader and
#       libglvnd packages into DEST/debs, and this script into DEST.
#       Needs apt-get download (Debian/Ubuntu) for the packages. Shaders are
#       compiled into the binaries, so nothing else is read at run time.
#   DEST/gpu-check.sh run [DEST]                    (there, in the repo root)
#       Unpacks the bundle under $TMPDIR, installs the loader only where
#       none is found, and writes everything to $OUT/log.txt (OUT defaults to
#       ./gpu-check-out) as it goes; vulkaninfo's full report goes to
#       $OUT/vulkaninfo.txt. VPM_VULKAN_DEVICE (a device-name substring, or
#       an index) picks the device; unset, vpm prefers a discrete GPU.
#       GPU_CHECK_BENCHES / GPU_CHECK_TESTS override the lists below (a
#       bench entry is its name, then its arguments, separated by ','); the
#       default benches skip their CPU-only parts (render_bench's CPU
#       reference, mesh_build_bench's O(N^2) scaling, the 5,000-vertex drag),
#       so the whole run takes about 4 minutes on a fast GPU. Then vpm's side
#       of bench/peer_vtk.py (--vpm-only: no VTK there; python3 with numpy
#       and Pillow), with GPU_CHECK_PEER_ARGS (empty: skipped) and
#       GPU_CHECK_PEER_TIMEOUT (seconds, default 300). Where
#       nvidia-smi is found, the SM clock, P-state and load are logged every
#       250 ms during the benches to $OUT/clocks.csv.
#       GPU_CHECK_TEST_TIMEOUT / GPU_CHECK_BENCH_TIMEOUT: seconds per binary.
# DEST is meant to be ignored by git (echo /.gpu/ >> .git/info/exclude) and
# carried to the other machine beside the repository's working tree.
set -uo pipefail

TESTS_DEFAULT="gpu/gpu_core_test volume/volume_test warp/warp_test raycast/raycast_test mesh/mesh_test scene/deformable_scene_test"
BENCHES_DEFAULT="gradient_bench mesh_build_bench,--stages-only warp_bench render_bench,--no-reference
  sample_rate_bench slice_bench drag_loop_bench,--max-vertices,1000 render_storm_bench
  step_psnr_bench,--cut,tests/data/ct-abdomen-kidney/ct_abdomen.nii.gz,phantom:abdomen
  interactive_quality_bench,--cut,--candidates"
PEER_ARGS_DEFAULT="--sizes 512 --vpm-runs 1 --vpm-steps 4,3,2.25,2,1.5,1,0.75,0.625,0.5"

bundle() {
  local build=${1:?usage: gpu-check.sh bundle BUILD_DIR [DEST]} dest=${2:-.gpu}
  local stage; stage=$(mktemp -d)
  mkdir -p "$stage"/bin "$stage"/lib "$stage"/lib-cxx "$stage"/layer "$stage"/vkinfo "$dest"/debs
  local t b l
  for t in ${GPU_CHECK_TESTS:-$TESTS_DEFAULT}; do
    strip --strip-unneeded -o "$stage/bin/${t##*/}" "$build/tests/$t" || return 1
  done
  cmake --build "$build" --target benches || return 1  # not in the default build
  for b in ${GPU_CHECK_BENCHES:-$BENCHES_DEFAULT}; do
    strip --strip-unneeded -o "$stage/bin/${b%%,*}" "$build/bench/${b%%,*}" || return 1
  done
  # The peer step's volume export (vpm volume export).
  strip --strip-unneeded -o "$stage/bin/vpm" "$build/client/vpm" || return 1
  for l in $(ldd "$stage"/bin/* | awk '/=> \//{print $3}' | sort -u); do
    case ${l##*/} in
      libc.so*|libm.so*|libpthread.so*|libdl.so*|librt.so*|ld-linux*|libvulkan.so*) ;;
      libstdc++.so*|libgcc_s.so*) cp -L "$l" "$stage"/lib-cxx/ ;;
      *) cp -L "$l" "$stage"/lib/ ;;
    esac
  done
  strip --strip-unneeded "$stage"/lib/* "$stage"/lib-cxx/* 2>/dev/null
  local layer_json=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json
  if [ -f "$layer_json" ]; then
    cp "$layer_json" "$stage"/layer/
    strip --strip-unneeded -o "$stage"/layer/libVkLayer_khronos_validation.so \
      "$(ldconfig -p | awk '/libVkLayer_khronos_validation.so/{print $NF; exit}')"
  else
    echo "no validation layer here (apt-get install vulkan-validationlayers); tests will run without it"
  fi
  local apt_opts=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64)
  local deb_dir; deb_dir=$(mktemp -d)
  (cd "$deb_dir" && apt-get "${apt_opts[@]}" download vulkan-tools libwayland-client0 libx11-6 \
      libxcb1 libxau6 libxdmcp6 libbsd0 libmd0 libffi8 >/dev/null) &&
    for f in "$deb_dir"/*.deb; do dpkg -x "$f" "$deb_dir/x"; done &&
    cp "$deb_dir"/x/usr/bin/vulkaninfo "$stage"/vkinfo/ &&
    cp -L "$deb_dir"/x/usr/lib/x86_64-linux-gnu/lib*.so.[0-9] "$stage"/vkinfo/ ||
    echo "vulkaninfo not bundled (apt-get download failed)"
  rm -f "$dest"/debs/*.deb
  (cd "$dest"/debs && apt-get "${apt_opts[@]}" download libvulkan1 libglvnd0 libegl1 libgl1 \
      libglx0 libgles2 libopengl0 >/dev/null) || echo "loader packages not downloaded"
  tar -C "$stage" -cf - . | xz -6 -T0 > "$dest"/bundle.tar.xz || return 1
  [ "$(realpath "$0")" = "$(realpath -m "$dest"/gpu-check.sh)" ] || cp "$0" "$dest"/gpu-check.sh
  rm -rf "$stage" "$deb_dir"
  du -sh "$dest"
}

run() {
  local dest=${1:-.gpu}
  OUT=${OUT:-$PWD/gpu-check-out}
  mkdir -p "$OUT"
  exec > >(tee -a "$OUT/log.txt") 2>&1
  local root=$PWD
  local b; b=$(mktemp -d "${TMPDIR:-/tmp}/vpm-gpu.XXXXXX")
  echo "# vpm GPU check, $(date -u +%Y-%m-%dT%H:%M:%SZ), $(nproc) cores, $(uname -m), $(ldd --version | head -1)"
  xz -dc "$dest"/bundle.tar.xz | tar -C "$b" -xf - || { echo "cannot unpack the bundle"; exit 1; }
  if ! ldconfig -p | grep -q 'libvulkan.so.1 ' || ! ldconfig -p | grep -q 'libGLdispatch.so.0 '; then
    echo "no Vulkan loader or libglvnd installed: unpacking $dest/debs"
    for f in "$dest"/debs/*.deb; do dpkg -x "$f" /; done
    ldconfig
  fi
  # The bundle's libstdc++ only where the system's is older than the build's.
  local cxx="" sys_cxx
  sys_cxx=$(ldconfig -p | awk '/libstdc\+\+.so.6 /{print $NF; exit}')
  local need; need=$(grep -ao 'GLIBCXX_3\.4\.[0-9]*' "$b"/bin/* | sed 's/.*://' | sort -uV | tail -1)
  if [ -z "$sys_cxx" ] || ! grep -aq "$need" "$sys_cxx"; then cxx=":$b/lib-cxx"; fi
  export LD_LIBRARY_PATH="$b/lib$cxx${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  # vpm's tests enable validation where the layer's manifest is in a system
  # folder (tests/gpu/gpu_test_context.cc), so the manifest goes there.
  if [ -f "$b"/layer/VkLayer_khronos_validation.json ]; then
    local layer_dir=/usr/share/vulkan/explicit_layer.d
    if [ ! -f "$layer_dir"/VkLayer_khronos_validation.json ]; then
      mkdir -p "$layer_dir" 2>/dev/null &&
        sed "s|\"library_path\": *\"[^\"]*\"|\"library_path\": \"$b/layer/libVkLayer_khronos_validation.so\"|" \
          "$b"/layer/VkLayer_khronos_validation.json > "$layer_dir"/VkLayer_khronos_validation.json ||
        echo "cannot install the validation layer's manifest (not root?): tests run without it"
    fi
  fi
  # NVIDIA's container runtime mounts the driver under /usr/local/nvidia,
  # where the loader does not look for its manifest.
  local nv_icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
  if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f $nv_icd ] && ! ls /usr/share/vulkan/icd.d/nvidia* /etc/vulkan/icd.d/nvidia* >/dev/null 2>&1; then
    export VK_DRIVER_FILES=$nv_icd VK_ICD_FILENAMES=$nv_icd
  fi
  local vkinfo=("$b"/vkinfo/vulkaninfo)
  local vkinfo_env=(env LD_LIBRARY_PATH="$b/vkinfo:$LD_LIBRARY_PATH")
  export VPM_SOURCE_DIR=$root
  echo "VK_DRIVER_FILES=${VK_DRIVER_FILES:-} VPM_VULKAN_DEVICE=${VPM_VULKAN_DEVICE:-}"
  echo; echo "## nvidia-smi"
  command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv
  if [ -x "${vkinfo[0]}" ]; then
    echo; echo "## vulkaninfo --summary (devices)"
    if ! "${vkinfo_env[@]}" timeout 60 "${vkinfo[@]}" --summary 2>&1 | grep -q '^GPU0'; then
      echo "vulkaninfo found no device; the loader's report:"
      "${vkinfo_env[@]}" VK_LOADER_DEBUG=error,warn,driver timeout 60 "${vkinfo[@]}" --summary 2>&1 | tail -40
    fi
    "${vkinfo_env[@]}" timeout 60 "${vkinfo[@]}" --summary 2>&1 |
      sed -n '/^Instance Layers/,/^Devices/p;/^GPU[0-9]/,/^$/p'
    "${vkinfo_env[@]}" timeout 60 "${vkinfo[@]}" > "$OUT"/vulkaninfo.txt 2>&1
    grep -iE 'subgroupSize|minSubgroupSize|maxSubgroupSize|maxComputeWorkGroupInvocations|timestampPeriod|shaderFloat64|shaderInt16 ' "$OUT"/vulkaninfo.txt | sort -u | head -20
  fi
  local failed=0 t s=$SECONDS
  for t in ${GPU_CHECK_TESTS:-$TESTS_DEFAULT}; do
    echo; echo "## test ${t##*/}"
    (cd "$root" && timeout "${GPU_CHECK_TEST_TIMEOUT:-240}" "$b/bin/${t##*/}" --gtest_color=no) ||
      { echo "## test ${t##*/}: exit $?"; failed=$((failed + 1)); }
  done
  echo; echo "## tests: $failed binaries failed, $((SECONDS - s)) s"
  local clocks=""
  if command -v nvidia-smi >/dev/null; then
    nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,pstate,utilization.gpu \
      --format=csv -lms 250 > "$OUT"/clocks.csv 2>&1 &
    clocks=$!
  fi
  local entry args
  for entry in ${GPU_CHECK_BENCHES:-$BENCHES_DEFAULT}; do
    IFS=, read -r -a args <<< "$entry"
    t=${args[0]}
    echo; echo "## $t ${args[*]:1}"
    s=$SECONDS
    (cd "$root" && timeout "${GPU_CHECK_BENCH_TIMEOUT:-120}" "$b/bin/$t" "${args[@]:1}") ||
      echo "## $t: exit $?"
    echo "## $t: $((SECONDS - s)) s"
  done
  peer "$b" "$root"
  [ -n "$clocks" ] && kill "$clocks" 2>/dev/null
  echo; echo "# done, $(date -u +%H:%M:%SZ)"
}

# vpm's side of bench/peer_vtk.py, run from the bundle's binaries laid out as
# a build folder.
peer() {
  local b=$1 root=$2 peer_args=${GPU_CHECK_PEER_ARGS-$PEER_ARGS_DEFAULT}
  [ -n "$peer_args" ] || return 0
  mkdir -p "$b"/build/bench "$b"/build/client
  ln -sf "$b"/bin/render_bench "$b"/build/bench/render_bench
  ln -sf "$b"/bin/vpm "$b"/build/client/vpm
  echo; echo "## peer_vtk.py --vpm-only $peer_args"
  local s=$SECONDS
  # shellcheck disable=SC2086  # the arguments are a list
  (cd "$root" && PYTHONUNBUFFERED=1 timeout "${GPU_CHECK_PEER_TIMEOUT:-300}" python3 \
    bench/peer_vtk.py --vpm-only --build "$b"/build --out "$b"/peer $peer_args) ||
    echo "## peer_vtk.py: exit $?"
  echo "## peer_vtk.py: $((SECONDS - s)) s"
}

case ${1:-} in
  bundle) shift; bundle "$@" ;;
  run) shift; run "$@" ;;
  *) sed -n '2,31p' "$0"; exit 2 ;;
esac
