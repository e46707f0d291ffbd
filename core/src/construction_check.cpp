// check_construction (see fba/task.hpp): what fba-run --check adds to the loader's checks. Which
// components are constructed, and why only those: a filter holds no device by its kind's contract
// (devices belong to sensors and actuators, and a blocking type waits on something outside), so
// constructing one has no effect beyond the process, and a run constructs it the same way. Its
// constructor is where a handle the spec does not declare is first used when the component binds
// its ports and parameters there (ctx(kOut) kept as a member), and where a filter refuses a
// configuration the spec's declarative checks cannot express. Both are then found by --check, as
// the plugin's mistake or the task's, not by a run. A handle first used in process() cannot be seen
// without running it: C++ has no way to list the handles a function uses, and calling process()
// without inputs would be a run of its own.
#include <exception>

#include "fba/component.hpp"
#include "fba/message_text.hpp"
#include "fba/task.hpp"
#include "graph.hpp"
#include "node.hpp"

namespace fba {

void check_construction(const TaskConfig& config) {
  // Wired as a run wires it (every port connected, as the constructors see it), never run; the
  // components constructed are destroyed with it.
  detail::Graph graph(config, RunOptions{});
  std::vector<Diagnostic> found;
  for (auto& n : graph.nodes) {
    if (n->spec.kind() != Kind::Filter || n->spec.is_blocking()) continue;
    const std::string who = "component '" + n->config.name + "' (" + n->spec.type_name() + ")";
    try {
      n->construct();
    } catch (const PluginBug& e) {  // the component's code is wrong, not the task file
      found.push_back({n->config.where, who + ": " + escape_controls(e.what())});
    } catch (const ConfigError& e) {
      for (const auto& d : e.diagnostics()) found.push_back(d);
    } catch (const std::exception& e) {
      found.push_back({n->config.where, who + " refused its configuration: " + escape_controls(e.what())});
    } catch (...) {
      found.push_back({n->config.where, who + " threw a non-exception (not derived from std::exception) from its constructor"});
    }
  }
  if (!found.empty()) throw ConfigError(std::move(found));
}

}  // namespace fba
