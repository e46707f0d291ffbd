// The plugins built in this tree (fba::test::plugin_dir()), loaded as a user's fba-run would load them.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include <fba/component.hpp>
#include <fba/registry.hpp>
#include "support/build_paths.hpp"

namespace fba::test {

inline Registry load_built_plugins() {
  Registry r;
  for (const auto& e : r.load_path({fba::test::plugin_dir()})) ADD_FAILURE() << e.what();
  return r;
}

inline const Registry& built_plugins() {
  static const Registry registry = load_built_plugins();
  return registry;
}

// The built plugins and the components this test executable registers itself (FBA_COMPONENT),
// these under `origin` in what the registry says of them.
inline Registry built_plugins_and_own(const std::string& origin) {
  Registry r = load_built_plugins();
  r.add_builtin(detail::plugin_entries(), origin);
  return r;
}

}  // namespace fba::test
