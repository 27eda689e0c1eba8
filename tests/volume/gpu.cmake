vpm_add_test(NAME volume_gpu_test
  SOURCES gradient_magnitude_test.cc transfer_function_test.cc
  LIBS vpm_volume_gpu vpm_gpu_testing)
