// The live feed (see live_feed.hpp).
#include "live_feed.hpp"

#include <iostream>

#include "live_messages.hpp"

namespace fba::serve {

LiveFeed::LiveFeed(RunRecord& record, const TaskConfig& task, const std::string& run_id) : record_(record) {
  publish(LiveMessage::Task, task_message(task, run_id));
}

void LiveFeed::watch(Task& task, const TaskConfig& config) {
  for (const auto& c : config.components)
    for (const auto& [output, type] : c.output_types)
      if (find_view(type)) {
        const std::string port = c.name + "." + output;
        // A type whose every sample is shown (the poses visited) is kept sample by sample until
        // taken, not only its newest: poses arrive faster than the updates at times (a burst of
        // view targets, the camera at each view).
        const std::size_t keep = viewed_samples(type) == ViewedSamples::Every ? kEveryViewedLimit : 1;
        watched_.push_back({port, task.watch(port, keep)});
      }
}

std::vector<std::string> LiveFeed::watched() const {
  std::vector<std::string> ports;
  for (const auto& w : watched_) ports.push_back(w.port);
  return ports;
}

void LiveFeed::sample(const RunResult& now, const RunResult* previous) {
  publish(LiveMessage::Stats, stats_message(now, previous));
  for (; events_said_ < now.events.size(); ++events_said_)
    publish(LiveMessage::Event, event_message(events_said_, now.events[events_said_]));
  // Each port's samples not taken yet: its newest, or every one in order for a type whose every
  // sample is shown.
  for (const auto& w : watched_)
    while (const std::optional<Packet> p = w.latest->take()) {
      if (!*p) continue;
      const ViewFunction view = find_view(p->type());
      if (!view) continue;
      std::string text;
      try {
        text = view(*p);
      } catch (const std::exception& e) {  // a view must not throw; if one does, the run goes on without it
        std::cerr << "fba-run: live view: the view of " << p->type()->name << " on " << w.port << " failed: " << e.what() << "\n";
        continue;
      }
      if (!text.empty()) publish(LiveMessage::View, view_message(w.port, p->type()->name, p->header(), text), w.port);
    }
}

void LiveFeed::end(const RunResult& result, const std::string& summary) {
  publish(LiveMessage::End, end_message(result, summary));
}

void LiveFeed::publish(LiveMessage::Kind kind, std::string text, std::string port) {
  const LiveMessage m = record_.add(kind, std::move(text), std::move(port));
  if (server_) server_->publish(m);
}

}  // namespace fba::serve
