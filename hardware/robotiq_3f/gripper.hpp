// A Robotiq 3-Finger gripper on a Modbus RTU line (libmodbus): commands, status, and the waits of a
// grasp, each bounded in time, each failure a DeviceError that names the device and the reason.
#pragma once

#include <atomic>
#include <functional>
#include <stdexcept>
#include <string>

#include "registers.hpp"

typedef struct _modbus modbus_t;

namespace fba::robotiq {

class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LineOptions {
  std::string device;  // the serial line, e.g. /dev/ttyUSB0
  int baud = 115200;   // 8N1
  int slave = 9;
  double response_timeout_s = 0.5;  // per request
  int retries = 2;                  // after a timeout or a garbled answer; a line that is gone is not retried
};

class Gripper {
 public:
  explicit Gripper(LineOptions options);  // opens the line; throws DeviceError
  ~Gripper();
  Gripper(const Gripper&) = delete;
  Gripper& operator=(const Gripper&) = delete;

  // "Robotiq 3-Finger gripper on /dev/ttyUSB0 (slave 9)": how every message names the device.
  const std::string& name() const { return name_; }

  // `doing` says what for, in messages: "closing", "activation"...
  void write(const Command& c, const std::string& doing);
  Status read(const std::string& doing);
  const Command& last_command() const { return last_; }

  // Polls the status every `poll_s` until `done` says so. Throws DeviceError when the device reports
  // a fault that does not clear by itself, when `timeout_s` passes (with the last status), or when
  // `interrupted` becomes true.
  Status wait_until(const std::function<bool(const Status&)>& done, double timeout_s, double poll_s,
                    const std::string& doing, const std::atomic<bool>* interrupted = nullptr);

  // Resets (rACT = 0), activates in `mode` and waits until gIMC = 3.
  void activate(Mode mode, double timeout_s, double poll_s, const std::atomic<bool>* interrupted = nullptr);

 private:
  [[noreturn]] void fail(const std::string& doing, const std::string& reason) const;
  // Runs one request with the retries; `request` returns libmodbus's result (-1 and errno on failure).
  void transact(const std::string& what, const std::string& doing, const std::function<int()>& request);

  LineOptions options_;
  std::string name_;
  modbus_t* ctx_ = nullptr;
  Command last_;
};

// One line of status for messages and logs: "imc 3, motion 2, fault 0x00, A 188/255 contact closing, ...".
std::string describe(const Status& s);

}  // namespace fba::robotiq
