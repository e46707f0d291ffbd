// What a live view shows of a running task's data (fba-run --serve, report.html): each data type's
// view of one sample, registered by the library that defines the type, and the newest sample of an
// output port handed from its producer's thread to a reader (Task::watch).
#pragma once

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

// Registered by the library that defines the type, when it is loaded (a static initialiser), so
// the view is there whenever a plugin using the type is. A later registration of the same name
// replaces the earlier one; a null `fn` removes it. Thread-safe.
void register_view(std::string_view type_name, ViewFunction fn);
// The view registered for the type's name; nullptr when none (or for a null type).
ViewFunction find_view(const TypeInfo* type);

// The newest sample of one output port, handed from the producer's thread to a reader on another:
// the producer swaps it in under a small lock and is never held back; a reader takes what is there.
// Made by Task::watch; it may outlive its task (plugins are never unloaded, so a sample kept here
// stays valid).
class LatestSample {
 public:
  LatestSample(std::string port, const TypeInfo* type);
  ~LatestSample();
  LatestSample(const LatestSample&) = delete;
  LatestSample& operator=(const LatestSample&) = delete;

  // The newest sample not taken yet; nullopt when none came since the last take.
  std::optional<Packet> take();
  // Offers a sample (the runtime does, as the port sends): replaces one not taken yet.
  void put(Packet p);

  const std::string& port() const { return port_; }  // "component.output"
  // The output's data type as the task resolved it (an "any" output's samples carry their own).
  const TypeInfo* type() const { return type_; }
  std::uint64_t offered() const;     // samples put so far
  std::uint64_t superseded() const;  // of which replaced before anyone took them

  // The runtime's handle: the output delivers into it like into a connection.
  detail::Buffer& buffer() { return *buffer_; }

 private:
  std::string port_;
  const TypeInfo* type_;
  std::unique_ptr<detail::Buffer> buffer_;
};

}  // namespace fba
