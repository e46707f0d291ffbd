// fba-run --profile and --check with profiles: the parameters and each slot's interface are
// printed, and the other profiles beside the task are compared with the chosen one.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "support/fba_run.hpp"
#include "support/slotted_task.hpp"

namespace {

using namespace fba::test;

// A task beside three profiles: two interchangeable, one (a composite relay, whose output is of
// any type rather than like its input) different.
fs::path write_task_and_profiles() {
  const fs::path dir = temp_dir("profiles");
  fs::create_directories(dir / "profiles");
  std::ofstream(dir / "task.yaml") << kSlottedTask;
  std::ofstream(dir / "profiles" / "pass.yaml") << kPassProfile;
  std::ofstream(dir / "profiles" / "faulty.yaml") << "components:\n  source: { type: examples.counter, params: { count: \"${n}\" } }\n"
                                                     "  pass: { type: examples.faulty, params: { fail_after: 100 } }\n";
  std::ofstream(dir / "profiles" / "relay.yaml") << "components:\n  source: { type: examples.counter, params: { count: \"${n}\" } }\n"
                                                    "  pass: { type: examples.relay }\n";
  return dir / "task.yaml";
}

}  // namespace

TEST(CliProfiles, CheckPrintsSlotsAndComparesTheOtherProfiles) {
  const auto task = write_task_and_profiles();
  const auto r = fba_run({task.string(), "--check", "--profile", "pass", "--set", "n=5"});
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string dir = task.parent_path().string();
  for (const std::string& line : std::vector<std::string>
       {"parameter n = 5  (int, --set)\n", "profile pass (" + dir + "/profiles/pass.yaml)\n",
        "slot source: examples.counter\n    inputs:  (none)\n    outputs: out (fba.Int)\n    events:  error, finished\n",
        "slot pass: examples.passthrough\n    inputs:  in (any)\n    outputs: out (like input 'in')\n",
        "profile faulty (" + dir + "/profiles/faulty.yaml): the same interfaces in every slot\n",
        "profile relay (" + dir + "/profiles/relay.yaml): 1 difference(s)\n"
        "    slot pass: output 'out': like input 'in' in examples.passthrough, any in examples.relay\n"})
    EXPECT_NE(r.output.find(line), std::string::npos) << line << " in:\n" << r.output;
}

TEST(CliProfiles, RunWritesTheProfileAndParametersIntoTheSummary) {
  const auto task = write_task_and_profiles();
  const fs::path out = temp_dir("out");
  const auto r = fba_run({task.string(), "--profile", "faulty", "--set", "n=4", "-o", out.string()});
  ASSERT_EQ(r.status, 0) << r.output;
  const auto summary = nlohmann::json::parse(read_file(out / "summary.json"));
  EXPECT_EQ(summary["profile"]["name"], "faulty");
  EXPECT_EQ(summary["params"]["n"]["value"], 4);
  EXPECT_EQ(summary["components"]["pass"]["type"], "examples.faulty");
}

TEST(CliProfiles, ASlottedTaskWithoutAProfileSaysWhichExist) {
  const auto task = write_task_and_profiles();
  const std::string out = refusal({task.string(), "--check"});
  EXPECT_NE(out.find("no profile binds them; choose one with --profile NAME or 'profile: NAME' in the task; profiles next to the "
                     "task: faulty, pass, relay"),
            std::string::npos)
      << out;
}
