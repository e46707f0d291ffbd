# FBA_SANITIZE=address,undefined or thread: applied to everything this project builds.
if(FBA_SANITIZE)
  set(_fba_san_flags -fsanitize=${FBA_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_compile_options(${_fba_san_flags})
  add_link_options(${_fba_san_flags})
endif()

# fba_compute_target(<target>) marks a target whose code does the heavy computing (carving, grasp
# synthesis, rendering, the quality measure, the runtime's data sets and task loader) or a test whose
# own checks compute (Eigen in a test's file): FBA_COMPUTE_FLAGS is added to its compile options.
# The sanitizer builds of tools/dev.sh compile at -O0 and these at -O2: optimising is most of an
# instrumented build's compile time elsewhere (the core's task-loader batch under clang's ASan+UBSan:
# 72 s of CPU at -O1, 26 s at -O0), and these need optimised code for their tests to run in minutes
# (Eigen at -O0 ran the grasp tests 7 times slower). clang compiles them as fast at -O2 as at -O1
# (the same batch 73 s) and the carving tests run a quarter faster.
set(FBA_COMPUTE_FLAGS "" CACHE STRING "Compile options added to the computing targets (tools/dev.sh: -O2 in its -O0 sanitizer builds)")
function(fba_compute_target target)
  if(FBA_COMPUTE_FLAGS)
    separate_arguments(flags UNIX_COMMAND "${FBA_COMPUTE_FLAGS}")
    target_compile_options(${target} PRIVATE ${flags})
  endif()
endfunction()
