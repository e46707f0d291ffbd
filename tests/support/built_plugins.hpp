// The plugins built in this tree, loaded as a user's fba-run would load them. Each test target
// defines FBA_TEST_PLUGIN_DIR (the build's plugin folder).
#pragma once

#include <gtest/gtest.h>

#include <fba/registry.hpp>

namespace fba::test {

inline const Registry& built_plugins() {
  static const Registry registry = [] {
    Registry r;
    for (const auto& e : r.load_path({FBA_TEST_PLUGIN_DIR})) ADD_FAILURE() << e.what();
    return r;
  }();
  return registry;
}

}  // namespace fba::test
