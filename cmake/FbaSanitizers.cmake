# FBA_SANITIZE=address,undefined or thread: applied to everything this project builds.
if(FBA_SANITIZE)
  set(_fba_san_flags -fsanitize=${FBA_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_compile_options(${_fba_san_flags})
  add_link_options(${_fba_san_flags})
  # clang compiles in ASan's stack-use-after-return checks, which its runtime leaves off unless
  # ASAN_OPTIONS asks (detect_stack_use_after_return, false in clang 14's), and CI does not ask:
  # code that never runs, compiled for nothing (docs/results.md, "CI time").
  if(FBA_SANITIZE MATCHES "address" AND CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    add_compile_options(-fsanitize-address-use-after-return=never)
  endif()
endif()

# fba_compute_target(<target>) marks a target whose code does the heavy computing (carving, grasp
# synthesis, rendering, the quality measure, the runtime's data sets and task loader) or a test whose
# own checks compute (Eigen in a test's file): FBA_COMPUTE_FLAGS is added to its compile options.
# tools/dev.sh's sanitizer builds compile at -O0 and these at -O2 (it says why, with the figures).
set(FBA_COMPUTE_FLAGS "" CACHE STRING "Compile options added to the computing targets (tools/dev.sh: -O2 in its -O0 sanitizer builds)")
function(fba_compute_target target)
  if(FBA_COMPUTE_FLAGS)
    separate_arguments(flags UNIX_COMMAND "${FBA_COMPUTE_FLAGS}")
    target_compile_options(${target} PRIVATE ${flags})
  endif()
endfunction()
