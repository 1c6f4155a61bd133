# Writes CTEST_FILE, the ctest tests of the GoogleTest binary EXE, after each
# link (cmake -P, from tests/CMakeLists.txt): one ctest test per test suite
# for the quick tests, so that a process (about 0.15 s to load OpenCV, GDAL
# and PoCL) and the fixtures it builds serve the whole suite, and one per
# test for those whose names match E2E (each its own process and timeout).
# Labels: DEVICE (host or opencl) and fast or e2e, and mpi for the e2e tests
# that match MPI. The runs the tests make keep no program binaries
# (SAPMVS_PROGRAM_CACHE=off): they would fill the user's cache folder, and
# PoCL compiles a program once more to hand out its binary (0.5 s each), for
# the tests' many variants; the cache's own tests give it folders.
execute_process(COMMAND "${EXE}" --gtest_list_tests OUTPUT_VARIABLE listing
                RESULT_VARIABLE rc TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${EXE} --gtest_list_tests failed (${rc})")
endif()
string(REPLACE ";" "," listing "${listing}")
string(REPLACE "\n" ";" lines "${listing}")
set(suites)
foreach(line IN LISTS lines)
  if(line MATCHES "^([^ #]+)\\.( *#.*)?$")
    set(suite "${CMAKE_MATCH_1}")
    list(APPEND suites "${suite}")
    set(e2e_${suite})
  elseif(line MATCHES "^  ([^ ]+)")
    set(test "${suite}.${CMAKE_MATCH_1}")
    if(test MATCHES "${E2E}")
      list(APPEND e2e_${suite} "${test}")
    else()
      set(fast_${suite} TRUE)
    endif()
  endif()
endforeach()

set(out "")
macro(add name filter labels)
  string(APPEND out "add_test([==[${name}]==] [==[${EXE}]==] [==[--gtest_filter=${filter}]==])\n"
         "set_tests_properties([==[${name}]==] PROPERTIES WORKING_DIRECTORY [==[${WORKDIR}]==]"
         " TIMEOUT 600 LABELS [==[${labels}]==]"
         " ENVIRONMENT [==[SAPMVS_PROGRAM_CACHE=off]==])\n")
endmacro()
foreach(suite IN LISTS suites)
  if(fast_${suite})
    string(JOIN ":" skip ${e2e_${suite}})
    if(skip)
      add("${suite}" "${suite}.*:-${skip}" "${DEVICE};fast")
    else()
      add("${suite}" "${suite}.*" "${DEVICE};fast")
    endif()
  endif()
  foreach(test IN LISTS e2e_${suite})
    if(MPI AND test MATCHES "${MPI}")
      add("${test}" "${test}" "${DEVICE};e2e;mpi")
    else()
      add("${test}" "${test}" "${DEVICE};e2e")
    endif()
    # A lone test that skips shows as skipped; a suite's skips are listed in
    # its output (a failure among them must not read as a skip).
    string(APPEND out "set_tests_properties([==[${test}]==] PROPERTIES"
           " SKIP_REGULAR_EXPRESSION [==[\\[  SKIPPED \\]]==])\n")
  endforeach()
endforeach()
file(WRITE "${CTEST_FILE}" "${out}")
