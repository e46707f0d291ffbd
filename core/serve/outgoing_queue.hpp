// What the live view's server has yet to send one page: bounded by dropping the oldest stats and
// view messages (a newer one says more), never the task, an event, a pose (each is a view visited)
// or the end, which a page needs whole. A page too slow even for those is cut off rather than let
// the queue grow without bound.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

#include "run_record.hpp"

namespace fba::serve {

class OutgoingQueue {
 public:
  // `limit`: messages queued before old stats and views are dropped; `hard_limit`: before the page
  // is given up on.
  OutgoingQueue(std::size_t limit, std::size_t hard_limit) : limit_(limit), hard_limit_(hard_limit) {}

  // Queues a message; false when the page must be cut off. `front_in_flight`: the first message is
  // being written, and stays.
  bool push(const LiveMessage& m, bool front_in_flight) {
    if (queue_.size() >= limit_) drop_one(front_in_flight);
    if (queue_.size() >= hard_limit_) return false;
    queue_.push_back(m);
    return true;
  }
  // What a page connecting late is sent first, whatever its length.
  void assign(const std::vector<LiveMessage>& messages) { queue_.assign(messages.begin(), messages.end()); }

  bool empty() const { return queue_.empty(); }
  std::size_t size() const { return queue_.size(); }
  const LiveMessage& front() const { return queue_.front(); }
  void pop() { queue_.pop_front(); }
  std::uint64_t dropped() const { return dropped_; }

 private:
  void drop_one(bool front_in_flight) {
    for (auto it = queue_.begin() + (front_in_flight && !queue_.empty() ? 1 : 0); it != queue_.end(); ++it)
      if (it->kind == LiveMessage::Stats || (it->kind == LiveMessage::View && !it->pose)) {
        queue_.erase(it);
        ++dropped_;
        return;
      }
  }

  std::deque<LiveMessage> queue_;
  std::size_t limit_, hard_limit_;
  std::uint64_t dropped_ = 0;
};

}  // namespace fba::serve
