vpm_add_test(NAME deformable_scene_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/deformable_scene_test.cc
  LIBS vpm_scene vpm_mesh vpm_gpu_testing)
