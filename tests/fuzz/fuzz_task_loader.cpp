// libFuzzer target: arbitrary bytes into the task loader. A ConfigError whose every diagnostic
// has a line is the loader doing its job; any other exception (it reaches std::terminate), a
// diagnostic without a line, a crash or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fba/registry.hpp"
#include "fba/task_config.hpp"
#include "support/build_paths.hpp"

namespace {

// The example components are compiled into this program (no dlopen), plus the examples'
// composite, so inputs can reach every kind of component.
const fba::Registry& registry() {
  static const fba::Registry r = [] {
    fba::Registry reg;
    reg.add_builtin(fba::detail::plugin_entries());
    fba::register_composite_file(reg, fba::test::source_dir() + "/plugins/examples/relay.yaml");
    return reg;
  }();
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    // Relative to the broken-task corpus, so that includes reach its helper composites (every
    // kind of parameter, and broken definitions).
    fba::load_task_text(text, "fuzz.yaml", fba::test::source_dir() + "/tests/broken_tasks", registry());
  } catch (const fba::ConfigError& e) {
    // The loader's promise: every error says where. One without a line is a finding too.
    for (const auto& d : e.diagnostics())
      if (d.where.line <= 0) {
        std::fprintf(stderr, "diagnostic without a line: %s\n", d.str().c_str());
        std::abort();
      }
  }
  return 0;
}
