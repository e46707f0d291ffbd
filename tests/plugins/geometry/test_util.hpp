// Helpers shared by the geometry tests.
#pragma once

#include <atomic>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace fba::geometry::test {

inline std::filesystem::path shared_data() { return FBA_SHARED_DATA_DIR; }

inline std::filesystem::path ycb_mesh(const std::string& name) {
  return shared_data() / "ycb" / name / "model.obj";
}

inline const char* const kYcbNames[] = {"YcbMustardBottle", "YcbMasterChefCan", "YcbBanana",
                                        "YcbCrackerBox"};

// A fresh directory under the system temp dir, removed on destruction.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("fba-geometry-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace fba::geometry::test
