// The run's record (see run_record.hpp).
#include "run_record.hpp"

#include <algorithm>

#include <nlohmann/json.hpp>

namespace fba::serve {

bool is_pose_view(const std::string& view_message) {
  // A pose is a few numbers; only a message that small is read to tell.
  if (view_message.size() > 2048) return false;
  const auto j = nlohmann::json::parse(view_message, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return false;
  const auto view = j.find("view");
  return view != j.end() && view->is_object() && view->value("kind", "") == "pose";
}

LiveMessage RunRecord::add(LiveMessage::Kind kind, std::string text, std::string port) {
  const bool pose = kind == LiveMessage::View && is_pose_view(text);
  std::lock_guard lock(mutex_);
  LiveMessage m{kind, std::move(port), std::make_shared<const std::string>(std::move(text)), ++seq_, pose};
  switch (kind) {
    case LiveMessage::Task: task_ = m; break;
    case LiveMessage::Stats: stats_ = m; break;
    case LiveMessage::Event: events_.push_back(m); break;
    case LiveMessage::View:
      if (pose) poses_.push_back(m);
      else views_[m.port] = m;
      break;
    case LiveMessage::End: end_ = m; break;
  }
  return m;
}

RunRecord::Replay RunRecord::replay() const {
  std::lock_guard lock(mutex_);
  Replay r;
  r.up_to = seq_;
  if (task_) r.messages.push_back(*task_);
  if (stats_) r.messages.push_back(*stats_);
  r.messages.insert(r.messages.end(), events_.begin(), events_.end());
  std::vector<LiveMessage> views = poses_;
  for (const auto& [port, m] : views_) views.push_back(m);
  std::sort(views.begin(), views.end(), [](const LiveMessage& a, const LiveMessage& b) { return a.seq < b.seq; });
  r.messages.insert(r.messages.end(), views.begin(), views.end());
  if (end_) r.messages.push_back(*end_);
  return r;
}

}  // namespace fba::serve
