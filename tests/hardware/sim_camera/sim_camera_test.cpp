// sim.camera against its twin vision.camera: one interface, so a profile can swap them; and the
// parameter that names the object's world.
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include <fba/testing.hpp>

#include "support/built_plugins.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"

namespace {

using fba::testing::ComponentHarness;

using fba::test::kCan;

std::vector<std::tuple<std::string, std::string, bool>> ports(const std::vector<fba::PortSpec>& list) {
  std::vector<std::tuple<std::string, std::string, bool>> out;
  for (const auto& p : list) out.emplace_back(p.name, p.type->name, p.required);
  return out;
}

std::vector<std::string> events(const fba::Spec& s) {
  std::vector<std::string> out;
  for (const auto& e : s.events()) out.push_back(e.name);
  return out;
}

}  // namespace

TEST(SimCameraSpec, PortsAndEventsAreVisionCameras) {
  const auto sim = fba::test::built_plugins().find("sim.camera");
  const auto real = fba::test::built_plugins().find("vision.camera");
  ASSERT_TRUE(sim && real);
  EXPECT_EQ(sim->spec.kind(), real->spec.kind());
  EXPECT_EQ(ports(sim->spec.inputs()), ports(real->spec.inputs()));
  EXPECT_EQ(ports(sim->spec.outputs()), ports(real->spec.outputs()));
  EXPECT_EQ(events(sim->spec), events(real->spec));
}

TEST(SimCamera, TheLastViewpointIsFollowedByLostAsTheEndOfAVideoFile) {
  ComponentHarness h(fba::test::built_plugins(), "sim.camera",
                     {{"mesh", kCan}, {"views", 3}, {"width", 64}, {"height", 48}, {"fx", 60.0}});
  h.run();
  EXPECT_EQ(h.packets("frame").size(), 3u);
  const auto all = h.events();
  std::vector<fba::Event> lost;
  for (const auto& e : all)
    if (e.name == "lost") lost.push_back(e);
  ASSERT_EQ(lost.size(), 1u);
  EXPECT_EQ(lost[0].payload, "sim_model");  // the frames' source
}

TEST(SimCamera, TheOldNameOfTheWorldParameterIsRefusedListingTheNewOne) {
  try {
    ComponentHarness h(fba::test::built_plugins(), "sim.camera", {{"mesh", kCan}, {"frame", "table"}});
    FAIL() << "'frame' (now the output's name only) was taken as a parameter";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("has no parameter 'frame'"), std::string::npos) << what;
    EXPECT_NE(what.find("world"), std::string::npos) << what;
  }
}
