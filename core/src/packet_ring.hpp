// Runtime internals: the queue of a connection's buffer, a ring of packets. Not part of the public
// API.
#pragma once

#include <cstddef>
#include <memory>
#include <utility>

#include "fba/packet.hpp"

namespace fba::detail {

// A first-in first-out queue of packets in one ring of slots, grown by doubling when full and
// never shrunk. A std::deque allocates and frees a block every few packets as its head and tail
// walk on (a malloc and a free every few hops) and computes its size from four pointers; a ring
// allocates only while a queue first grows, and keeps its size as a count.
class PacketRing {
 public:
  bool empty() const { return count_ == 0; }
  std::size_t size() const { return count_; }
  const Packet& front() const { return slots_[head_]; }  // requires !empty()
  void push_back(Packet&& p) {
    if (count_ == capacity_) grow();
    slots_[(head_ + count_) & (capacity_ - 1)] = std::move(p);
    ++count_;
  }
  // The head, moved into `out` (one move, no temporary: this is half of every hop); its slot is
  // left empty. Requires !empty().
  void pop_front_into(Packet& out) {
    out = std::move(slots_[head_]);
    head_ = (head_ + 1) & (capacity_ - 1);
    --count_;
  }
  Packet take_front() {
    Packet p;
    pop_front_into(p);
    return p;
  }

 private:
  [[gnu::noinline]] void grow() {
    const std::size_t bigger = capacity_ == 0 ? 8 : 2 * capacity_;  // a power of two, for the mask
    auto slots = std::make_unique<Packet[]>(bigger);
    for (std::size_t i = 0; i < count_; ++i) slots[i] = std::move(slots_[(head_ + i) & (capacity_ - 1)]);
    slots_ = std::move(slots);
    capacity_ = bigger;
    head_ = 0;
  }

  std::unique_ptr<Packet[]> slots_;
  std::size_t capacity_ = 0, head_ = 0, count_ = 0;
};

}  // namespace fba::detail
