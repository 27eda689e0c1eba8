# Volume operations on the GPU (each has its CPU reference in vpm_volume).
add_library(vpm_volume_gpu
  ${CMAKE_CURRENT_LIST_DIR}/gpu_volume.cc
  ${CMAKE_CURRENT_LIST_DIR}/gradient_magnitude_gpu.cc
  ${CMAKE_CURRENT_LIST_DIR}/transfer_function_gpu.cc
)
target_link_libraries(vpm_volume_gpu PUBLIC vpm_volume vpm_gpu vpm_shaders)
