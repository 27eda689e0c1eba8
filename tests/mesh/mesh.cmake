vpm_add_test(NAME mesh_test
  SOURCES lattice_test.cc decimate_test.cc classify_refine_test.cc
  LIBS vpm_mesh)
vpm_add_test(NAME mesh_gpu_test
  SOURCES lattice_costs_gpu_test.cc
  LIBS vpm_mesh vpm_gpu_testing)
vpm_add_test(NAME compare_meshes_test
  SOURCES compare_meshes_test.cc
  LIBS vpm_mesh vpm_phantom)
vpm_add_test(NAME deformation_measures_test
  SOURCES deformation_measures_test.cc
  LIBS vpm_mesh vpm_phantom)
