include(GoogleTest)

# How a GoogleTest binary becomes CTest tests. ON (the default): each test case is its own CTest test,
# so `ctest -R Name` runs one case. OFF: each binary is one CTest test, its cases run in one process,
# and `ctest -R fba_core_tests` runs a binary (one case: bin/fba_core_tests --gtest_filter=Name).
# tools/dev.sh test (CI) turns it OFF: a test binary links OpenCV and, through it, 150 shared
# libraries, whose loading costs 0.15 s a process, 0.37 s under AddressSanitizer. With a process per
# case that was half of the sanitizer stage's test time (748 s of test time against 365 s).
option(FBA_TEST_EACH_CASE "Register each GoogleTest case as its own CTest test (OFF: each test binary as one)" ON)

# fba_add_gtest(<target> LABELS <label>... [TIMEOUT <seconds>] [COST <seconds>]): registers a
# GoogleTest binary with CTest, with its labels (ctest -L) and, per case, its timeout (a binary takes
# ctest's --timeout). COST (roughly its seconds under ASan), for a binary that runs for minutes and is
# one CTest test (FBA_TEST_EACH_CASE=OFF, as in CI): ctest starts the costliest first, so that the
# longest does not start last and run alone while the other cores idle. ctest orders by the times it
# recorded itself, but a clean checkout (CI's) has none.
function(fba_add_gtest target)
  cmake_parse_arguments(ARG "" "TIMEOUT;COST" "LABELS" ${ARGN})
  if(NOT ARG_LABELS)
    message(FATAL_ERROR "fba_add_gtest(${target}): give its LABELS")
  endif()
  if(FBA_TEST_EACH_CASE)
    # PRE_TEST: a binary is asked for its cases when ctest runs, not once more after every link.
    gtest_discover_tests(${target} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60 TEST_LIST ${target}_cases)
    # The properties are set by a script run after discovery, not through gtest_discover_tests'
    # PROPERTIES, which splits lists: LABELS "tasks;signals" became LABELS tasks and a property
    # named signals, and a TIMEOUT after it was lost (CMake issue 17812).
    set(properties "LABELS [==[${ARG_LABELS}]==]")
    if(ARG_TIMEOUT)
      string(APPEND properties " TIMEOUT ${ARG_TIMEOUT}")
    endif()
    set(script ${CMAKE_CURRENT_BINARY_DIR}/${target}_properties.cmake)
    file(WRITE ${script} "if(${target}_cases)\n  set_tests_properties(\${${target}_cases} PROPERTIES ${properties})\nendif()\n")
    set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${script})
  else()
    add_test(NAME ${target} COMMAND ${target})
    set_tests_properties(${target} PROPERTIES LABELS "${ARG_LABELS}" WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
    if(ARG_COST)
      set_tests_properties(${target} PROPERTIES COST ${ARG_COST})
    endif()
  endif()
endfunction()
