// Runtime internals: a connection's storage (Buffer), its lock, and the counts it keeps. Not part
// of the public API.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fba/packet.hpp"
#include "fba/task_config.hpp"
#include "packet_ring.hpp"
#include "pi_mutex.hpp"

namespace fba::detail {

class Node;

// A count written by one thread (a node's strand) and read by others while the task runs (the
// live graph dump): a relaxed atomic, so the reads are not data races, at the cost of a plain
// increment.
class Counter {
 public:
  std::uint64_t get() const { return v_.load(std::memory_order_relaxed); }
  operator std::uint64_t() const { return get(); }
  std::uint64_t operator++(int) {  // post-increment: the value before
    const std::uint64_t old = get();
    v_.store(old + 1, std::memory_order_relaxed);
    return old;
  }
  Counter& operator++() { (*this)++; return *this; }
  Counter& operator+=(std::uint64_t d) { v_.store(get() + d, std::memory_order_relaxed); return *this; }
  void raise_to(std::uint64_t v) {  // a running maximum
    if (v > get()) v_.store(v, std::memory_order_relaxed);
  }

 private:
  std::atomic<std::uint64_t> v_{0};
};

// One connection's storage, in front of one input.
//
// The lock is a priority-inheriting mutex, not a spinlock or a plain mutex: under real-time
// priorities a spinning waiter can keep the preempted holder from ever running, and a plain mutex
// lets a medium-priority thread delay a high-priority waiter without bound. Packets leaving the buffer (displaced, dropped, or an
// input's previous sample) are destroyed after it is released: one may be a whole frame.
struct Buffer {
  BufferPolicy policy = BufferPolicy::Lossless;
  std::size_t capacity = 16;
  std::size_t max_bytes = 0;  // payload bytes queued at most; 0 for no byte budget
  bool gating = false;  // a full buffer holds its producer back (lossless connections)
  bool feedback = false;
  // Every push and pop on one thread (the deterministic executor's data connections): no lock,
  // since the snapshots other threads take read only the atomic size and counts.
  bool one_thread = false;
  Node* producer = nullptr;  // null for event deliveries
  Node* consumer = nullptr;  // null for taps
  std::string from, to;      // "component.port", for messages and statistics

  PiMutex mutex;
  PacketRing queue;          // Lossless and DropOldest
  Packet latest;             // Latest
  std::atomic<std::size_t> size{0};   // readable without the lock, for scheduling decisions
  std::size_t queued_bytes = 0;        // payload bytes queued, under the lock
  std::atomic<std::size_t> bytes{0};  // queued_bytes, published for full() when max_bytes > 0
  std::atomic<bool> producer_done{false};
  // Written under the lock, read by snapshots without it. Every sample pushed is consumed, dropped
  // by the policy, or still queued: pushed = consumed + dropped + queued().
  Counter pushed, consumed, dropped;
  Counter peak, peak_bytes;  // the most samples and bytes queued at once
  std::size_t tap_keep = SIZE_MAX;
  std::vector<Packet>* tap = nullptr;  // set for taps: packets are appended, at most tap_keep kept

  // A latest buffer leaves `p` holding the sample it superseded (if any), for the caller to
  // destroy after the lock; every other policy takes `p`.
  void push(Packet&& p);
  // Pops the head; `was_full` tells the caller to wake a producer held back by this buffer.
  bool pop(Packet& out, bool& was_full);
  // Drops the head, counted as dropped (an All trigger's unmatched sample).
  bool drop_head(bool& was_full);
  bool full() const {
    return gating && (size.load(std::memory_order_seq_cst) >= capacity ||
                      (max_bytes > 0 && bytes.load(std::memory_order_seq_cst) >= max_bytes));
  }
  bool empty() const { return size.load(std::memory_order_seq_cst) == 0; }
  // Peeks at the head's stamp (All trigger matching); requires non-empty.
  std::int64_t head_stamp();
  // Samples still queued (at the stop: left unseen). Without the lock.
  std::size_t queued() const;

 private:
  bool take_head(Packet& out, bool& was_full);  // under the lock
  // A tap's or a drop_oldest buffer's push: what it displaces is destroyed after the lock.
  [[gnu::noinline]] void push_displacing(Packet&& p);
  std::size_t publish_size();  // under the lock; returns the size it published
  void publish_growth();  // publish_size and the peaks, after a push; under the lock
};

// A buffer's lock, taken unless one thread does every push and pop (Buffer::one_thread).
class BufferLock {
 public:
  explicit BufferLock(Buffer& b) : b_(b.one_thread ? nullptr : &b) {
    if (b_) b_->mutex.lock();
  }
  ~BufferLock() {
    if (b_) b_->mutex.unlock();
  }
  BufferLock(const BufferLock&) = delete;
  BufferLock& operator=(const BufferLock&) = delete;

 private:
  Buffer* b_;
};

}  // namespace fba::detail
