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
# ctest's --timeout). COST (roughly its seconds under ASan), for a binary that runs long (tens of
# seconds or more) and is one CTest test (FBA_TEST_EACH_CASE=OFF, as in CI): ctest starts the
# costliest first, so that the longest does not start last and run alone while the other cores
# idle. ctest orders by the times it recorded itself, but a clean checkout (CI's) has none.
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

# Each module's tests live beside it, in its tests/ folder (core/tests, core/<part>/tests, libs/<lib>/tests,
# plugins/<plugin>/tests, hardware/<device>/tests, tools/<tool>/tests); tests/ holds only what
# belongs to no single module (shared helpers, the task files' graph tests, the broken-task corpus,
# the fuzzer, the install test). Test code is compiled as below wherever it lives.
#
# fba_test_code(<target> [COMPUTE]): marks a target as test code. What the tests check (the core, plugins
# and programs) is built as users build it; the tests' own code is optimised less, because it is half
# of what CI compiles and runs little. In an optimised build: -O0, or -O1 for a test whose own checks
# compute (COMPUTE: Eigen in its files, loops over meshes). Under the sanitizers (tools/dev.sh) the
# tests compile at -O0 too but for those that compute (fba_compute_target: its -O2), and the slowest
# tests carve smaller problems (FBA_TEST_SANITIZED). (docs/results.md, "CI time", has the figures.)
# Not -O0 in a GCC sanitizer build: under GCC's ASan, Eigen's aligned_malloc adds its own header (its
# Memory.h trusts malloc's alignment only without __SANITIZE_ADDRESS__) while KDL, built without ASan,
# frees with free(); at -O0 a test binary's out-of-line aligned_malloc was exported and interposed
# KDL's, and every arm test aborted with an ASan bad-free in ChainIkSolverPos_LMA. clang's sanitizer
# builds export no such symbol from a test (nm -D), and the arm tests would abort if one did.
# The target joins fba_tests (fba_add_test_folders), which a sanitizer build builds alone.
function(fba_test_code target)
  cmake_parse_arguments(ARG "COMPUTE" "" "" ${ARGN})
  if(FBA_SANITIZE)
    target_compile_definitions(${target} PRIVATE FBA_TEST_SANITIZED=1)
    if(ARG_COMPUTE)
      fba_compute_target(${target})
    endif()
  elseif(ARG_COMPUTE)
    target_compile_options(${target} PRIVATE $<$<CONFIG:Release,RelWithDebInfo,MinSizeRel>:-O1>)
  else()
    target_compile_options(${target} PRIVATE $<$<CONFIG:Release,RelWithDebInfo,MinSizeRel>:-O0>)
  endif()
  set_property(GLOBAL APPEND PROPERTY FBA_TEST_TARGETS ${target})
endfunction()

# fba_add_test(<target> SOURCES <file>... [LIBRARIES <lib>...] [DEPENDS <target>...]
#              LABELS <label>... [TIMEOUT <seconds>] [COST <seconds>] [COMPUTE])
# One GoogleTest executable: built from SOURCES as test code (fba_test_code), linked with LIBRARIES,
# GoogleTest's main and the build's paths (tests/support/build_paths.hpp; tests/ is on its include
# path, so `#include "support/..."`), built after DEPENDS (the programs and plugins it runs), and
# registered with CTest (fba_add_gtest: LABELS, TIMEOUT, COST). COMPUTE: its own checks compute, so
# it is optimised more (fba_test_code).
function(fba_add_test target)
  cmake_parse_arguments(ARG "COMPUTE" "TIMEOUT;COST" "SOURCES;LIBRARIES;DEPENDS;LABELS" ${ARGN})
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "fba_add_test(${target}): give its SOURCES")
  endif()
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_LIBRARIES} GTest::gtest_main fba_build_paths)
  if(ARG_DEPENDS)
    add_dependencies(${target} ${ARG_DEPENDS})
  endif()
  set(compute "")
  if(ARG_COMPUTE)
    set(compute COMPUTE)
  endif()
  fba_test_code(${target} ${compute})
  set(options LABELS ${ARG_LABELS})
  if(ARG_TIMEOUT)
    list(APPEND options TIMEOUT ${ARG_TIMEOUT})
  endif()
  if(ARG_COST)
    list(APPEND options COST ${ARG_COST})
  endif()
  fba_add_gtest(${target} ${options})
endfunction()

# fba_add_test_folders(): every module's tests/ folder, then tests/, and the target fba_tests that
# builds every test target (fba_test_code), so that a sanitizer build builds what its tests run and
# nothing else (fba-run, the programs and the plugins come in as their dependencies). Called once,
# after every module is configured: a test may need any program or plugin, wherever it is defined,
# and some tests are left out when what they test is (if(TARGET ...)).
function(fba_add_test_folders)
  file(GLOB folders LIST_DIRECTORIES true RELATIVE ${PROJECT_SOURCE_DIR}
       ${PROJECT_SOURCE_DIR}/core/tests ${PROJECT_SOURCE_DIR}/core/*/tests ${PROJECT_SOURCE_DIR}/libs/*/tests ${PROJECT_SOURCE_DIR}/plugins/*/tests
       ${PROJECT_SOURCE_DIR}/hardware/*/tests ${PROJECT_SOURCE_DIR}/tools/*/tests)
  foreach(folder IN LISTS folders)
    if(EXISTS ${PROJECT_SOURCE_DIR}/${folder}/CMakeLists.txt)
      add_subdirectory(${PROJECT_SOURCE_DIR}/${folder} ${PROJECT_BINARY_DIR}/${folder})
    endif()
  endforeach()
  add_subdirectory(${PROJECT_SOURCE_DIR}/tests ${PROJECT_BINARY_DIR}/tests)
  get_property(targets GLOBAL PROPERTY FBA_TEST_TARGETS)
  add_custom_target(fba_tests)
  if(targets)
    add_dependencies(fba_tests ${targets})
  endif()
endfunction()
