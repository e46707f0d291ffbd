#include "fba/canopen/cia402.hpp"

#include <fmt/format.h>

namespace fba::canopen::cia402 {

namespace {

// Each state as CiA 402 shows it in the statusword (the bits under its mask) and by name; decode
// tries them in this order.
struct StateInfo {
  State state;
  std::uint16_t mask;
  std::uint16_t bits;
  const char* name;
};
constexpr StateInfo kStates[] = {
    {State::not_ready_to_switch_on, 0x4F, 0x00, "not ready to switch on"},
    {State::switch_on_disabled, 0x4F, 0x40, "switch on disabled"},
    {State::ready_to_switch_on, 0x6F, 0x21, "ready to switch on"},
    {State::switched_on, 0x6F, 0x23, "switched on"},
    {State::operation_enabled, 0x6F, 0x27, "operation enabled"},
    {State::quick_stop_active, 0x6F, 0x07, "quick stop active"},
    {State::fault_reaction_active, 0x4F, 0x0F, "fault reaction active"},
    {State::fault, 0x4F, 0x08, "fault"},
};

const StateInfo* info(State state) {
  for (const auto& i : kStates)
    if (i.state == state) return &i;
  return nullptr;
}

}  // namespace

State decode(std::uint16_t s) {
  for (const auto& i : kStates)
    if ((s & i.mask) == i.bits) return i.state;
  return State::not_ready_to_switch_on;  // no state of the standard matches: not ready
}

std::uint16_t state_bits(State state) {
  const StateInfo* i = info(state);
  return i ? i->bits : 0;
}

std::string to_string(State state) {
  const StateInfo* i = info(state);
  return i ? i->name : "unknown";
}

Drive::Drive(Master& master, int node, DriveOptions options) : master_(master), node_(node), options_(options) {}

std::uint16_t Drive::statusword() { return master_.read<std::uint16_t>(node_, od::kStatusword, 0); }
std::int32_t Drive::position() { return master_.read<std::int32_t>(node_, od::kPositionActual, 0); }
std::uint16_t Drive::error_code() { return master_.read<std::uint16_t>(node_, od::kErrorCode, 0); }
void Drive::controlword(std::uint16_t value) { master_.write<std::uint16_t>(node_, od::kControlword, 0, value); }

std::uint16_t Drive::wait(const std::function<bool(std::uint16_t)>& done, std::chrono::milliseconds timeout,
                          const std::string& what) {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    master_.throw_if_faulted(node_);
    const std::uint16_t s = statusword();
    if (done(s)) return s;
    if (decode(s) == State::fault) {
      const std::uint16_t code = error_code();
      throw Error(fmt::format("node {}: the drive is in fault while waiting for {}: error code 0x{:04X} ({})", node_,
                              what, code, emcy_name(code)));
    }
    if (Clock::now() >= deadline)
      throw Error(
          fmt::format("node {}: timed out after {} ms waiting for {}; the drive is in \"{}\" (statusword 0x{:04X})",
                      node_, timeout.count(), what, to_string(decode(s)), s));
    master_.spin_for(options_.poll_period);
  }
}

std::uint16_t Drive::enable(std::chrono::milliseconds timeout, bool reset_fault) {
  const auto deadline = Clock::now() + timeout;
  std::uint16_t reset = 0;
  for (;;) {
    master_.throw_if_faulted(node_);
    const State state = this->state();
    if (state == State::operation_enabled) return reset;
    if (Clock::now() >= deadline)
      throw Error(fmt::format("node {}: could not enable the drive within {} ms; it stays in \"{}\"", node_,
                              timeout.count(), to_string(state)));
    switch (state) {
      case State::fault: {
        const std::uint16_t code = error_code();
        if (!reset_fault || reset != 0)
          throw DriveFault(node_, code,
                           fmt::format("node {}: the drive is in fault{}, error code 0x{:04X} ({})", node_,
                                       reset != 0 ? " again after its fault was reset" : "", code, emcy_name(code)));
        reset = code ? code : 0xFFFF;  // a fault without a code was reset too
        fault_reset(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()));
        break;
      }
      case State::switch_on_disabled:
        controlword(cw::kShutdown);
        break;
      case State::ready_to_switch_on:
        controlword(cw::kSwitchOn);
        break;
      case State::switched_on:
        controlword(cw::kEnableOperation);
        break;
      case State::quick_stop_active:
        controlword(cw::kDisableVoltage);
        break;  // back through "switch on disabled"
      case State::not_ready_to_switch_on:
      case State::fault_reaction_active:
      case State::operation_enabled:
        break;  // the drive moves on by itself
    }
    master_.spin_for(options_.poll_period);
  }
}

void Drive::set_mode(std::int8_t mode) {
  master_.write<std::int8_t>(node_, od::kModesOfOperation, 0, mode);
  const auto shown = master_.read<std::int8_t>(node_, od::kModesOfOperationDisplay, 0);
  if (shown != mode)
    throw Error(fmt::format("node {}: the drive shows mode of operation {} after {} was set", node_, shown, mode));
}

void Drive::set_profile(std::uint32_t velocity, std::uint32_t acceleration) {
  set_mode(kProfilePosition);
  master_.write<std::uint32_t>(node_, od::kProfileVelocity, 0, velocity);
  master_.write<std::uint32_t>(node_, od::kProfileAcceleration, 0, acceleration);
  master_.write<std::uint32_t>(node_, od::kProfileDeceleration, 0, acceleration);
}

void Drive::start_move(std::int32_t target, std::chrono::milliseconds timeout, bool relative) {
  master_.write<std::int32_t>(node_, od::kTargetPosition, 0, target);
  const std::uint16_t base = cw::kEnableOperation | cw::kChangeImmediately | (relative ? cw::kRelative : 0);
  controlword(base | cw::kNewSetPoint);
  wait([](std::uint16_t s) { return (s & sw::kSetPointAcknowledge) != 0; }, timeout,
       fmt::format("the set-point acknowledge of target {}", target));
  controlword(base);  // the handshake: bit 4 low again, ready for the next set-point
}

bool Drive::target_reached() { return (statusword() & sw::kTargetReached) != 0; }

void Drive::move_to(std::int32_t target, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  start_move(target, timeout);
  const auto left = std::max(std::chrono::milliseconds(0),
                             std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()));
  wait(
      [this, target](std::uint16_t s) {
        if (decode(s) != State::operation_enabled)
          throw Error(fmt::format(
              "node {}: the drive left \"operation enabled\" for \"{}\" while moving to {} (statusword 0x{:04X})",
              node_, to_string(decode(s)), target, s));
        return (s & sw::kTargetReached) != 0;
      },
      left, fmt::format("target position {}", target));
}

void Drive::quick_stop() { controlword(cw::kQuickStop); }

void Drive::fault_reset(std::chrono::milliseconds timeout) {
  controlword(cw::kDisableVoltage);  // bit 7 low, so that the reset is a rising edge
  controlword(cw::kFaultReset);
  const auto deadline = Clock::now() + timeout;
  for (std::uint16_t s = statusword(); decode(s) == State::fault || decode(s) == State::fault_reaction_active;
       s = statusword()) {
    if (Clock::now() >= deadline)
      throw Error(fmt::format("node {}: still in fault {} ms after a fault reset (statusword 0x{:04X}, error code 0x{:04X})",
                              node_, timeout.count(), s, error_code()));
    master_.spin_for(options_.poll_period);
  }
  controlword(cw::kDisableVoltage);  // bit 7 low again
}

void Drive::disable() { controlword(cw::kDisableVoltage); }

}  // namespace fba::canopen::cia402
