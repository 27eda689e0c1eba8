# The deformable scene: FEM + backward map + renderer for one case.
add_library(vpm_scene ${CMAKE_CURRENT_LIST_DIR}/deformable_scene.cc)
target_link_libraries(vpm_scene PUBLIC vpm_fem vpm_warp vpm_raycast)
