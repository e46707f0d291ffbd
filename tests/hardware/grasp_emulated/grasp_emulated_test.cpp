// tasks/grasp.yaml --profile emulated: the real arm driver (CANopen over SLCAN) and the real hand
// driver (Modbus RTU) run the whole loop against fba-canopen-arm-emulator and
// fba-robotiq-3f-emulator on pseudo-terminals; the camera renders the object from the pose the
// drives report. The same task, with --profile real, drives the devices themselves.
#include <gtest/gtest.h>

#include <fba/registry.hpp>
#include <fba/task.hpp>
#include <string>

#include "support/built_plugins.hpp"
#include "support/child_process.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"

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

}  // namespace
