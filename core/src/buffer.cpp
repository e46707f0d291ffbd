// The connections' storage (Buffer): a sample pushed by a producer, popped by its consumer, under
// each connection's policy (lossless, drop_oldest, latest) and byte budget. Apart from the nodes
// and the graph because it is the one piece every hop goes through twice, and the one a test
// checks alone (core/tests/data_path_test.cpp).
#include "buffer.hpp"

#include <vector>

namespace fba::detail {

// Inlined: they run twice on every hop.
[[gnu::always_inline]] inline std::size_t Buffer::publish_size() {
  const std::size_t n = policy == BufferPolicy::Latest ? (latest ? 1 : 0) : queue.size();
  // Sequentially consistent for the wake-up protocol (Graph::run_strand) between threads; one
  // thread running every node has no such race, and the fence was a fifth of its hop.
  // (Two stores, not one with a computed order: GCC makes any order not known at compile time
  // sequentially consistent.)
  if (one_thread)
    size.store(n, std::memory_order_relaxed);
  else
    size.store(n, std::memory_order_seq_cst);
  if (max_bytes > 0) bytes.store(queued_bytes, std::memory_order_seq_cst);  // read by full() only
  return n;
}

[[gnu::always_inline]] inline void Buffer::publish_growth() {
  peak.raise_to(publish_size());  // only a push can raise the peaks
  peak_bytes.raise_to(queued_bytes);
}

void Buffer::push(Packet&& p) {
  if (tap || policy == BufferPolicy::DropOldest) return push_displacing(std::move(p));
  BufferLock lock(*this);
  ++pushed;
  const std::size_t b = p.bytes();
  if (policy == BufferPolicy::Latest) {
    // A sample superseded before anyone read it goes back in `p`, which the caller destroys
    // after the lock: no vector allocated on the path of a watched output's every sample.
    if (latest) ++dropped;
    std::swap(latest, p);
    queued_bytes = b;
  } else {
    queue.push_back(std::move(p));
    queued_bytes += b;
  }
  publish_growth();
}

void Buffer::push_displacing(Packet&& p) {
  std::vector<Packet> displaced;  // declared before the lock: destroyed after it is released
  BufferLock lock(*this);
  ++pushed;
  if (tap) {
    if (tap->size() >= tap_keep && !tap->empty()) {
      displaced.push_back(std::move(tap->front()));
      tap->erase(tap->begin());
    }
    if (tap_keep > 0) tap->push_back(std::move(p));
    return;
  }
  const std::size_t b = p.bytes();
  while (!queue.empty() && (queue.size() >= capacity || (max_bytes > 0 && queued_bytes + b > max_bytes))) {
    queued_bytes -= queue.front().bytes();
    displaced.push_back(queue.take_front());
    ++dropped;
  }
  queue.push_back(std::move(p));
  queued_bytes += b;
  publish_growth();
}

// Inlined into pop: a call less on every hop.
[[gnu::always_inline]] inline bool Buffer::take_head(Packet& out, bool& was_full) {
  was_full = false;
  if (policy == BufferPolicy::Latest) {
    if (!latest) return false;
    out = std::move(latest);
    latest = Packet();
  } else {
    if (queue.empty()) return false;
    was_full = full();
    queue.pop_front_into(out);
  }
  queued_bytes -= out.bytes();
  publish_size();
  return true;
}

bool Buffer::pop(Packet& out, bool& was_full) {
  if (one_thread) {  // no lock: the input's previous sample may be freed here, so the sample goes straight in
    if (!take_head(out, was_full)) return false;
    ++consumed;
    return true;
  }
  Packet taken;
  {
    BufferLock lock(*this);
    if (!take_head(taken, was_full)) return false;
    ++consumed;
  }
  out = std::move(taken);  // frees the input's previous sample, outside the lock
  return true;
}

bool Buffer::drop_head(bool& was_full) {
  Packet taken;  // declared before the lock: destroyed after it is released
  BufferLock lock(*this);
  if (!take_head(taken, was_full)) return false;
  ++dropped;
  return true;
}

std::int64_t Buffer::head_stamp() {
  BufferLock lock(*this);
  if (policy == BufferPolicy::Latest) return latest.header().stamp_ns;
  return queue.front().header().stamp_ns;
}

std::size_t Buffer::queued() const {
  // The size published after every change (publish_size), not the queue under the lock: a
  // sampler reading it while the task runs must never make a worker wait for the lock.
  return tap ? 0 : size.load(std::memory_order_relaxed);
}

}  // namespace fba::detail
