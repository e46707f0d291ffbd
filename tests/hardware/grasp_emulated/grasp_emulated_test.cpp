// tasks/grasp.yaml --profile emulated: the real arm driver (CANopen over SLCAN) and the real hand
// driver (Modbus RTU) run the whole loop against fba-canopen-arm-emulator and
// fba-robotiq-3f-emulator on pseudo-terminals; the camera renders the object from the pose the
// drives report. The same task, with --profile real, drives the devices themselves.
#include <gtest/gtest.h>

#include <signal.h>

#include <fba/registry.hpp>
#include <fba/task.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "support/built_plugins.hpp"
#include "support/child_process.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"
#include "tasks/fba_run_process.hpp"

namespace {

using fba::test::Child;

TEST(GraspEmulated, TheRealDriversRunTheLoopAgainstTheEmulatorsToAHeldObject) {
  const fba::test::TempDir temp;
  const std::string arm_link = (temp.path() / "arm").string(), hand_link = (temp.path() / "hand").string();
  Child arm({fba::test::program("fba-canopen-arm-emulator"), "--link", arm_link});
  ASSERT_NE(arm.read_until("(link " + arm_link + ")").find("SLCAN adapter on"), std::string::npos) << arm.read_until("");
  // The mustard bottle (58 x 95 x 190 mm) the camera renders: held across its depth, B and C may
  // spread along its height.
  Child hand({fba::test::program("fba-robotiq-3f-emulator"), "--link", hand_link, "--activation-s", "0.05", "--object-width", "0.07",
              "--object-length", "0.19"});
  ASSERT_NE(hand.read_until("(link " + hand_link + ")").find("Modbus RTU slave 9"), std::string::npos);

  fba::LoadOptions load;
  load.profile = "emulated";
  load.overrides.push_back({"arm_bus=slcan:" + arm_link});
  load.overrides.push_back({"hand_device=" + hand_link});
  fba::RunOptions options;
  options.timeout_s = 600;  // a hang detector only: the run takes seconds of emulated motion
  fba::Task task(fba::load_task(fba::test::tasks_dir() + "/grasp.yaml", fba::test::built_plugins(), load), options);
  const auto r = task.run();
  ASSERT_TRUE(r.final_event) << r.reason;
  EXPECT_EQ(r.final_event->source, "hand") << r.reason;
  EXPECT_EQ(r.final_event->name, "held") << r.final_event->payload;
  std::size_t arrivals = 0;
  bool selected = false;
  for (const auto& e : r.events) {
    arrivals += e.source == "arm" && e.name == "arrived";
    selected = selected || (e.source == "synthesis" && e.name == "grasp_selected");
  }
  EXPECT_GE(arrivals, 3u);  // the drives reached the initial views
  EXPECT_TRUE(selected);
  // Both drivers were told to go safe at the stop, and said so.
  for (const char* device : {"arm", "hand"}) {
    bool safe = false;
    for (const auto& s : r.safe_states) safe = safe || (s.component == device && s.status == "reached");
    EXPECT_TRUE(safe) << device;
  }
}

// Ctrl-C while the hand activates (its emulator never finishes activating): the activation gives
// up at once rather than at activation_timeout, the arm constructed before it goes to its safe
// state, and fba-run exits 130 with the summary saying where the run stopped.
TEST(GraspEmulated, CtrlCWhileTheHandActivatesStopsAtOnceWithTheSafeStatesInTheSummary) {
  const fba::test::TempDir temp;
  const std::string arm_link = (temp.path() / "arm").string(), hand_link = (temp.path() / "hand").string();
  Child arm({fba::test::program("fba-canopen-arm-emulator"), "--link", arm_link});
  ASSERT_NE(arm.read_until("(link " + arm_link + ")").find("SLCAN adapter on"), std::string::npos) << arm.read_until("");
  Child hand({fba::test::program("fba-robotiq-3f-emulator"), "--link", hand_link, "--never-activate"});
  ASSERT_NE(hand.read_until("(link " + hand_link + ")").find("Modbus RTU slave 9"), std::string::npos);

  const auto out = temp.path() / "out";
  fba::test::Process run({fba::test::tasks_dir() + "/grasp.yaml", "--profile", "emulated", "--set",
                          "arm_bus=slcan:" + arm_link, "--set", "hand_device=" + hand_link, "--output-dir",
                          out.string()});
  ASSERT_TRUE(run.wait_for_output(": activating (")) << run.output();
  run.signal(SIGINT);
  const auto r = run.wait();
  EXPECT_EQ(r.status, 130) << r.output;
  EXPECT_NE(r.output.find("activation: interrupted (the task is stopping)"), std::string::npos) << r.output;
  const auto summary = nlohmann::json::parse(fba::test::read_file(out / "summary.json"), nullptr, false);
  ASSERT_TRUE(summary.is_object()) << r.output;
  EXPECT_EQ(summary.value("phase", ""), "constructing") << summary.dump(2);
  EXPECT_GT(summary.value("wall_time_s", 0.0), 0) << summary.dump(2);
  const auto& safe = summary["safe_states"];
  EXPECT_EQ(safe["hand"]["status"], "not constructed") << summary.dump(2);
  EXPECT_EQ(safe["arm"]["status"], "reached") << summary.dump(2);  // constructed before the hand
}

}  // namespace
