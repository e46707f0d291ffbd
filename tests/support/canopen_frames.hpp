// What the CANopen arm emulator heard (CanopenArmEmulator::heard()), read back by tests: where a
// master's quick stops and give-ups stand in the order the drives received them.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

#include "fba/can/frame.hpp"

namespace fba::test {

// The place in `frames` of the last quick stop to `node` (an expedited SDO download of 0x0002 to
// the controlword 0x6040:00), or -1.
inline long last_quick_stop(const std::vector<can::Frame>& frames, int node) {
  for (long i = static_cast<long>(frames.size()) - 1; i >= 0; --i) {
    const can::Frame& f = frames[static_cast<std::size_t>(i)];
    if (f.id == 0x600u + static_cast<unsigned>(node) && f.dlc == 8 && f.data[0] == 0x2B && f.data[1] == 0x40 &&
        f.data[2] == 0x60 && f.data[3] == 0x00 && f.data[4] == 0x02 && f.data[5] == 0x00)
      return i;
  }
  return -1;
}

// The place of the first SDO abort sent to `node` after `from` (how a master gives up a request
// that got no answer), or -1.
inline long sdo_abort_after(const std::vector<can::Frame>& frames, int node, long from) {
  for (long i = from + 1; i < static_cast<long>(frames.size()); ++i) {
    const can::Frame& f = frames[static_cast<std::size_t>(i)];
    if (f.id == 0x600u + static_cast<unsigned>(node) && f.dlc == 8 && f.data[0] == 0x80) return i;
  }
  return -1;
}

// What `emulator` heard once it holds the abort to `node` after its last quick stop (a master
// sends it last; the emulator hears it a moment later), and that abort's place in `given_up` (-1 if
// it never came: the bound only catches a hang).
template <class Emulator>
std::vector<can::Frame> heard_until_given_up(const Emulator& emulator, int node, long& given_up) {
  std::vector<can::Frame> heard;
  for (int i = 0; i < 60'000; ++i) {
    heard = emulator.heard();
    given_up = sdo_abort_after(heard, node, last_quick_stop(heard, node));
    if (given_up >= 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return heard;
}

// Checks, in the order the drives heard it, that each of the arm's six drives got its quick stop
// before the master gave up on the drive at `silent` (a silent one costs a single time-out).
template <class Emulator>
void expect_quick_stops_before_giving_up(const Emulator& emulator, int silent) {
  long given_up = -1;
  const auto heard = heard_until_given_up(emulator, silent, given_up);
  ASSERT_GE(given_up, 0) << "node " << silent << " was not told its quick stop was given up";
  for (int node = 1; node <= 6; ++node) {
    const long sent = last_quick_stop(heard, node);
    EXPECT_GE(sent, 0) << "node " << node;
    EXPECT_LT(sent, given_up) << "node " << node << "'s quick stop waited for node " << silent << "'s time-out";
  }
}

}  // namespace fba::test
