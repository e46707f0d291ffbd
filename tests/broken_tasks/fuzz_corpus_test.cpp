// The task-loader fuzzer's corpus (tests/fuzz/corpus: the inputs that once crashed or hung it,
// and its seeds) replayed in every build, not only in the clang fuzz build: each input loads or
// is refused with a ConfigError whose every diagnostic says where, as the fuzz target demands.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fba/registry.hpp"
#include "fba/task_config.hpp"
#include "support/build_paths.hpp"
#include "support/built_plugins.hpp"

namespace {

namespace fs = std::filesystem;

// The example components and the examples' composite (relay.yaml), as the fuzz target has them.
using fba::test::built_plugins;

std::vector<std::string> corpus() {
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(fba::test::source_dir() + "/tests/fuzz/corpus"))
    if (e.is_regular_file()) files.push_back(e.path().filename().string());
  std::sort(files.begin(), files.end());
  return files;
}

class FuzzCorpus : public testing::TestWithParam<std::string> {};

TEST_P(FuzzCorpus, LoadsOrIsRefusedWithEveryErrorPlaced) {
  std::ifstream in(fs::path(fba::test::source_dir() + "/tests/fuzz/corpus") / GetParam(), std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  try {
    // Relative to the broken-task corpus, as in the fuzz target, so that includes reach its composites.
    fba::load_task_text(text.str(), "fuzz.yaml", fba::test::source_dir() + "/tests/broken_tasks", built_plugins());
  } catch (const fba::ConfigError& e) {
    for (const auto& d : e.diagnostics()) EXPECT_GT(d.where.line, 0) << d.str();
  }
}

std::string case_name(const testing::TestParamInfo<std::string>& info) {
  std::string n = info.param;
  for (auto& c : n)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return n;
}

INSTANTIATE_TEST_SUITE_P(Corpus, FuzzCorpus, testing::ValuesIn(corpus()), case_name);

}  // namespace
