// A task with device slots and the profile that fills them: the loader's tests
// (core/tests/task_params_test.cpp) and fba-run's (tests/tasks/profile_cli_test.cpp) bind the same
// slots. The loader's tests name lines of the task: keep its layout.
#pragma once

namespace fba::test {

// Slots `source` and `pass` between nothing and a sink expecting n integers.
inline constexpr const char* kSlottedTask = R"(task: slotted
params:
  n: { type: int, default: 3, min: 1 }
components:
  source: { profile: true, doc: what produces the integers }
  pass: { profile: true, doc: what forwards them }
  sink: { type: examples.sink, params: { expected: "${n}" } }
connections:
  - source.out -> pass.in
  - pass.out -> sink.in
on: { sink.done: stop_success, sink.gap: stop_failure }
)";

// Fills the slots with a counter of n and a passthrough.
inline constexpr const char* kPassProfile = R"(profile: pass
doc: a counter and a passthrough
components:
  source: { type: examples.counter, params: { count: "${n}" } }
  pass: { type: examples.passthrough }
)";

}  // namespace fba::test
