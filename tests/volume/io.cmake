# Tests of the volume readers, the NIfTI writer and the source dispatcher.
if(TARGET DCMTK::dcmdata)
  set(VPM_TEST_DCMTK_LIBS DCMTK::dcmdata DCMTK::dcmjpeg DCMTK::dcmjpls)
else()
  set(VPM_TEST_DCMTK_LIBS ${DCMTK_LIBRARIES})
endif()
vpm_add_test(NAME volume_io_test
  SOURCES
    ${CMAKE_CURRENT_LIST_DIR}/check_dicom_structure_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/fuzz_seeds_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/read_dicom_series_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/read_metaimage_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/read_nifti_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/read_nrrd_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/read_raw_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/read_volume_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/write_nifti_test.cc
  LIBS vpm_volume_io ${NIFTI2_LIBRARY} ${ZNZ_LIBRARY} ${VPM_TEST_DCMTK_LIBS} ZLIB::ZLIB m)
# The tests also use nifti_clib directly, as an independent reader, and
# DCMTK to write DICOM series.
target_include_directories(volume_io_test SYSTEM PRIVATE ${NIFTI_INCLUDE_DIR})

# Runs every fuzz target briefly (builds build-fuzz with clang on first use).
add_test(NAME fuzz_readers_smoke
  COMMAND ${CMAKE_SOURCE_DIR}/scripts/fuzz.sh 5
  WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(fuzz_readers_smoke PROPERTIES LABELS fuzz TIMEOUT 1800)
