# vpm_gtest_suites(TARGET name [PROPERTIES prop value ...] [SERIAL_SUITES suite ...])
# One ctest entry per gtest suite of a test binary, named BINARY:SUITE
# (e.g. service_test:SessionTest), running `BINARY --gtest_filter=SUITE.*`
# in the build folder with the given test properties. SERIAL_SUITES run
# alone (RUN_SERIAL): suites that time a gRPC call's answer, which on two
# cores shared with another test's threads waits for a CPU. After each build of
# the binary its suites are listed (--gtest_list_tests,
# cmake/gtest_suites_list.cmake); ctest reads that list when it runs, as
# gtest_discover_tests does for single tests.
#
# Why suites, not single tests: a process per test paid for its start-up
# (the Vulkan loader and lavapipe, the shader cache, the first server) once
# per test: 0.6 s of CPU for a service test, 3 s under ThreadSanitizer. A
# suite pays it once (docs/benchmarks/CI_TIME.md). Every test still runs,
# and a failing suite's output names its failing tests.
#
# VPM_TEST_EXCLUDE (cache, default empty): gtest patterns, ':'-separated,
# that no entry runs (scripts/sanitize.sh leaves the longest tests to the
# unsanitized suite this way).
set(VPM_TEST_EXCLUDE "" CACHE STRING "gtest patterns (a:b) that no ctest entry runs")
set(VPM_GTEST_SUITES_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/gtest_suites_list.cmake)

function(vpm_gtest_suites)
  cmake_parse_arguments(ARG "" "TARGET" "PROPERTIES;SERIAL_SUITES" ${ARGN})
  set(list_file ${CMAKE_CURRENT_BINARY_DIR}/${ARG_TARGET}_suites.cmake)
  add_custom_command(TARGET ${ARG_TARGET} POST_BUILD
    COMMAND ${CMAKE_COMMAND} -D "binary=$<TARGET_FILE:${ARG_TARGET}>"
            -D "working_dir=${CMAKE_BINARY_DIR}" -D "out=${list_file}"
            -P ${VPM_GTEST_SUITES_SCRIPT}
    BYPRODUCTS ${list_file}
    VERBATIM)
  set(filter_tail "")
  if(NOT VPM_TEST_EXCLUDE STREQUAL "")
    set(filter_tail "-${VPM_TEST_EXCLUDE}")
  endif()
  set(props "WORKING_DIRECTORY [==[${CMAKE_BINARY_DIR}]==]")
  foreach(item IN LISTS ARG_PROPERTIES)
    string(APPEND props " [==[${item}]==]")
  endforeach()
  # Read by ctest: the list sets `binary` and `suites`; before the first
  # build there is none, and an entry says so.
  set(include_file ${CMAKE_CURRENT_BINARY_DIR}/${ARG_TARGET}_suites_include.cmake)
  file(WRITE ${include_file} "\
if(EXISTS [==[${list_file}]==])
  include([==[${list_file}]==])
  set(serial_suites [==[${ARG_SERIAL_SUITES}]==])
  foreach(suite IN LISTS suites)
    add_test(\"${ARG_TARGET}:\${suite}\" \"\${binary}\" \"--gtest_filter=\${suite}.*${filter_tail}\")
    set_tests_properties(\"${ARG_TARGET}:\${suite}\" PROPERTIES ${props})
    list(FIND serial_suites \"\${suite}\" serial)
    if(NOT serial EQUAL -1)
      set_tests_properties(\"${ARG_TARGET}:\${suite}\" PROPERTIES RUN_SERIAL TRUE)
    endif()
  endforeach()
else()
  add_test(${ARG_TARGET}_NOT_BUILT ${ARG_TARGET}_NOT_BUILT)
endif()
")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${include_file})
endfunction()
