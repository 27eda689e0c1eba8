# Delaunay tetrahedralization of the proxy mesh and the section-6 mesh
# measurements (quality, point location, reconstruction error, largest empty
# sphere), plus the mesh file writers. CGAL is included by tetrahedralize.cc
# only, so that one file pays its compile time.
add_library(vpm_tetmesh
  vertex_kind_name.cc
  tetrahedralize.cc
  tet_quality.cc
  tet_locator.cc
  tf_positive_set.cc
  sample_trilinear.cc
  rasterize_tets.cc
  reconstruction_error.cc
  interpolate_on_mesh.cc
  largest_empty_sphere.cc
  mesh_json.cc
  write_vtu.cc
)
target_link_libraries(vpm_tetmesh
  PUBLIC vpm_volume nlohmann_json::nlohmann_json Threads::Threads
  PRIVATE CGAL::CGAL)
