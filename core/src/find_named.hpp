// The lookup by name of a spec's ports, parameters and events and a task's components and slots.
// Not part of the public API.
#pragma once

#include <string_view>

namespace fba {

// The first element of `items` whose `name` is `name`; nullptr when there is none.
template <class Items>
const typename Items::value_type* find_named(const Items& items, std::string_view name) {
  for (const auto& item : items)
    if (item.name == name) return &item;
  return nullptr;
}

}  // namespace fba
