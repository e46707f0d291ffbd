// The alternate signal stack each runtime thread gets, so that fba-run's crash handler can still
// run when a component overflowed its stack. Apart because it is the one piece of the runtime
// that is about signals rather than tasks.
#include <signal.h>

#include <memory>

#include "graph.hpp"

namespace fba::detail {

void prepare_thread_for_crash_reports() {
  struct AltStack {
    std::unique_ptr<char[]> memory;
    ~AltStack() {
      if (!memory) return;
      stack_t off{};
      off.ss_flags = SS_DISABLE;
      sigaltstack(&off, nullptr);  // before the memory goes
    }
  };
  thread_local AltStack alt;
  if (alt.memory) return;
  constexpr std::size_t kSize = 64 * 1024;
  alt.memory = std::make_unique<char[]>(kSize);
  stack_t ss{};
  ss.ss_sp = alt.memory.get();
  ss.ss_size = kSize;
  if (sigaltstack(&ss, nullptr) != 0) alt.memory.reset();
}

}  // namespace fba::detail
