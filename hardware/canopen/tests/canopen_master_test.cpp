// The CANopen master and the CiA 402 helper against the arm emulator, on both transports the
// tests can have here: SLCAN over a pseudo-terminal (the serial code a USB-CAN adapter runs) and a
// socketpair (the frame-record code SocketCAN runs). Every wait in the code under test has a
// timeout, so a failure here is an error, never a hang.
#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "emulated_arm.hpp"
#include "fba/canopen/cia402.hpp"
#include "fba/canopen/master.hpp"
#include "support/contains.hpp"

using namespace std::chrono_literals;
using namespace fba::canopen;
using fba::emulators::CanopenArmEmulator;

namespace {

using fba::test::Transport;

using fba::test::contains;

// Three drives (nodes 1, 2, 3) with a 20 ms heartbeat, and a master on the other end of the chosen transport.
class CanopenMaster : public ::testing::TestWithParam<Transport> {
 protected:
  void SetUp() override {
    fba::emulators::CanopenArmOptions options;
    options.nodes = {1, 2, 3};
    options.heartbeat_ms = 20;
    options.profile_velocity = 200'000;
    arm_.emplace(GetParam(), options);
    master_.emplace(arm_->host(), MasterOptions{.sdo_timeout = 1s});  // generous: the emulator may wait for a core
    // Every node's boot-up (or first heartbeat) arrives before the tests start.
    ASSERT_TRUE(master_->spin_until([this] { return heard(1) && heard(2) && heard(3); }, 5s));
  }
  bool heard(int node) { return master_->state(node) != NmtState::unknown; }
  Master& master() { return *master_; }
  CanopenArmEmulator& emulator() { return arm_->emulator(); }
  // Operational, enabled and in profile position mode.
  cia402::Drive ready_drive(int node) {
    master().nmt(NmtCommand::start, node);
    cia402::Drive drive(master(), node);
    drive.enable(2s);
    drive.set_profile(200'000, 2'000'000);
    return drive;
  }
  // Waits for the master's first fault and checks its kind, its node and what it says.
  void expect_first_fault(Fault::Kind kind, int node, const std::string& says) {
    ASSERT_TRUE(master().spin_until([&] { return !master().faults().empty(); }, 5s));
    const Fault fault = master().faults().front();
    EXPECT_EQ(fault.kind, kind);
    EXPECT_EQ(fault.node, node);
    EXPECT_TRUE(contains(fault.message, says)) << fault.message;
  }

  std::optional<fba::test::EmulatedArm> arm_;
  std::optional<Master> master_;  // declared after arm_: destroyed before the bus it uses
};

}  // namespace

INSTANTIATE_TEST_SUITE_P(Transports, CanopenMaster, ::testing::Values(Transport::slcan_pty, Transport::socketpair),
                         fba::test::transport_name);

TEST_P(CanopenMaster, SdoUploadAndDownloadRoundTrip) {
  EXPECT_EQ(master().read<std::uint32_t>(1, 0x1000, 0), 0x00020192u);  // CiA 402 servo drive
  EXPECT_EQ(master().read<std::uint32_t>(3, 0x1018, 4), 3u);
  master().write<std::int32_t>(2, 0x607A, 0, -123456);
  EXPECT_EQ(master().read<std::int32_t>(2, 0x607A, 0), -123456);
  master().write<std::uint16_t>(2, 0x1017, 0, 25);
  EXPECT_EQ(master().read<std::uint16_t>(2, 0x1017, 0), 25);
  EXPECT_EQ(master().read<std::int32_t>(1, 0x607A, 0), 0);  // another node's object is its own
}

TEST_P(CanopenMaster, SdoAbortsCarryTheirCodeAndName) {
  const struct {
    std::function<void()> call;
    std::uint32_t code;
    std::string name;
  } cases[] = {
      {[&] { master().read<std::uint32_t>(1, 0x2000, 0); }, 0x06020000, "object does not exist"},
      {[&] { master().write<std::uint16_t>(1, 0x6041, 0, 1); }, 0x06010002, "read-only"},
      {[&] { master().write<std::uint32_t>(1, 0x6040, 0, 6); }, 0x06070010,
       "length of service parameter does not match"},
      {[&] { master().read<std::uint32_t>(1, 0x1018, 9); }, 0x06090011, "sub-index does not exist"},
      {[&] { master().write<std::int8_t>(1, 0x6060, 0, 3); }, 0x06090030, "invalid value"},
  };
  for (const auto& c : cases) {
    try {
      c.call();
      ADD_FAILURE() << "no abort for code " << std::hex << c.code;
    } catch (const SdoAbort& e) {
      EXPECT_EQ(e.code, c.code) << e.what();
      EXPECT_EQ(e.node, 1);
      EXPECT_TRUE(contains(e.what(), c.name)) << e.what();
      EXPECT_TRUE(contains(e.what(), "node 1")) << e.what();
    }
  }
}

TEST_P(CanopenMaster, AnSdoToAnAbsentNodeTimesOutNamingIt) {
  try {
    master().read<std::uint16_t>(9, 0x6041, 0);
    FAIL();
  } catch (const SdoTimeout& e) {
    EXPECT_TRUE(contains(e.what(), "node 9")) << e.what();
    EXPECT_TRUE(contains(e.what(), "nothing has been heard")) << e.what();
  }
}

TEST_P(CanopenMaster, NmtCommandsShowInTheHeartbeats) {
  master().nmt(NmtCommand::start, 0);
  ASSERT_TRUE(master().spin_until(
      [&] { return master().state(1) == NmtState::operational && master().state(3) == NmtState::operational; }, 2s));
  master().nmt(NmtCommand::stop, 2);
  ASSERT_TRUE(master().spin_until([&] { return master().state(2) == NmtState::stopped; }, 2s));
  EXPECT_EQ(master().state(1), NmtState::operational);
  EXPECT_THROW(master().read<std::uint16_t>(2, 0x6041, 0), SdoTimeout);  // a stopped node does not answer SDO
  master().nmt(NmtCommand::pre_operational, 2);
  ASSERT_TRUE(master().spin_until([&] { return master().state(2) == NmtState::pre_operational; }, 2s));
  master().write<std::uint16_t>(2, 0x1017, 0, 50);
  master().nmt(NmtCommand::reset_node, 2);  // back to the defaults, with a boot-up message
  ASSERT_TRUE(master().spin_until([&] { return master().state(2) == NmtState::pre_operational; }, 2s));
  EXPECT_EQ(master().read<std::uint16_t>(2, 0x1017, 0), 20);
  EXPECT_TRUE(master().faults().empty());  // a reset the master asked for is no fault
}

TEST_P(CanopenMaster, ANodeThatRebootsUnaskedIsAFaultNamingIt) {
  cia402::Drive drive = ready_drive(2);
  emulator().reboot(2);
  expect_first_fault(Fault::Kind::rebooted, 2, "node 2: rebooted unasked");
  EXPECT_EQ(master().state(2), NmtState::pre_operational);
  EXPECT_EQ(drive.state(), cia402::State::switch_on_disabled);  // the drive lost its enable with the reboot
}

TEST_P(CanopenMaster, TheDriveIsEnabledAndMovedToAPosition) {
  master().nmt(NmtCommand::start, 1);
  cia402::Drive drive(master(), 1);
  EXPECT_EQ(drive.state(), cia402::State::switch_on_disabled);
  drive.enable(2s);
  EXPECT_EQ(drive.state(), cia402::State::operation_enabled);
  drive.set_profile(200'000, 2'000'000);
  drive.move_to(20'000, 5s);
  EXPECT_EQ(drive.position(), 20'000);
  EXPECT_EQ(emulator().position(1), 20'000);
  EXPECT_TRUE(drive.target_reached());
  drive.move_to(-5'000, 5s);
  EXPECT_EQ(drive.position(), -5'000);
  EXPECT_EQ(emulator().position(2), 0);  // the other joints stayed where they were
}

TEST_P(CanopenMaster, QuickStopHoldsTheDriveShortOfItsTarget) {
  cia402::Drive drive = ready_drive(1);
  drive.start_move(10'000'000, 2s);  // 50 s at 200,000 units/s
  master().spin_for(20ms);
  drive.quick_stop();
  EXPECT_EQ(drive.state(), cia402::State::quick_stop_active);
  const std::int32_t stopped_at = drive.position();
  master().spin_for(50ms);
  EXPECT_EQ(drive.position(), stopped_at);
  EXPECT_LT(stopped_at, 10'000'000);
  drive.enable(2s);  // a quick stop is left through "switch on disabled"
  EXPECT_EQ(drive.state(), cia402::State::operation_enabled);
}

TEST_P(CanopenMaster, PdosAreMappedThroughSdoAndExchangedOnSync) {
  const int node = 2;
  master().configure_tpdo(node, 1, {{{0x6041, 0, 16}, {0x6064, 0, 32}}, 1});     // on every SYNC
  master().configure_rpdo(node, 1, {{{0x6040, 0, 16}, {0x607A, 0, 32}}, 0xFF});  // applied on arrival
  EXPECT_EQ(master().read<std::uint8_t>(node, 0x1A00, 0), 2);
  EXPECT_EQ(master().read<std::uint32_t>(node, 0x1A00, 2), 0x60640020u);
  cia402::Drive drive = ready_drive(node);
  auto rpdo = [&](std::uint16_t controlword, std::int32_t target) {
    const auto t = static_cast<std::uint32_t>(target);
    const std::uint8_t bytes[6] = {static_cast<std::uint8_t>(controlword), static_cast<std::uint8_t>(controlword >> 8),
                                   static_cast<std::uint8_t>(t),           static_cast<std::uint8_t>(t >> 8),
                                   static_cast<std::uint8_t>(t >> 16),     static_cast<std::uint8_t>(t >> 24)};
    master().send_rpdo(node, 1, bytes);
  };
  auto tpdo_position = [&]() -> std::optional<std::int32_t> {
    const auto s = master().tpdo(node, 1);
    if (!s || s->frame.dlc != 6) return std::nullopt;
    return static_cast<std::int32_t>(s->frame.data[2] | s->frame.data[3] << 8 | s->frame.data[4] << 16 |
                                     static_cast<std::uint32_t>(s->frame.data[5]) << 24);
  };
  rpdo(0x003F, 7'000);  // enable operation + new set-point + change immediately
  rpdo(0x002F, 7'000);  // the handshake's second half
  for (int i = 0; i < 400 && tpdo_position() != 7'000; ++i) {
    master().send_sync();
    master().spin_for(5ms);
  }
  EXPECT_EQ(tpdo_position(), 7'000);
  const auto sample = master().tpdo(node, 1);
  ASSERT_TRUE(sample);
  EXPECT_EQ(sample->frame.id, 0x182u);
  const auto statusword = static_cast<std::uint16_t>(sample->frame.data[0] | sample->frame.data[1] << 8);
  EXPECT_EQ(cia402::decode(statusword), cia402::State::operation_enabled);
  EXPECT_GT(emulator().syncs_seen(), 0u);
  EXPECT_EQ(drive.position(), 7'000);
}

TEST_P(CanopenMaster, TheSyncProducerDrivesSynchronousTpdos) {
  Master& m = master();
  m.configure_tpdo(3, 2, {{{0x6064, 0, 32}}, 2});  // every second SYNC
  m.nmt(NmtCommand::start, 3);
  Master producer(m.bus(), MasterOptions{.sync_period = 5ms});
  ASSERT_TRUE(producer.spin_until([&] { return producer.tpdo(3, 2) && producer.tpdo(3, 2)->count >= 3; }, 5s));
  EXPECT_EQ(producer.tpdo(3, 2)->frame.id, 0x283u);  // TPDO2: 0x280 + node
  EXPECT_GE(emulator().syncs_seen(), 6u);
}

TEST_P(CanopenMaster, BadPdoMappingsAreRefusedWithNamedAborts) {
  try {
    master().configure_tpdo(1, 1, {{{0x1000, 0, 32}}});
    FAIL();
  } catch (const SdoAbort& e) {
    EXPECT_EQ(e.code, 0x06040041u) << e.what();
    EXPECT_TRUE(contains(e.what(), "cannot be mapped")) << e.what();
  }
  EXPECT_THROW(master().configure_tpdo(1, 1, {{{0x6064, 0, 32}, {0x6064, 0, 32}, {0x6041, 0, 16}}}),
               std::invalid_argument);
  EXPECT_THROW(master().configure_tpdo(1, 5, {}), std::invalid_argument);
}

TEST_P(CanopenMaster, HeartbeatLossIsAFaultNamingTheNode) {
  // Timeouts far above the 20 ms heartbeat, so that a loaded machine cannot fake a loss.
  for (int node : {1, 2, 3}) master().watch_heartbeat(node, 500ms);
  master().spin_for(300ms);
  EXPECT_TRUE(master().faults().empty());
  emulator().silence(2);
  expect_first_fault(Fault::Kind::heartbeat_lost, 2, "node 2: heartbeat lost");
  master().spin_for(300ms);
  EXPECT_EQ(master().faults().size(), 1u);  // the others still beat
  EXPECT_THROW(master().throw_if_faulted(2), NodeFault);
  EXPECT_NO_THROW(master().throw_if_faulted(1));
}

TEST_P(CanopenMaster, ANodeFallingSilentMidMotionEndsTheMoveAndTheOthersQuickStop) {
  master().watch_heartbeat(2, 500ms);
  cia402::Drive silent = ready_drive(2);
  cia402::Drive other = ready_drive(1);
  other.start_move(10'000'000, 2s);
  silent.start_move(10'000'000, 2s);
  emulator().silence(2);
  try {
    silent.move_to(10'000'000, 10s);
    FAIL();
  } catch (const Error& e) {  // the lost heartbeat, or the SDO that went unanswered: either names node 2
    EXPECT_TRUE(contains(e.what(), "node 2")) << e.what();
  }
  other.quick_stop();
  EXPECT_EQ(other.state(), cia402::State::quick_stop_active);
}

TEST_P(CanopenMaster, AnEmcyIsReportedNamedAndEndsTheMove) {
  cia402::Drive drive = ready_drive(3);
  drive.start_move(10'000'000, 2s);
  emulator().inject_fault(3, 0x2310);
  try {
    drive.move_to(10'000'000, 10s);
    FAIL();
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), "node 3")) << e.what();
  }
  ASSERT_TRUE(master().spin_until([&] { return !master().emergencies().empty(); }, 2s));
  const Emergency emcy = master().emergencies().front();
  EXPECT_EQ(emcy.node, 3);
  EXPECT_EQ(emcy.code, 0x2310);
  EXPECT_EQ(emcy.error_register, 0x03);
  EXPECT_TRUE(contains(emcy.describe(), "continuous over-current")) << emcy.describe();
  EXPECT_TRUE(contains(emcy.describe(), "generic, current")) << emcy.describe();
  ASSERT_FALSE(master().faults().empty());
  EXPECT_TRUE(contains(master().faults().front().message, "node 3: EMCY 0x2310 (continuous over-current)"))
      << master().faults().front().message;
  EXPECT_EQ(drive.state(), cia402::State::fault);
  EXPECT_EQ(drive.error_code(), 0x2310);

  // Reset: the drive comes back, with an "error reset" EMCY that is not a fault.
  master().clear_faults(3);
  drive.fault_reset(2s);
  EXPECT_EQ(drive.error_code(), 0);
  ASSERT_TRUE(master().spin_until([&] { return master().emergencies().size() == 2; }, 2s));
  EXPECT_EQ(master().emergencies().back().code, 0x0000);
  EXPECT_TRUE(master().faults().empty());
  drive.enable(2s);
  drive.move_to(1'000, 5s);
  EXPECT_EQ(drive.position(), 1'000);
}

TEST_P(CanopenMaster, GarbageOnTheLineIsSkippedCountedAndHarmless) {
  for (int i = 0; i < 20; ++i) {
    emulator().inject_garbage();
    master().write<std::int32_t>(1, 0x607A, 0, i);
    EXPECT_EQ(master().read<std::int32_t>(1, 0x607A, 0), i);
  }
  master().spin_for(20ms);
  EXPECT_GT(master().bus().discarded(), 0u);
  EXPECT_FALSE(master().bus().last_discard_reason().empty());
}

TEST_P(CanopenMaster, TheLineVanishingMidMotionIsAClearErrorNotAHang) {
  cia402::Drive drive = ready_drive(1);
  drive.start_move(10'000'000, 2s);
  emulator().disconnect();
  try {
    drive.move_to(10'000'000, 10s);
    FAIL();
  } catch (const fba::can::BusError& e) {
    EXPECT_TRUE(contains(e.what(), master().bus().name())) << e.what();
  }
  EXPECT_THROW(master().nmt(NmtCommand::stop, 0), fba::can::BusError);
}

TEST_P(CanopenMaster, ANodeRepeatingEmcyWithoutEndIsKeptWithinBounds) {
  // In rounds of 50, each taken in before the next: this thread both asks for the EMCYs and reads
  // them, and a bus left full would stall the emulator's sends.
  for (int i = 0; i < 1500; ++i) {
    emulator().inject_fault(1, static_cast<std::uint16_t>(0x5000 + i));
    if (i % 50 == 49)
      ASSERT_TRUE(master().spin_until(
          [&] { return !master().emergencies().empty() && master().emergencies().back().code == 0x5000 + i; }, 20s));
  }
  EXPECT_EQ(master().emergencies().size(), 1000u);  // the latest thousand
  EXPECT_EQ(master().emergencies().front().code, 0x5000 + 500);
  EXPECT_EQ(master().faults().size(), 1000u);
  EXPECT_TRUE(contains(master().faults().front().message, "EMCY 0x5000")) << master().faults().front().message;
}
