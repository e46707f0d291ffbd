// A temporary folder of its own for each test: created unique (mkdtemp) under GoogleTest's temporary
// directory, named after the running test so a leftover is easy to trace, and removed with what it
// holds when the object goes out of scope. Tests that run in parallel, in several builds at once, or
// several times in one process never share a file.
#pragma once

#include <stdlib.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include <gtest/gtest.h>

namespace fba::test {

class TempDir {
 public:
  // `what`, if given, ends the name: what the folder is for, when a test has several.
  explicit TempDir(const std::string& what = {}) {
    std::string name = "fba";
    if (const auto* info = ::testing::UnitTest::GetInstance()->current_test_info())
      name += std::string("-") + info->test_suite_name() + "-" + info->name();
    if (!what.empty()) name += "-" + what;
    for (char& c : name)  // parameterised tests have '/' in their names
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
    std::string pattern = (std::filesystem::path(::testing::TempDir()) / (name + "-XXXXXX")).string();
    if (!::mkdtemp(pattern.data()))
      throw std::runtime_error("cannot create a temporary folder " + pattern + ": " + std::strerror(errno));
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // A new folder that lives until the test process ends, for helpers that hand out paths rather
  // than objects (each test runs in a process of its own under ctest, so nothing piles up).
  static const std::filesystem::path& until_exit(const std::string& what = {}) {
    static std::vector<std::unique_ptr<TempDir>> kept;
    kept.push_back(std::make_unique<TempDir>(what));
    return kept.back()->path();
  }
  // Writes `text` to `name` inside the folder, making the folders on its way; returns its path.
  std::filesystem::path write(const std::string& name, const std::string& text) const {
    std::filesystem::create_directories((path_ / name).parent_path());
    std::ofstream(path_ / name, std::ios::binary) << text;
    return path_ / name;
  }
  // The path of `name` inside the folder, as a string; with `text`, the file is written first.
  std::string file(const std::string& name, const std::string& text = {}) const {
    const std::string p = (path_ / name).string();
    if (!text.empty() && !(std::ofstream(p) << text))
      throw std::runtime_error("cannot write the temporary file " + p);
    return p;
  }

 private:
  std::filesystem::path path_;
};

}  // namespace fba::test
