vpm_add_test(NAME phantom_test SOURCES phantom_test.cc LIBS vpm_phantom)
