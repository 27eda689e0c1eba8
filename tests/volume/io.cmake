# Tests of the volume readers, the NIfTI writer and the source dispatcher.
vpm_add_test(NAME volume_io_test
  SOURCES
    ${CMAKE_CURRENT_LIST_DIR}/read_nifti_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/write_nifti_test.cc
  LIBS vpm_volume_io ${NIFTI2_LIBRARY} ${ZNZ_LIBRARY} ZLIB::ZLIB m)
# The tests also use nifti_clib directly, as an independent reader.
target_include_directories(volume_io_test SYSTEM PRIVATE ${NIFTI_INCLUDE_DIR})
