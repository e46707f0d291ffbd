// What the live view has said about a run so far, kept for a page that connects late and for
// report.html: the task, the last stats, every event, the newest view of each port and every pose
// view, and the end. Written by one thread (the sampler), read by the server's.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace fba::serve {

struct LiveMessage {
  enum Kind { Task, Stats, Event, View, End };
  Kind kind = Stats;
  std::string port;  // View: "component.output"
  std::shared_ptr<const std::string> text;
  std::uint64_t seq = 0;  // its place among every message added, from 1
  bool pose = false;      // View: a pose, every one of which is kept (the views visited)
};

class RunRecord {
 public:
  // Adds a message and returns it numbered. A view whose VIEW is a pose is kept with every other
  // pose of its port (the views visited); any other view replaces its port's previous one.
  LiveMessage add(LiveMessage::Kind kind, std::string text, std::string port = {});

  struct Replay {
    std::vector<LiveMessage> messages;  // task, last stats, events, views, end
    std::uint64_t up_to = 0;            // the last seq they include
  };
  // What a page is sent first, and what report.html holds.
  Replay replay() const;

 private:
  mutable std::mutex mutex_;
  std::uint64_t seq_ = 0;
  std::optional<LiveMessage> task_, stats_, end_;
  std::vector<LiveMessage> events_;
  std::map<std::string, LiveMessage> views_;               // newest per port, not poses
  std::vector<LiveMessage> poses_;                          // every pose view, in order
};

// Whether a VIEW's JSON text is a pose ({"kind":"pose", ...}).
bool is_pose_view(const std::string& view_message);

}  // namespace fba::serve
