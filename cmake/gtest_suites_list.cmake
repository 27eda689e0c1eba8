# Run after a test binary is built (cmake/GtestSuites.cmake): writes `out`,
# which sets `binary` and `suites` (the binary's gtest suites but those
# whose names start with DISABLED_). Inputs (-D): binary, working_dir, out.
execute_process(COMMAND "${binary}" --gtest_list_tests
                WORKING_DIRECTORY "${working_dir}"
                TIMEOUT 60
                OUTPUT_VARIABLE listing
                ERROR_VARIABLE errors
                RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  file(REMOVE "${out}")
  message(FATAL_ERROR "${binary} --gtest_list_tests failed (${result}):\n${errors}")
endif()
string(REPLACE "\n" ";" lines "${listing}")
set(suites "")
foreach(line IN LISTS lines)
  # A suite line is its name and a dot at the start of the line (typed
  # suites add "  # TypeParam = ..."); the tests' lines are indented.
  if(line MATCHES "^([A-Za-z_][A-Za-z0-9_/]*)\\.( .*)?$")
    set(suite "${CMAKE_MATCH_1}")
    if(NOT suite MATCHES "^DISABLED_")
      list(APPEND suites "${suite}")
    endif()
  elseif(NOT line STREQUAL "" AND NOT line MATCHES "^ " AND NOT line MATCHES "^Running main")
    # Never a suite left out unseen.
    file(REMOVE "${out}")
    message(FATAL_ERROR "${binary} --gtest_list_tests: a line not understood: '${line}'")
  endif()
endforeach()
if(NOT suites)
  file(REMOVE "${out}")
  message(FATAL_ERROR "${binary}: --gtest_list_tests listed no suite")
endif()
file(WRITE "${out}" "set(binary [==[${binary}]==])\nset(suites ${suites})\n")
