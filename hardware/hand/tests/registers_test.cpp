// The register codec against the example frames of Robotiq's 3-Finger Gripper manual (its Modbus
// RTU example: close at full speed and force, and the status when the grip is completed), so the
// driver's reading of the manual is checked against the manual, not only against the emulator.
#include "registers.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace rq = fba::robotiq;

TEST(Robotiq3fRegisters, CloseAtFullSpeedAndForceEncodesAsTheManualsExample) {
  // 09 10 03 E8 00 03 06 | 09 00 00 FF FF FF: rACT = 1, rGTO = 1, position, speed, force 255.
  rq::Command c;
  c.activate = true;
  c.go = true;
  c.axes[rq::kA] = {255, 255, 255};
  c.axes[rq::kB] = c.axes[rq::kC] = c.axes[rq::kScissor] = {0, 0, 0};
  const rq::Registers r = rq::encode(c);
  EXPECT_EQ(r[0], 0x0900);
  EXPECT_EQ(r[1], 0x00FF);
  EXPECT_EQ(r[2], 0xFFFF);
  for (int i = 3; i < rq::kRegisterCount; ++i) EXPECT_EQ(r[i], 0) << i;
}

TEST(Robotiq3fRegisters, OptionsAndModeBitsSitWhereTheManualPutsThem) {
  rq::Command c;
  c.activate = true;
  c.mode = rq::Mode::scissor;
  c.auto_release = true;
  c.individual_fingers = true;
  c.individual_scissor = true;
  c.axes[rq::kScissor] = {0x12, 0x34, 0x56};
  const rq::Registers r = rq::encode(c);
  EXPECT_EQ(r[0] >> 8, 0x01 | 0x03 << 1 | 0x10);  // rACT, rMOD = 3, rATR; rGTO clear
  EXPECT_EQ(r[0] & 0xFF, 0x04 | 0x08);            // rICF (bit 2), rICS (bit 3)
  EXPECT_EQ(r[6], 0x1234);                        // bytes 12, 13: scissor position, speed
  EXPECT_EQ(r[7], 0x5600);                        // byte 14: scissor force; byte 15 is past the command
}

TEST(Robotiq3fRegisters, ValueOutsideAByteIsRefusedNamingTheField) {
  rq::Command c;
  c.axes[rq::kB].force = 256;
  try {
    rq::encode(c);
    FAIL() << "encoded a force of 256";
  } catch (const std::out_of_range& e) {
    EXPECT_STREQ(e.what(), "force of axis B must be 0..255, not 256");
  }
  c.axes[rq::kB].force = 0;
  c.axes[rq::kScissor].position = -1;
  EXPECT_THROW(rq::encode(c), std::out_of_range);
}

TEST(Robotiq3fRegisters, GripCompletedStatusDecodesAsTheManualExplainsIt) {
  // 09 03 10 | B9 EA 00 FF BC 00 00 C1 00 00 BD 00 00 89 00 00: all fingers stopped on the object.
  const rq::Registers r{0xB9EA, 0x00FF, 0xBC00, 0x00C1, 0x0000, 0xBD00, 0x0089, 0x0000};
  const rq::Status s = rq::decode(r);
  EXPECT_TRUE(s.activated);
  EXPECT_EQ(s.mode, rq::Mode::basic);
  EXPECT_TRUE(s.go);
  EXPECT_EQ(s.imc, 3);
  EXPECT_EQ(s.motion, 2);  // all fingers stopped before the requested position
  EXPECT_EQ(s.fault, 0);
  for (int axis : {rq::kA, rq::kB, rq::kC}) EXPECT_EQ(s.axes[axis].contact, rq::Contact::while_closing) << axis;
  EXPECT_EQ(s.axes[rq::kScissor].contact, rq::Contact::at_request);
  EXPECT_EQ(s.axes[rq::kA].requested, 0xFF);
  EXPECT_EQ(s.axes[rq::kA].position, 0xBC);
  EXPECT_EQ(s.axes[rq::kB].position, 0xC1);
  EXPECT_EQ(s.axes[rq::kC].position, 0xBD);
  EXPECT_EQ(s.axes[rq::kScissor].position, 0x89);
}

TEST(Robotiq3fRegisters, ActivationInProgressAndCompletedDecodeAsTheManualSays) {
  EXPECT_EQ(rq::decode({0x1100}).imc, 1);        // 09 03 02 11 00: activation in progress
  const rq::Status done = rq::decode({0x3100});  // 09 03 02 31 00: activation completed
  EXPECT_TRUE(done.activated);
  EXPECT_EQ(done.imc, 3);
  EXPECT_FALSE(done.go);
}

TEST(Robotiq3fRegisters, FaultCodesAreNamedAndOnlyTheSelfClearingOnesAreTransient) {
  EXPECT_EQ(rq::fault_text(0x0D),
            "0x0D activation fault, verify that no interference or other error occurred (major: reset required)");
  EXPECT_EQ(rq::fault_text(0x03), "0x03 a fault code the manual does not list");
  for (int code : {0x05, 0x06, 0x09, 0x0A}) EXPECT_TRUE(rq::fault_is_transient(code)) << code;
  for (int code : {0x07, 0x0B, 0x0D, 0x0E, 0x0F}) EXPECT_FALSE(rq::fault_is_transient(code)) << code;
}
