// Helpers shared by the geometry tests.
#pragma once

#include <filesystem>
#include <string>

#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"

namespace fba::geometry::test {

inline std::filesystem::path data() { return fba::test::data_dir(); }

inline std::filesystem::path ycb_mesh(const std::string& name) {
  return data() / "ycb" / name / "model.obj";
}

inline const char* const kYcbNames[] = {"YcbMustardBottle", "YcbMasterChefCan", "YcbBanana",
                                        "YcbCrackerBox"};

using fba::test::TempDir;

}  // namespace fba::geometry::test
