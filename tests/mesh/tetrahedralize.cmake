# Delaunay, mesh measurements and mesh files (vpm_tetmesh).
vpm_add_test(NAME tetmesh_test
  SOURCES
    tetrahedralize_test.cc
    tet_quality_test.cc
    tet_locator_test.cc
    tf_positive_set_test.cc
    reconstruction_error_test.cc
    largest_empty_sphere_test.cc
    mesh_json_test.cc
    write_vtu_test.cc
  LIBS vpm_tetmesh)
