vpm_add_test(NAME raycast_test
  SOURCES
    ${CMAKE_CURRENT_LIST_DIR}/raycast_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/camera_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/overlay_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/frame_encoder_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/render_presets_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/pick_ray_test.cc
  LIBS vpm_raycast vpm_phantom vpm_gpu_testing)
# The golden images live in the source tree (tests/render/golden).
target_compile_definitions(raycast_test PRIVATE VPM_TEST_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
