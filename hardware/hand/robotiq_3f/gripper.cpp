#include "gripper.hpp"

#include <modbus.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <thread>

namespace fba::robotiq {

namespace {

using Clock = std::chrono::steady_clock;

std::string seconds_text(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%g s", s);
  return text;
}

bool line_gone(int error) {
  return error == EIO || error == ECONNRESET || error == EBADF || error == ENXIO || error == EPIPE;
}

}  // namespace

Gripper::Gripper(LineOptions options) : options_(std::move(options)) {
  name_ = "Robotiq 3-Finger gripper on " + options_.device + " (slave " + std::to_string(options_.slave) + ")";
  ctx_ = modbus_new_rtu(options_.device.c_str(), options_.baud, 'N', 8, 1);
  if (!ctx_) fail("opening the line", std::string("libmodbus refused the settings: ") + modbus_strerror(errno));
  const auto whole = static_cast<std::uint32_t>(options_.response_timeout_s);
  const auto micro = static_cast<std::uint32_t>(std::lround((options_.response_timeout_s - whole) * 1e6));
  if (modbus_set_slave(ctx_, options_.slave) != 0 || modbus_set_response_timeout(ctx_, whole, micro) != 0 ||
      modbus_set_byte_timeout(ctx_, whole, micro) != 0) {
    const std::string why = modbus_strerror(errno);
    modbus_free(ctx_);
    ctx_ = nullptr;
    fail("opening the line", "libmodbus refused the slave id or the timeouts: " + why);
  }
  if (modbus_connect(ctx_) != 0) {
    const std::string why = modbus_strerror(errno);
    modbus_free(ctx_);
    ctx_ = nullptr;
    fail("opening the line", "cannot open the serial line: " + why, DeviceError::Kind::line_gone);
  }
}

Gripper::~Gripper() {
  if (!ctx_) return;
  modbus_close(ctx_);
  modbus_free(ctx_);
}

void Gripper::fail(const std::string& doing, const std::string& reason, DeviceError::Kind kind) const {
  throw DeviceError(name_ + ": " + doing + ": " + reason, kind);
}

std::string Gripper::refused() const {
  if (taken_) return "not sent: the safe state has the line";
  if (options_.stop.stop_requested()) return "interrupted (the task is stopping)";
  return {};
}

void Gripper::transact(const std::string& what, const std::string& doing, const std::function<int()>& request,
                       bool task) {
  std::string reason;
  bool answered = false;  // by any of the tries: the gripper hears the line
  for (int attempt = 0; attempt <= options_.retries; ++attempt) {
    if (request() != -1) return;
    const int error = errno;
    if (line_gone(error))
      fail(doing, what + ": the serial line is gone (" + std::strerror(error) + ")", DeviceError::Kind::line_gone);
    answered = answered || error != ETIMEDOUT;
    if (error == ETIMEDOUT)
      reason = "no answer within " + seconds_text(options_.response_timeout_s) +
               " (Modbus timeout: the gripper is off, on another slave id or not wired)";
    else if (error == EMBBADCRC)
      reason = "the answer's CRC was wrong (noise on the line)";
    else if (error >= EMBXILFUN && error <= EMBXGTAR)
      fail(doing, what + ": the gripper answered with a Modbus exception: " + modbus_strerror(error));
    else
      reason = std::string("a garbled answer (") + modbus_strerror(error) + ")";
    // What is left of a garbled answer would spoil the next one: let it arrive, then drop it.
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    modbus_flush(ctx_);
    if (const std::string why = task ? refused() : ""; !why.empty())
      fail(doing, what + ": " + reason + "; not retried: " + why, answered ? DeviceError::Kind::device : DeviceError::Kind::no_answer);
  }
  fail(doing, what + ": " + reason + ", " + std::to_string(options_.retries + 1) + " tries",
       answered ? DeviceError::Kind::device : DeviceError::Kind::no_answer);
}

void Gripper::send_command(const Command& c, const std::string& doing, bool task) {
  Registers r;
  try {
    r = encode(c);
  } catch (const std::out_of_range& e) {
    fail(doing, std::string("command refused before sending: ") + e.what());
  }
  std::lock_guard lock(line_);
  if (const std::string why = task ? refused() : ""; !why.empty()) fail(doing, why);
  transact("writing the command registers", doing,
           [&] { return modbus_write_registers(ctx_, kCommandAddress, kRegisterCount, r.data()); }, task);
  last_ = c;
}

Status Gripper::read_status(const std::string& doing, bool task) {
  Registers r{};
  std::lock_guard lock(line_);
  if (const std::string why = task ? refused() : ""; !why.empty()) fail(doing, why);
  transact("reading the status registers", doing,
           [&] { return modbus_read_input_registers(ctx_, kStatusAddress, kRegisterCount, r.data()); }, task);
  return decode(r);
}

Command Gripper::last_command() const {
  std::lock_guard lock(line_);
  return last_;
}

void Gripper::pause(double seconds) const {
  std::mutex m;
  std::condition_variable_any cv;
  std::unique_lock lock(m);
  cv.wait_for(lock, options_.stop, std::chrono::duration<double>(seconds), [] { return false; });
}

Status Gripper::poll_until(const std::function<bool(const Status&)>& done, double timeout_s, double poll_s,
                           const std::string& doing, bool task) {
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  for (;;) {
    const Status s = read_status(doing, task);
    if (s.fault != 0 && !fault_is_transient(s.fault)) fail(doing, "the gripper reports fault " + fault_text(s.fault));
    if (done(s)) return s;
    if (Clock::now() >= deadline)
      fail(doing, "not done within " + seconds_text(timeout_s) + "; last status: " + describe(s) +
                      (s.fault ? " (" + fault_text(s.fault) + ")" : ""));
    if (task)
      pause(poll_s);  // a stop ends it; the next read says so
    else
      std::this_thread::sleep_for(std::chrono::duration<double>(poll_s));
  }
}

void Gripper::activate(Mode mode, double timeout_s, double poll_s) {
  Command c;
  write(c, "activation (reset)");
  c.activate = true;
  c.mode = mode;
  write(c, "activation");
  wait_until([](const Status& s) { return s.activated && s.imc == 3; }, timeout_s, poll_s, "activation");
}

std::string describe(const Status& s) {
  std::string text = std::string(s.activated ? "active" : "reset") + ", mode " + to_string(s.mode) + ", " +
                     (s.go ? "go" : "stopped") + ", gIMC " + std::to_string(s.imc) + ", gSTA " +
                     std::to_string(s.motion);
  for (int axis = 0; axis < kAxes; ++axis)
    text += std::string(", ") + axis_name(axis) + " " + std::to_string(s.axes[axis].position) + "/255 (" +
            to_string(s.axes[axis].contact) + ")";
  return text;
}

}  // namespace fba::robotiq
