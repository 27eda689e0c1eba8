# Steps 1-4 of the proxy mesh and the pipeline that ties them together.
add_library(vpm_mesh
  ${CMAKE_CURRENT_LIST_DIR}/lattice.cc
  ${CMAKE_CURRENT_LIST_DIR}/lattice_costs.cc
  ${CMAKE_CURRENT_LIST_DIR}/lattice_costs_gpu.cc
  ${CMAKE_CURRENT_LIST_DIR}/indexed_min_heap.cc
  ${CMAKE_CURRENT_LIST_DIR}/monotone_min_queue.cc
  ${CMAKE_CURRENT_LIST_DIR}/point_grid.cc
  ${CMAKE_CURRENT_LIST_DIR}/decimate.cc
  ${CMAKE_CURRENT_LIST_DIR}/classify_hardness.cc
  ${CMAKE_CURRENT_LIST_DIR}/refine_at_point.cc
  ${CMAKE_CURRENT_LIST_DIR}/build_proxy_mesh.cc
  ${CMAKE_CURRENT_LIST_DIR}/compare_meshes.cc
  ${CMAKE_CURRENT_LIST_DIR}/deformation_measures.cc
)
target_link_libraries(vpm_mesh PUBLIC vpm_volume vpm_volume_gpu vpm_tetmesh vpm_fem)
# Step 2's neighbour search computes ~200 candidate distances per vertex in
# one flat loop; without errno for sqrt (never read) the compiler vectorizes
# it (the cost model of -O2 refuses loops that need a scalar tail). sqrt stays correctly rounded, so the results are the same bits.
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/decimate.cc
                            PROPERTIES COMPILE_OPTIONS "-fno-math-errno;-fvect-cost-model=dynamic")
