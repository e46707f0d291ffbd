// A Robotiq 3-Finger gripper on a Modbus RTU line (libmodbus): commands, status, and the waits of a
// grasp, each bounded in time, each failure a DeviceError that names the device and the reason. The
// task's requests and a safe state's may come from two threads at once.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <stop_token>
#include <string>

#include "registers.hpp"

typedef struct _modbus modbus_t;

namespace fba::robotiq {

class DeviceError : public std::runtime_error {
 public:
  // What failed: the gripper answered (wrongly, garbled, or with a fault) and so hears commands; it
  // did not answer at all; or the line is gone.
  enum class Kind { device, no_answer, line_gone };
  explicit DeviceError(const std::string& what, Kind kind_ = Kind::device) : std::runtime_error(what), kind(kind_) {}
  Kind kind;
};

struct LineOptions {
  std::string device;  // the serial line, e.g. /dev/ttyUSB0
  int baud = 115200;   // 8N1
  int slave = 9;
  double response_timeout_s = 0.5;  // per request
  int retries = 2;                  // after a timeout or a garbled answer; a line that is gone is not retried
  std::stop_token stop;             // requested: the task's requests and waits end at once (not the safe state's)
};

// The line carries one request at a time: every request holds it for its exchange (and its retries)
// only, so a request from another thread goes out between two of a wait's polls.
class Gripper {
 public:
  explicit Gripper(LineOptions options);  // opens the line; throws DeviceError
  ~Gripper();
  Gripper(const Gripper&) = delete;
  Gripper& operator=(const Gripper&) = delete;

  // "Robotiq 3-Finger gripper on /dev/ttyUSB0 (slave 9)": how every message names the device.
  const std::string& name() const { return name_; }

  // The task's requests. Each fails at once, without going out, once the stop is requested ("interrupted
  // (the task is stopping)") or the safe state has the line; a request in flight then gets no retry.
  // `doing` says what for, in messages: "closing", "activation"...
  void write(const Command& c, const std::string& doing) { send_command(c, doing, true); }
  Status read(const std::string& doing) { return read_status(doing, true); }
  Command last_command() const;

  // Polls the status every `poll_s` until `done` says so. Throws DeviceError when the device reports
  // a fault that does not clear by itself, when `timeout_s` passes (with the last status), or at
  // once when the stop is requested.
  Status wait_until(const std::function<bool(const Status&)>& done, double timeout_s, double poll_s,
                    const std::string& doing) {
    return poll_until(done, timeout_s, poll_s, doing, true);
  }
  // Resets (rACT = 0), activates in `mode` and waits until gIMC = 3; ends at once on a stop.
  void activate(Mode mode, double timeout_s, double poll_s);
  // Waits `seconds`, less when the stop is requested meanwhile.
  void pause(double seconds) const;
  bool stopping() const { return options_.stop.stop_requested(); }

  // The safe state's hold on the line, from any thread, beside the task's requests: from its
  // construction on, the task's requests fail (the one in flight finishes, without retries) and
  // its own go out, stop or not.
  class SafeState {
   public:
    explicit SafeState(Gripper& g) : g_(g) { g_.taken_ = true; }
    void write(const Command& c, const std::string& doing) { g_.send_command(c, doing, false); }
    Status read(const std::string& doing) { return g_.read_status(doing, false); }
    Status wait_until(const std::function<bool(const Status&)>& done, double timeout_s, double poll_s,
                      const std::string& doing) {
      return g_.poll_until(done, timeout_s, poll_s, doing, false);
    }
    Command last_command() const { return g_.last_command(); }

   private:
    Gripper& g_;
  };

 private:
  [[noreturn]] void fail(const std::string& doing, const std::string& reason,
                         DeviceError::Kind kind = DeviceError::Kind::device) const;
  // Why a request of the task must not go out (or be retried) now; empty when it may.
  std::string refused() const;
  void send_command(const Command& c, const std::string& doing, bool task);
  Status read_status(const std::string& doing, bool task);
  Status poll_until(const std::function<bool(const Status&)>& done, double timeout_s, double poll_s,
                    const std::string& doing, bool task);
  // Runs one request with the retries, the line held; `request` returns libmodbus's result (-1 and
  // errno on failure). A task's request is not retried once refused() says so.
  void transact(const std::string& what, const std::string& doing, const std::function<int()>& request, bool task);

  LineOptions options_;
  std::string name_;
  modbus_t* ctx_ = nullptr;
  mutable std::mutex line_;  // one request at a time; guards ctx_ and last_
  Command last_;
  std::atomic<bool> taken_{false};  // the safe state has the line
};

// One line of status for messages and logs: "imc 3, motion 2, fault 0x00, A 188/255 contact closing, ...".
std::string describe(const Status& s);

}  // namespace fba::robotiq
