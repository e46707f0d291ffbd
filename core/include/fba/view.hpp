// What a live view shows of a running task's data (fba-run --serve, report.html): each data type's
// view of one sample, registered by the library that defines the type, and the newest sample of an
// output port handed from its producer's thread to a reader (Task::watch).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "fba/packet.hpp"

namespace fba {

namespace detail {
struct Buffer;
}

// The VIEW object of docs/live-view.md for one sample, as JSON text ("" to show nothing). Called on
// the reader's thread, never on the data path: it may take milliseconds (an image encoded), but
// must not block, and must not throw for any sample of its type.
using ViewFunction = std::string (*)(const Packet&);

// Which samples of a watched output a live view shows. Newest: the newest at each update (a model,
// an image: a newer one says more). Every: each sample, in order (a pose: the camera's poses are
// the views visited, each one of them), up to kEveryViewedLimit between two updates.
enum class ViewedSamples { Newest, Every };
inline constexpr std::size_t kEveryViewedLimit = 256;

// Registered by the library that defines the type, when it is loaded (a static initialiser), so
// the view is there whenever a plugin using the type is. A later registration of the same name
// replaces the earlier one; a null `fn` removes it. Thread-safe.
void register_view(std::string_view type_name, ViewFunction fn, ViewedSamples samples = ViewedSamples::Newest);
// The view registered for the type's name; nullptr when none (or for a null type).
ViewFunction find_view(const TypeInfo* type);
// Which samples the type's view shows (Newest when it has none).
ViewedSamples viewed_samples(const TypeInfo* type);

// The newest sample of one output port, handed from the producer's thread to a reader on another:
// the producer swaps it in under a small lock and is never held back; a reader takes what is there.
// With `keep` > 1, the samples not taken yet, oldest first, at most `keep` of them (beyond, the
// oldest is dropped): for a view that shows every sample (ViewedSamples::Every). Made by
// Task::watch; it may outlive its task (plugins are never unloaded, so a sample kept here stays
// valid).
class LatestSample {
 public:
  LatestSample(std::string port, const TypeInfo* type, std::size_t keep = 1);
  ~LatestSample();
  LatestSample(const LatestSample&) = delete;
  LatestSample& operator=(const LatestSample&) = delete;

  // The newest sample not taken yet (with keep > 1: the oldest not taken yet); nullopt when none
  // came since the last take.
  std::optional<Packet> take();
  // Offers a sample (the runtime does, as the port sends): replaces one not taken yet (with
  // keep > 1: joins them, the oldest dropped when `keep` are waiting).
  void put(Packet p);

  const std::string& port() const { return port_; }  // "component.output"
  // The output's data type as the task resolved it (an "any" output's samples carry their own).
  const TypeInfo* type() const { return type_; }
  std::uint64_t offered() const;     // samples put so far
  std::uint64_t superseded() const;  // of which replaced (or dropped) before anyone took them

  // The runtime's handle: the output delivers into it like into a connection.
  detail::Buffer& buffer() { return *buffer_; }

 private:
  std::string port_;
  const TypeInfo* type_;
  std::unique_ptr<detail::Buffer> buffer_;
};

}  // namespace fba
