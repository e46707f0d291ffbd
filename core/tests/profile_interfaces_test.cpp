// Profile interfaces (core/src/profile_interfaces.cpp): what a component type offers the task
// around it, and what differs between two, from their specs alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include <fba/task_config.hpp>

#include "fixture_components.hpp"

TEST(ProfileInterfaces, TwoTypesDifferInTheirPortsAndEventsOneLineEach) {
  const auto& reg = fba::test::registry();
  const fba::Interface pass = fba::interface_of(reg.find("examples.passthrough")->spec);
  const fba::Interface countdown = fba::interface_of(reg.find("test.countdown")->spec);
  EXPECT_TRUE(fba::interface_differences(pass, pass).empty());
  EXPECT_EQ(fba::interface_differences(pass, countdown),
            (std::vector<std::string>{"input 'in': any in examples.passthrough, fba.Int in test.countdown",
                                      "output 'out': like input 'in' in examples.passthrough, fba.Int in test.countdown"}));
  const fba::Interface sink = fba::interface_of(reg.find("examples.sink")->spec);
  const auto diff = fba::interface_differences(pass, sink);
  EXPECT_NE(std::find(diff.begin(), diff.end(), "output 'out' (like input 'in'): only examples.passthrough has it"), diff.end())
      << ::testing::PrintToString(diff);
  EXPECT_NE(std::find(diff.begin(), diff.end(), "event 'done': only examples.sink emits it"), diff.end()) << ::testing::PrintToString(diff);
  EXPECT_EQ(fba::describe(pass), "    inputs:  in (any)\n    outputs: out (like input 'in')\n    events:  error, finished\n");
}
