// What a run says to its live view and report: the task when it is loaded, then at each sample the
// stats, the events new since the last one and the newest view of each output that has one, and
// the end. Each message goes into the run's record (report.html, late pages) and to the server.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "fba/task.hpp"
#include "fba/view.hpp"
#include "live_server.hpp"
#include "run_record.hpp"

namespace fba::serve {

class LiveFeed {
 public:
  // Adds the task message.
  LiveFeed(RunRecord& record, const TaskConfig& task, const std::string& run_id);

  // Each message from now on also goes to `server` (null: none).
  void publish_to(LiveServer* server) { server_ = server; }

  // Watches every output whose data type has a view (Task::watch): its newest sample, or every
  // sample for a view that shows each (ViewedSamples::Every). Before task.run().
  void watch(Task& task, const TaskConfig& config);

  // One sample of the running task (a Monitor's watcher, on its thread): stats, new events, the
  // views of what each watched port sent since the last sample.
  void sample(const RunResult& now, const RunResult* previous);

  // The run is over (its last sample given): the end message, with summary.json's text.
  void end(const RunResult& result, const std::string& summary);
  // An end message made elsewhere: a run that ended before its task ran.
  void end_with(std::string end_message) { publish(LiveMessage::End, std::move(end_message)); }

  // The ports watched, "component.output", in the task's order.
  std::vector<std::string> watched() const;

 private:
  void publish(LiveMessage::Kind kind, std::string text, std::string port = {});

  struct Watched {
    std::string port;
    std::shared_ptr<LatestSample> latest;
  };
  RunRecord& record_;
  LiveServer* server_ = nullptr;
  std::vector<Watched> watched_;
  std::size_t events_said_ = 0;
};

}  // namespace fba::serve
