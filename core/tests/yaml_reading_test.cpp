// Guarded YAML reading (core/src/yaml_reading.cpp): a task file that is not a regular file of at
// most 4 MiB, not one YAML document, or malformed is refused at its place before anything else is
// read; through the loader, and the stage called directly.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <string>
#include <vector>

#include <fba/task_config.hpp>

#include "support/temp_dir.hpp"
#include "fixture_components.hpp"
#include "yaml_reading.hpp"

namespace {
namespace fs = std::filesystem;
}  // namespace

using fba::test::errors_of;
using fba::test::errors_of_file;
using fba::test::load;
using fba::test::TempDir;

// An alias is its anchor's node, tags and both styles are read, and a value's error names the line
// and column it was written at, also through an alias.
TEST(Loader, AnchorsTagsAndPlacesAreKeptThroughAliases) {
  const auto task = load(R"(
components:
  a: { type: examples.counter, params: &five { count: !!int 5 } }
  b:
    type: examples.counter
    params: *five
  sink: { type: examples.sink }
connections: [ a.out -> sink.in ]
)");
  EXPECT_EQ(std::get<std::int64_t>(task.find("b")->params.at("count")), 5);
  const auto e = errors_of(R"(
components:
  a: { type: examples.counter, params: &bad { count: -1 } }
  b:
    type: examples.counter
    params: *bad
)");
  EXPECT_NE(e.find("test.yaml:3:54: error: parameter 'count' must be in"), std::string::npos) << e;
  EXPECT_EQ(e.find("test.yaml:6:"), std::string::npos) << e;
}

TEST(Loader, YamlSyntaxErrorsPointAtTheirPlace) {
  const auto e = errors_of("components:\n  a: { type: examples.counter\n");
  EXPECT_NE(e.find("test.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("YAML syntax"), std::string::npos) << e;
}

TEST(Loader, ATaskFileMustBeARegularFileAndSaysWhatItIsInstead) {
  TempDir dir;
  EXPECT_NE(errors_of_file(dir.path()).find("the task file is a directory; expected a regular file"), std::string::npos);
  EXPECT_NE(errors_of_file("/dev/zero").find("/dev/zero: error: the task file is a character device"), std::string::npos);
  const fs::path fifo = dir.path() / "task.fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // Opening a FIFO for reading would wait for a writer forever: the check comes first.
  EXPECT_NE(errors_of_file(fifo).find("the task file is a FIFO (a pipe)"), std::string::npos);
  EXPECT_NE(errors_of_file(dir.path() / "missing.yaml").find("the task file does not exist"), std::string::npos);
}

TEST(Loader, ATaskFileOverFourMebibytesIsRefusedBeforeItIsRead) {
  TempDir dir;
  const fs::path big = dir.write("big.yaml", "components:\n");
  fs::resize_file(big, (4u << 20) + 1);  // sparse: no disk or memory spent
  EXPECT_NE(errors_of_file(big).find("is 4194305 bytes; task and composite files are limited to 4 MiB (4194304 bytes)"), std::string::npos);
}

TEST(Loader, AnIncludedFifoOrDeviceSaysWhatItIs) {
  TempDir dir;
  ASSERT_EQ(mkfifo((dir.path() / "c.fifo").c_str(), 0600), 0);
  const auto task = dir.write("t.yaml", "include: [c.fifo, /dev/zero]\ncomponents:\n  a: { type: examples.counter }\n");
  const std::string e = errors_of_file(task);
  EXPECT_NE(e.find("t.yaml:1:11: error: included file 'c.fifo' is a FIFO (a pipe)"), std::string::npos) << e;
  EXPECT_NE(e.find("t.yaml:1:19: error: included file '/dev/zero' is a character device"), std::string::npos) << e;
}

// The stage alone: text in, one document or every reason with its place out.
TEST(YamlReading, OneDocumentOrTheReasonsWithTheirPlaces) {
  std::vector<fba::Diagnostic> d;
  EXPECT_TRUE(fba::loader::parse_yaml("a: 1\nb: [2, 3]\n", "t.yaml", d));
  EXPECT_TRUE(d.empty());
  EXPECT_FALSE(fba::loader::parse_yaml("a: 1\n---\nb: 2\n", "t.yaml", d));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "t.yaml:2:1: error: a second YAML document ('---') in one file; a task or composite file is one document");
  d.clear();
  EXPECT_FALSE(fba::loader::parse_yaml("[a]\n, b\n", "t.yaml", d));  // yaml-cpp 0.7 would never return
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "t.yaml:2:1: error: YAML syntax: ',' separates the entries of a flow list or mapping ([a, b] or {a: 1, b: 2}); "
                        "here it stands outside one");
  d.clear();
  EXPECT_FALSE(fba::loader::parse_yaml("a: " + std::string(65, '[') + std::string(65, ']') + "\n", "t.yaml", d));
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].str(), "t.yaml:1:68: error: nesting deeper than 64 levels");
}

TEST(YamlReading, DuplicateAndMergeKeysAreFoundInEveryMapping) {
  std::vector<fba::Diagnostic> d;
  const auto doc = fba::loader::parse_yaml("a: 1\nb: {x: 1, x: 2}\nc: &m {y: 1}\nd: {<<: *m}\n", "t.yaml", d);
  ASSERT_TRUE(doc);
  fba::loader::check_mappings(*doc, fba::loader::Source{"t.yaml", "."}, d);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].str(), "t.yaml:2:11: error: key 'x' is given twice in one mapping (first at line 2, column 5); a key can appear once");
  EXPECT_EQ(d[1].str(), "t.yaml:4:5: error: YAML merge keys ('<<') are not supported; write the keys out");
}
