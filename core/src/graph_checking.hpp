// Graph checking, the loader's last stage: the whole task once every component, connection and
// event rule is read and composites are flattened: an input takes one connection (or one kind of
// event delivery, of fba.Event), every required input is connected, every cycle has a connection
// marked as its back edge, and each connection's data type matches its input, outputs typed like
// an input resolved along the graph. Free of YAML: it works on the TaskConfig alone, so a test
// checks a graph without writing a task file. The checks made as each connection, trigger and rule
// is read (its ports and events exist, its settings are valid) are here too, as Loader members.
#pragma once

#include <optional>
#include <vector>

#include "fba/task_config.hpp"

namespace fba::loader {

// Every problem of the whole graph, in the order found; fills in each connection's and each
// output's resolved type. `require_inputs`: false for the component harness, which feeds inputs
// itself.
std::vector<Diagnostic> check_graph(TaskConfig& task, bool require_inputs);

// More components with a thread of their own than kMaxDedicatedThreads: said at the first beyond.
std::optional<Diagnostic> check_thread_limit(const TaskConfig& task);

}  // namespace fba::loader
