// A Robotiq 3-Finger Adaptive Gripper emulator: a Modbus RTU server (libmodbus) on one end of a serial
// line, with the gripper's command registers (1000, function 16) and status registers (2000, functions
// 3 and 4), activation, grasping modes, individual finger and scissor control, finger motion at the
// commanded speed, and an object that stops the fingers it touches (object detection per finger).
// Written from the gripper's manual, not from the driver in hardware/hand/robotiq_3f, so the driver's tests
// against it check both readings of the manual.
//
// The object's section in the fingers' plane is an ellipse: `object_width` from the thumb's side to
// the fingers', `object_length` along the spread (B to C; 0: the width, an upright cylinder), its
// centre `object_offset` from the hand's centre towards the thumb (finger A). A bottle grasped with B
// and C along its height is long in that direction, a can held across is round. A finger at position p (0 open,
// 255 closed) is (max_aperture / 2) (1 - p / 255) from the centre; fingers B and C are spread sideways
// by the scissor (max_spread (1 - s / 255) apart), so a spread wider than the object passes beside it.
//
// With `stall_aperture`, the object is simpler: every finger stalls where the aperture (thumb to
// fingers) is that wide, as on an object of that width held anywhere along the fingers.
//
// Faults can be injected while it runs: it stops answering, sends bad CRCs, puts noise on the line,
// reports a fault code, drops the object, or closes the line (a pulled cable).
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "fba/can/fd.hpp"

typedef struct _modbus modbus_t;
struct _modbus_mapping_t;

namespace fba::emulators {

struct Robotiq3fOptions {
  int slave_id = 9;
  double activation_s = 1.0;    // how long activation takes
  bool activates = true;        // false: activation starts and never ends (gIMC stays 1)
  double speed_scale = 1.0;     // the fingers' speed as a share of the real hand's (slow: long motions)
  double max_aperture = 0.155;  // metres, thumb to fingers, fully open
  double max_spread = 0.12;     // metres, finger B to finger C, scissor at 0
  bool object = true;
  double object_width = 0.06;  // metres
  double object_length = 0.0;  // metres; 0: object_width
  double object_offset = 0.0;  // metres, towards the thumb
  // > 0: instead of the ellipse, every finger (A, B and C) stalls on the object where the thumb and
  // the fingers are this far apart, whatever the spread: an object the grasp holds.
  double stall_aperture = 0.0;  // metres
};

class Robotiq3fEmulator {
 public:
  // `line`: the emulator's end (a pseudo-terminal's master); `name` names it in messages.
  Robotiq3fEmulator(can::Fd line, std::string name, Robotiq3fOptions options);
  ~Robotiq3fEmulator();
  Robotiq3fEmulator(const Robotiq3fEmulator&) = delete;
  Robotiq3fEmulator& operator=(const Robotiq3fEmulator&) = delete;

  // Answers requests and moves the fingers until stop() or the line is gone. Returns why it ended:
  // "stopped", "disconnected (fault injection)", or the line's error.
  std::string run();
  void stop() { stop_ = true; }

  // Fault injection, safe from any thread; acted on by run() within a few milliseconds.
  void silence();               // answers nothing from now on
  void corrupt_replies(int n);  // the next n answers carry a wrong CRC (-1: every answer)
  void inject_garbage();        // noise on the line before the next answer
  void inject_fault(int code);  // gFLT = code; motion stops until a reset and activation clear it
  void remove_object();         // the object slips out: fingers in contact close on to their request
  void disconnect();            // closes the line

  // For tests.
  struct Axis {
    double position = 0;  // 0..255
    int request = 0, speed = 0, force = 0;
    int contact = 0;  // gDTx
  };
  struct State {
    bool activated = false;
    int mode = 0;
    bool go = false;
    int imc = 0;
    int fault = 0;
    std::array<Axis, 4> axes;
    std::uint64_t requests = 0;  // requests answered
  };
  State state() const;
  // A command as it arrived, with the gripper's state just before: the order in which a driver's
  // commands reached the hand, and what the fingers were doing then.
  struct CommandSeen {
    std::array<std::uint16_t, 8> registers{};  // from 1000 (0x03E8), as written
    State before;
    std::chrono::steady_clock::time_point when;  // when it arrived, to order it against another device's records
    bool go() const { return (registers[0] >> 8) & 0x08; }
    int request_a() const { return registers[1] & 0xFF; }  // byte 3: finger A's (or all fingers') position
  };
  static constexpr std::size_t kCommandsKept = 1024;
  std::vector<CommandSeen> commands() const;  // oldest first, the last kCommandsKept

 private:
  void handle(const std::uint8_t* request, int length);
  void apply_command(const std::array<std::uint16_t, 8>& registers);
  void update(std::chrono::steady_clock::time_point now);
  std::array<std::uint16_t, 8> status_registers() const;
  void send_corrupted(const std::uint8_t* request);

  can::Fd line_;
  std::string name_;
  Robotiq3fOptions options_;
  modbus_t* ctx_ = nullptr;
  _modbus_mapping_t* mapping_ = nullptr;

  mutable std::mutex mutex_;  // guards the state and the fault requests below
  State state_;
  std::array<std::uint16_t, 8> command_{};
  std::deque<CommandSeen> commands_;
  double activation_left_ = 0;
  bool individual_fingers_ = false, individual_scissor_ = false;
  bool silent_ = false, disconnect_ = false;
  int corrupt_ = 0, garbage_ = 0;
  std::chrono::steady_clock::time_point last_update_;
  std::atomic<bool> stop_{false};
};

}  // namespace fba::emulators
