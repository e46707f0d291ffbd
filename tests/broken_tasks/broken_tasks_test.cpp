// Runs `fba-run --check` on every broken task file in this folder and on every example task.
// A broken file starts with comment lines that say what the check must report:
//   # expect-file: includes/x.yaml   (optional: the error is in this file, not the broken one)
//   # expect-line: N                 (the line the message points to)
//   # expect: text                   (a substring of the message)
//   # why: the mistake it plays
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>
#include "support/build_paths.hpp"
#include "support/child_process.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path kBrokenDir = fba::test::source_dir() + "/tests/broken_tasks";
const fs::path kExampleDir = fba::test::tasks_dir() + "/examples";

// fba-run --check FILE, with stderr apart (its stdout is not looked at).
fba::test::Result check(const fs::path& file) {
  return fba::test::run({fba::test::program("fba-run"), "--check", file.string()}, {.stderr_apart = true});
}

std::vector<fs::path> yaml_files(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && e.path().extension() == ".yaml") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

// A test name from a file name: gtest allows only letters, digits and '_'.
std::string case_name(const testing::TestParamInfo<fs::path>& info) {
  std::string s = info.param.stem().string();
  std::replace_if(s.begin(), s.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); }, '_');
  return s;
}

struct Expectation {
  fs::path file;
  int line = 0;
  std::string text, why;
};

Expectation read_header(const fs::path& broken) {
  Expectation x;
  x.file = broken;
  std::ifstream in(broken);
  const auto value = [](const std::string& l, const std::string& key) { return l.rfind(key, 0) == 0 ? l.substr(key.size()) : ""; };
  for (std::string l; std::getline(in, l) && l.rfind('#', 0) == 0;) {
    if (auto v = value(l, "# expect-file: "); !v.empty()) x.file = (broken.parent_path() / v).lexically_normal();
    if (auto v = value(l, "# expect-line: "); !v.empty()) x.line = std::stoi(v);
    if (auto v = value(l, "# expect: "); !v.empty()) x.text = v;
    if (auto v = value(l, "# why: "); !v.empty()) x.why = v;
  }
  return x;
}

class BrokenTask : public testing::TestWithParam<fs::path> {};

TEST_P(BrokenTask, FailsTheCheckAtTheExpectedLine) {
  const Expectation x = read_header(GetParam());
  ASSERT_GT(x.line, 0) << "header needs '# expect-line: N'";
  ASSERT_FALSE(x.text.empty()) << "header needs '# expect: text'";
  ASSERT_FALSE(x.why.empty()) << "header needs '# why: ...'";
  const auto run = check(GetParam());
  ASSERT_EQ(run.signal, 0) << "fba-run died of signal " << run.signal << "\n" << run.err;
  EXPECT_EQ(run.status, 2) << run.err;
  const std::string place = x.file.string() + ":" + std::to_string(x.line) + ":";
  EXPECT_NE(run.err.find(place), std::string::npos) << "expected an error at " << place << "\n" << run.err;
  EXPECT_NE(run.err.find(x.text), std::string::npos) << "expected '" << x.text << "'\n" << run.err;
}

INSTANTIATE_TEST_SUITE_P(Corpus, BrokenTask, testing::ValuesIn(yaml_files(kBrokenDir)), case_name);

TEST(BrokenTaskCorpus, HasAtLeast40Cases) { EXPECT_GE(yaml_files(kBrokenDir).size(), 40u); }

class ExampleTask : public testing::TestWithParam<fs::path> {};

TEST_P(ExampleTask, PassesTheCheck) {
  const auto run = check(GetParam());
  ASSERT_EQ(run.signal, 0) << run.err;
  EXPECT_EQ(run.status, 0) << run.err;
}

// The task files only; composites/ holds what they include.
INSTANTIATE_TEST_SUITE_P(Examples, ExampleTask, testing::ValuesIn(yaml_files(kExampleDir)), case_name);

}  // namespace
