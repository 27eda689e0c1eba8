# Ray casting: camera, presets, overlays, the GPU renderer, its CPU
# reference, and frame encoding (docs/RENDERING.md).
find_package(PNG REQUIRED)
pkg_check_modules(TURBOJPEG REQUIRED IMPORTED_TARGET libturbojpeg)

add_library(vpm_raycast
  ${CMAKE_CURRENT_LIST_DIR}/camera.cc
  ${CMAKE_CURRENT_LIST_DIR}/frame_encoder.cc
  ${CMAKE_CURRENT_LIST_DIR}/overlay.cc
  ${CMAKE_CURRENT_LIST_DIR}/pick_ray.cc
  ${CMAKE_CURRENT_LIST_DIR}/raycast_cpu.cc
  ${CMAKE_CURRENT_LIST_DIR}/render_presets.cc
  ${CMAKE_CURRENT_LIST_DIR}/render_request.cc
  ${CMAKE_CURRENT_LIST_DIR}/volume_renderer.cc
)
target_link_libraries(vpm_raycast
  PUBLIC vpm_volume_gpu vpm_volume vpm_gpu vpm_shaders Threads::Threads
  PRIVATE PNG::PNG PkgConfig::TURBOJPEG)
