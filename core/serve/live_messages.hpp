// The messages of the live view (docs/live-view.md, "Messages"), as JSON text: what the server
// sends a page and what report.html replays.
#pragma once

#include <cstddef>
#include <string>

#include "fba/task.hpp"

namespace fba::serve {

// {"type":"task"}: the graph as loaded, with each port's type and each component's doc.
std::string task_message(const TaskConfig& task, const std::string& run_id);

// {"type":"stats"}: counts as they stand, rates since `previous` (since the start without one).
std::string stats_message(const RunResult& now, const RunResult* previous);

// {"type":"event"}: the event at `index` of the run's events. A payload that is JSON goes in as
// JSON, any other text as a string.
std::string event_message(std::size_t index, const Event& event);

// {"type":"view"}: `view` is the VIEW object's JSON text, put in as it is.
std::string view_message(const std::string& port, const std::string& data_type, const Header& header, const std::string& view);

// {"type":"end"}: the outcome and summary.json's text (`summary`, put in as it is).
std::string end_message(const RunResult& result, const std::string& summary);

}  // namespace fba::serve
