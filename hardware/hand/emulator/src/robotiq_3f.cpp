#include "fba/emulators/robotiq_3f.hpp"

#include <modbus.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace fba::emulators {

namespace {

constexpr int kCommandAddress = 0x03E8, kStatusAddress = 0x07D0, kRegisters = 8;
constexpr int kA = 0, kB = 1, kC = 2, kS = 3;
constexpr int kScissorMode = 3;
constexpr double kNever = 1e9;  // a contact position no axis reaches

// Where each grasping mode puts the scissor (basic is the manual's 0x89 = 137).
double scissor_for_mode(int mode) {
  static constexpr double kPositions[4] = {137, 220, 30, 0};
  return kPositions[mode & 3];
}

std::uint16_t crc16(const std::uint8_t* data, std::size_t size) {
  std::uint16_t crc = 0xFFFF;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001) : static_cast<std::uint16_t>(crc >> 1);
  }
  return crc;
}

bool line_gone(int error) {
  return error == EIO || error == ECONNRESET || error == EBADF || error == ENXIO || error == EPIPE;
}

}  // namespace

Robotiq3fEmulator::Robotiq3fEmulator(can::Fd line, std::string name, Robotiq3fOptions options)
    : line_(std::move(line)), name_(std::move(name)), options_(options) {
  // The context is never connected: its line is the descriptor given (a pseudo-terminal's master
  // cannot be opened again by path).
  ctx_ = modbus_new_rtu(name_.c_str(), 115200, 'N', 8, 1);
  if (!ctx_) throw std::runtime_error(name_ + ": libmodbus: " + modbus_strerror(errno));
  modbus_set_slave(ctx_, options_.slave_id);
  modbus_set_socket(ctx_, line_.get());
  modbus_set_indication_timeout(ctx_, 0, 10'000);  // returns every 10 ms to move the fingers
  // Holding registers from the commands to the end of the status (function 3 reads the status too),
  // input registers over the status (function 4).
  mapping_ = modbus_mapping_new_start_address(
      0, 0, 0, 0, kCommandAddress, kStatusAddress + kRegisters - kCommandAddress, kStatusAddress, kRegisters);
  if (!mapping_) {
    modbus_free(ctx_);
    throw std::runtime_error(name_ + ": libmodbus: cannot make the register map: " + modbus_strerror(errno));
  }
  last_update_ = std::chrono::steady_clock::now();
}

Robotiq3fEmulator::~Robotiq3fEmulator() {
  modbus_mapping_free(mapping_);
  modbus_free(ctx_);  // not modbus_close: the descriptor is line_'s
}

std::string Robotiq3fEmulator::run() {
  std::uint8_t request[MODBUS_RTU_MAX_ADU_LENGTH];
  while (!stop_) {
    {
      std::lock_guard lock(mutex_);
      if (disconnect_) {
        modbus_set_socket(ctx_, -1);
        line_.reset();
        return "disconnected (fault injection)";
      }
    }
    const int length = modbus_receive(ctx_, request);
    const int error = errno;
    std::lock_guard lock(mutex_);
    update(std::chrono::steady_clock::now());
    if (length > 0) {
      handle(request, length);
    } else if (length == -1 && error != ETIMEDOUT) {
      if (line_gone(error)) return std::string("the line is gone: ") + std::strerror(error);
      modbus_flush(ctx_);  // a garbled request: drop what is left of it
    }
  }
  return "stopped";
}

void Robotiq3fEmulator::handle(const std::uint8_t* request, int length) {
  if (silent_) return;
  const int header = modbus_get_header_length(ctx_);
  const int function = request[header];
  const int address = request[header + 1] << 8 | request[header + 2];
  const int count = request[header + 3] << 8 | request[header + 4];
  if (garbage_ > 0) {
    --garbage_;
    static constexpr std::uint8_t kNoise[] = {0x00, 0xFF, 0x55, 0xAA, 0x09, 0x04, 0x10, 0x13, 0xFE, 0x01, 0x09, 0x83};
    [[maybe_unused]] const auto written = ::write(line_.get(), kNoise, sizeof kNoise);
  }
  const bool read = function == MODBUS_FC_READ_HOLDING_REGISTERS || function == MODBUS_FC_READ_INPUT_REGISTERS;
  if (function != MODBUS_FC_WRITE_MULTIPLE_REGISTERS && !read) {
    modbus_reply_exception(ctx_, request, MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
    return;
  }
  const int base = read ? kStatusAddress : kCommandAddress;
  if (address < base || count < 1 || address + count > base + kRegisters) {
    modbus_reply_exception(ctx_, request, MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
    return;
  }
  ++state_.requests;
  if (read) {
    const auto status = status_registers();
    for (int i = 0; i < kRegisters; ++i) {
      mapping_->tab_input_registers[i] = status[i];
      mapping_->tab_registers[kStatusAddress - kCommandAddress + i] = status[i];
    }
  }
  if (!read) {
    for (int i = 0; i < count; ++i)
      command_[address - base + i] =
          static_cast<std::uint16_t>(request[header + 6 + 2 * i] << 8 | request[header + 7 + 2 * i]);
    commands_.push_back({command_, state_, std::chrono::steady_clock::now()});
    if (commands_.size() > kCommandsKept) commands_.pop_front();
  }
  if (corrupt_ != 0) {
    if (corrupt_ > 0) --corrupt_;
    if (!read) apply_command(command_);  // the command arrived; only its answer is spoilt
    send_corrupted(request);
    return;
  }
  modbus_reply(ctx_, request, length, mapping_);
  if (!read) apply_command(command_);
}

// The answer libmodbus would send, with its CRC turned upside down.
void Robotiq3fEmulator::send_corrupted(const std::uint8_t* request) {
  const int header = modbus_get_header_length(ctx_);
  const int function = request[header];
  std::vector<std::uint8_t> frame{request[0], static_cast<std::uint8_t>(function)};
  if (function == MODBUS_FC_WRITE_MULTIPLE_REGISTERS) {
    frame.insert(frame.end(), request + header + 1, request + header + 5);
  } else {
    const int address = request[header + 1] << 8 | request[header + 2],
              count = request[header + 3] << 8 | request[header + 4];
    frame.push_back(static_cast<std::uint8_t>(2 * count));
    const auto status = status_registers();
    for (int i = 0; i < count; ++i) {
      frame.push_back(static_cast<std::uint8_t>(status[address - kStatusAddress + i] >> 8));
      frame.push_back(static_cast<std::uint8_t>(status[address - kStatusAddress + i] & 0xFF));
    }
  }
  const std::uint16_t crc = static_cast<std::uint16_t>(~crc16(frame.data(), frame.size()));
  frame.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  frame.push_back(static_cast<std::uint8_t>(crc >> 8));
  [[maybe_unused]] const auto written = ::write(line_.get(), frame.data(), frame.size());
}

void Robotiq3fEmulator::apply_command(const std::array<std::uint16_t, 8>& registers) {
  std::uint8_t b[2 * kRegisters];
  for (int i = 0; i < kRegisters; ++i) {
    b[2 * i] = static_cast<std::uint8_t>(registers[i] >> 8);
    b[2 * i + 1] = static_cast<std::uint8_t>(registers[i] & 0xFF);
  }
  const bool act = b[0] & 1, go = (b[0] >> 3) & 1;
  const int mode = (b[0] >> 1) & 3;
  individual_fingers_ = (b[1] >> 2) & 1;
  individual_scissor_ = (b[1] >> 3) & 1;
  State& s = state_;
  if (!act) {  // reset: clears faults, stops everything
    s.activated = false;
    s.imc = 0;
    s.go = false;
    s.fault = go ? 0x07 : 0;
    activation_left_ = 0;
    return;
  }
  if (!s.activated && s.imc != 1) {  // rising activation: the fingers open, the scissor takes its place
    s.imc = 1;
    s.fault = 0;
    s.mode = mode;
    activation_left_ = options_.activation_s;
  } else if (s.activated && mode != s.mode) {
    s.mode = mode;
    s.imc = 2;
  }
  s.go = go;
  if (s.imc == 1 && go) s.fault = 0x05;
  if (s.imc != 3) return;  // requests count once activated and in mode
  auto set_request = [&](int axis, int offset) {
    Axis& a = s.axes[axis];
    const int request = b[offset], speed = b[offset + 1], force = b[offset + 2];
    if (request != a.request || force > a.force) a.contact = 0;  // a new move, or more force: detection starts again
    a.request = request;
    a.speed = speed;
    a.force = force;
  };
  if (s.mode == kScissorMode && !individual_scissor_) {
    set_request(kS, 3);  // finger A's request drives the scissor; the fingers stay
  } else {
    for (int axis : {kA, kB, kC}) set_request(axis, individual_fingers_ ? 3 + 3 * axis : 3);
    if (individual_scissor_) set_request(kS, 12);
  }
}

void Robotiq3fEmulator::update(std::chrono::steady_clock::time_point now) {
  const double dt = std::chrono::duration<double>(now - last_update_).count();
  last_update_ = now;
  State& s = state_;
  const double half = options_.max_aperture / 2;
  auto units_per_s = [&](int speed) {  // 22 to 110 mm/s at the tip
    return options_.speed_scale * 255.0 * (0.022 + 0.088 * speed / 255.0) / half;
  };
  if (s.imc == 1) {  // activation: fingers open, scissor to the mode's place
    if (options_.activates) activation_left_ -= dt;
    if (activation_left_ > 0) return;
    for (int axis : {kA, kB, kC}) s.axes[axis] = Axis{0, 0, s.axes[axis].speed, s.axes[axis].force, 3};
    s.axes[kS] = Axis{scissor_for_mode(s.mode), static_cast<int>(scissor_for_mode(s.mode)), 255, 0, 3};
    s.activated = true;
    s.imc = 3;
    if (s.fault == 0x05) s.fault = 0;
    return;
  }
  if (s.fault != 0 && s.fault != 0x05 && s.fault != 0x06) return;  // a fault freezes the hand
  if (s.imc == 2) {                                                // mode change: the scissor moves to the mode's place
    Axis& sc = s.axes[kS];
    const double target = individual_scissor_ ? sc.request : scissor_for_mode(s.mode);
    const double step = units_per_s(255) * dt;
    sc.position =
        std::abs(target - sc.position) <= step ? target : sc.position + std::copysign(step, target - sc.position);
    if (sc.position == target) {
      s.imc = 3;
      sc.request = static_cast<int>(target);
      sc.contact = 3;
    }
    return;
  }
  if (!s.activated || !s.go) return;

  // Where each axis would touch the object while closing.
  std::array<double, 4> touch{kNever, kNever, kNever, kNever};
  if (options_.object) {
    const double r = options_.object_width / 2, x = options_.object_offset;
    const double half_length = (options_.object_length > 0 ? options_.object_length : options_.object_width) / 2;
    auto position_at = [&](double reach) { return reach <= 0 ? kNever : std::max(0.0, 255.0 * (1 - reach / half)); };
    if (options_.stall_aperture > 0 && !(s.mode == kScissorMode && !individual_scissor_)) {
      touch[kA] = touch[kB] = touch[kC] = position_at(options_.stall_aperture / 2);
    } else if (s.mode == kScissorMode && !individual_scissor_) {
      touch[kS] =
          options_.object_width >= options_.max_spread ? 0 : 255.0 * (1 - options_.object_width / options_.max_spread);
    } else {
      touch[kA] = position_at(x + r);
      const double side = options_.max_spread * (1 - s.axes[kS].position / 255.0) / 2;  // B and C off the centre line
      if (side < half_length)  // where B's and C's line meets the ellipse
        touch[kB] = touch[kC] = position_at(r * std::sqrt(1 - (side / half_length) * (side / half_length)) - x);
    }
  }
  for (int axis = 0; axis < 4; ++axis) {
    Axis& a = s.axes[axis];
    const double step = units_per_s(a.speed) * dt;
    if (a.request > a.position) {
      const double limit = std::min<double>(a.request, std::max(touch[axis], a.position));
      if (a.position + step >= limit) {
        a.position = limit;
        a.contact = limit < a.request ? 2 : 3;
      } else {
        a.position += step;
        a.contact = 0;
      }
    } else if (a.request < a.position) {
      a.position = std::max<double>(a.request, a.position - step);
      a.contact = a.position == a.request ? 3 : 0;
    } else if (a.contact == 0) {
      a.contact = 3;
    }
  }
}

std::array<std::uint16_t, 8> Robotiq3fEmulator::status_registers() const {
  const State& s = state_;
  // gSTA over the fingers that grasp: the scissor in scissor mode, else A, B and C.
  std::vector<int> grasping =
      s.mode == kScissorMode && !individual_scissor_ ? std::vector<int>{kS} : std::vector<int>{kA, kB, kC};
  int moving = 0, early = 0;
  for (int axis : grasping) {
    moving += s.axes[axis].contact == 0;
    early += s.axes[axis].contact == 1 || s.axes[axis].contact == 2;
  }
  int motion = 0;
  if (s.go && s.imc == 3 && moving == 0) motion = early == 0 ? 3 : early == static_cast<int>(grasping.size()) ? 2 : 1;
  std::uint8_t b[2 * kRegisters] = {};
  b[0] = static_cast<std::uint8_t>((s.activated ? 1 : 0) | (s.mode << 1) | (s.go ? 1 << 3 : 0) | (s.imc << 4) |
                                   (motion << 6));
  for (int axis = 0; axis < 4; ++axis) {
    const Axis& a = s.axes[axis];
    b[1] |= static_cast<std::uint8_t>((a.contact & 3) << (2 * axis));
    b[3 + 3 * axis] = static_cast<std::uint8_t>(a.request);
    b[4 + 3 * axis] = static_cast<std::uint8_t>(std::lround(a.position));
    // Current, in 10 mA: some while moving, more the harder a finger pushes on the object.
    b[5 + 3 * axis] = static_cast<std::uint8_t>(a.contact == 0 ? 10 : a.contact == 2 ? 10 + a.force / 4 : 0);
  }
  b[2] = static_cast<std::uint8_t>(s.fault);
  if (s.mode == kScissorMode && !individual_scissor_)
    b[3] = static_cast<std::uint8_t>(s.axes[kS].request);  // A's request, echoed
  std::array<std::uint16_t, 8> r{};
  for (int i = 0; i < kRegisters; ++i) r[i] = static_cast<std::uint16_t>(b[2 * i] << 8 | b[2 * i + 1]);
  return r;
}

void Robotiq3fEmulator::silence() {
  std::lock_guard lock(mutex_);
  silent_ = true;
}
void Robotiq3fEmulator::corrupt_replies(int n) {
  std::lock_guard lock(mutex_);
  corrupt_ = n;
}
void Robotiq3fEmulator::inject_garbage() {
  std::lock_guard lock(mutex_);
  ++garbage_;
}
void Robotiq3fEmulator::inject_fault(int code) {
  std::lock_guard lock(mutex_);
  state_.fault = code;
}
void Robotiq3fEmulator::remove_object() {
  std::lock_guard lock(mutex_);
  options_.object = false;
}
void Robotiq3fEmulator::disconnect() {
  std::lock_guard lock(mutex_);
  disconnect_ = true;
}

Robotiq3fEmulator::State Robotiq3fEmulator::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

std::vector<Robotiq3fEmulator::CommandSeen> Robotiq3fEmulator::commands() const {
  std::lock_guard lock(mutex_);
  return {commands_.begin(), commands_.end()};
}

}  // namespace fba::emulators
