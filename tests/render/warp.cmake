# Volume warping: backward map and resampling, GPU against the CPU references
# (validation layer on through GpuTest).
vpm_add_test(NAME warp_test
  SOURCES backward_map_test.cc tet_grid_boxes_test.cc warp_volume_test.cc
  LIBS vpm_warp vpm_gpu_testing)
