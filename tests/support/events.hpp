// The events a component emitted (ComponentHarness::events()), looked up by name.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <fba/packet.hpp>

namespace fba::test {

// The first event called `name`; nullopt when there is none.
inline std::optional<Event> find_event(const std::vector<Event>& events, const std::string& name) {
  for (const auto& e : events)
    if (e.name == name) return e;
  return std::nullopt;
}

inline bool has_event(const std::vector<Event>& events, const std::string& name) {
  return find_event(events, name).has_value();
}

// Every event called `name`, in order.
inline std::vector<Event> named(const std::vector<Event>& events, const std::string& name) {
  std::vector<Event> out;
  for (const auto& e : events)
    if (e.name == name) out.push_back(e);
  return out;
}

}  // namespace fba::test
