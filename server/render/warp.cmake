# Volume warping (ALGORITHM.md section 7): the backward map, the resampled
# volume, and their CPU references (docs/WARP.md).
add_library(vpm_warp
  ${CMAKE_CURRENT_LIST_DIR}/backward_map.cc
  ${CMAKE_CURRENT_LIST_DIR}/backward_map_cpu.cc
  ${CMAKE_CURRENT_LIST_DIR}/backward_map_values.cc
  ${CMAKE_CURRENT_LIST_DIR}/check_map_inputs.cc
  ${CMAKE_CURRENT_LIST_DIR}/tet_displacement_frame.cc
  ${CMAKE_CURRENT_LIST_DIR}/tet_grid_boxes.cc
  ${CMAKE_CURRENT_LIST_DIR}/warp_volume.cc
  ${CMAKE_CURRENT_LIST_DIR}/warp_volume_cpu.cc
)
target_link_libraries(vpm_warp PUBLIC vpm_volume vpm_volume_gpu vpm_gpu vpm_shaders vpm_tetmesh)
