// io.recorder: what a run carried, one JSON line per sample or event, readable back.
#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include <fba/task.hpp>
#include <fba/testing.hpp>

#include "support/built_plugins.hpp"
#include "support/temp_dir.hpp"

namespace {

struct Opaque {
  double x[4];
};

std::vector<nlohmann::json> read_lines(const std::filesystem::path& file) {
  std::vector<nlohmann::json> lines;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

}  // namespace

FBA_DATA_TYPE(Opaque, "test.Opaque", "Four doubles the recorder knows nothing about.");

TEST(Recorder, WritesScalarsAndEventsWithTheirValuesAndOtherTypesByName) {
  fba::test::TempDir dir;
  const auto file = dir.path() / "r.jsonl";
  fba::testing::ComponentHarness h(fba::test::built_plugins(), "io.recorder", {{"file", file.string()}});
  h.push<std::int64_t>("in", 42, 1'000'000'000);
  h.push<double>("in", 0.5, 2'000'000'000);
  h.push<std::string>("in", "say \"hi\"", 3'000'000'000);
  h.push<fba::Event>("in", fba::Event{"carver", "updated", "{\"views\": 3}", 4'000'000'000}, 4'000'000'000);
  h.push<Opaque>("in", Opaque{}, 5'000'000'000);
  EXPECT_EQ(h.run(), 5);
  const auto lines = read_lines(file);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0]["type"], "fba.Int");
  EXPECT_EQ(lines[0]["value"], 42);
  EXPECT_DOUBLE_EQ(lines[0]["t"].get<double>(), 1.0);
  EXPECT_EQ(lines[1]["value"], 0.5);
  EXPECT_EQ(lines[2]["value"], "say \"hi\"");
  EXPECT_EQ(lines[3]["type"], "fba.Event");
  EXPECT_EQ(lines[3]["value"]["source"], "carver");
  EXPECT_EQ(lines[3]["value"]["name"], "updated");
  EXPECT_EQ(lines[3]["value"]["payload"], "{\"views\": 3}");
  EXPECT_EQ(lines[4]["type"], "test.Opaque");
  EXPECT_FALSE(lines[4].contains("value"));
  EXPECT_EQ(lines[4]["bytes"], sizeof(Opaque));
  EXPECT_EQ(lines[4]["seq"], 4);
}

TEST(Recorder, ARelativeFileGoesInTheOutputFolderAndNeedsOne) {
  fba::test::TempDir dir;
  const char* task = R"(
components:
  src: { type: examples.counter, params: { count: 3, start: 5 } }
  rec: { type: io.recorder, params: { file: ints.jsonl } }
connections:
  - src.out -> rec.in
)";
  fba::RunOptions options;
  options.output_dir = dir.path();
  fba::Task run(fba::load_task_text(task, "rec.yaml", dir.path(), fba::test::built_plugins()), options);
  EXPECT_EQ(run.run().outcome, fba::Outcome::Success);
  const auto lines = read_lines(dir.path() / "ints.jsonl");
  ASSERT_EQ(lines.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(lines[i]["value"], 5 + i);
    EXPECT_EQ(lines[i]["producer"], "src.out");
    EXPECT_EQ(lines[i]["seq"], i);
  }
  try {
    fba::Task no_output(fba::load_task_text(task, "rec.yaml", dir.path(), fba::test::built_plugins()));
    FAIL() << "a relative file without --output-dir was accepted";
  } catch (const fba::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--output-dir"), std::string::npos) << e.what();
  }
}

TEST(Recorder, AFileThatCannotBeWrittenIsRefusedAtConstruction) {
  fba::test::TempDir dir;
  try {
    fba::testing::ComponentHarness h(fba::test::built_plugins(), "io.recorder",
                                     {{"file", (dir.path() / "no_such_folder" / "r.jsonl").string()}});
    FAIL() << "an unwritable file was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("cannot write"), std::string::npos) << e.what();
  }
}
