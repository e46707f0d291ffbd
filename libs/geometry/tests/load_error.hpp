// What load_mesh says when it refuses a file: the tests check the message names the file and why.
#pragma once

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "fba/geometry/mesh_io.hpp"

namespace fba::geometry::test {

// The MeshLoadError's message; a file that loads is a test failure.
inline std::string load_error(const std::filesystem::path& p) {
  try {
    load_mesh(p);
  } catch (const MeshLoadError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for " << p;
  return {};
}

}  // namespace fba::geometry::test
