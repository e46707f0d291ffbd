// The plugins built in this tree (fba::test::plugin_dir()), loaded as a user's fba-run would load them.
#pragma once

#include <gtest/gtest.h>

#include <fba/registry.hpp>
#include "support/build_paths.hpp"

namespace fba::test {

inline const Registry& built_plugins() {
  static const Registry registry = [] {
    Registry r;
    for (const auto& e : r.load_path({fba::test::plugin_dir()})) ADD_FAILURE() << e.what();
    return r;
  }();
  return registry;
}

}  // namespace fba::test
