// The Robotiq 3-Finger Adaptive Gripper's Modbus registers, as its instruction manual lays them out:
// eight command registers from 1000 (0x03E8, written with function 16) and eight status registers
// from 2000 (0x07D0, read with function 4), two bytes per register, high byte first.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace fba::robotiq {

inline constexpr int kCommandAddress = 0x03E8;
inline constexpr int kStatusAddress = 0x07D0;
inline constexpr int kRegisterCount = 8;
using Registers = std::array<std::uint16_t, kRegisterCount>;

enum class Mode { basic = 0, pinch = 1, wide = 2, scissor = 3 };
const char* to_string(Mode m);

// The four axes, in register order. Finger A is the thumb, opposing B and C; the scissor axis
// turns B and C towards or away from each other.
enum Axis { kA = 0, kB = 1, kC = 2, kScissor = 3 };
inline constexpr int kAxes = 4;
const char* axis_name(int axis);

// Position 0 is fully open, 255 fully closed; speed and force 0 (least) to 255 (most).
struct AxisRequest {
  int position = 0;
  int speed = 255;
  int force = 150;
};

struct Command {
  bool activate = false;            // rACT
  Mode mode = Mode::basic;          // rMOD
  bool go = false;                  // rGTO: move to the requested positions
  bool auto_release = false;        // rATR
  bool individual_fingers = false;  // rICF: A, B and C each follow their own request (else all follow A's)
  bool individual_scissor = false;  // rICS: the scissor follows its own request (else the mode's)
  std::array<AxisRequest, kAxes> axes;
};

// The registers for a command; throws std::out_of_range naming the field when a position, speed
// or force is outside 0..255 (nothing outside the device's range is ever sent).
Registers encode(const Command& c);

// gDTx: what each axis reports about an object.
enum class Contact { moving = 0, while_opening = 1, while_closing = 2, at_request = 3 };
const char* to_string(Contact c);

struct AxisStatus {
  int requested = 0;  // echo of the position request
  int position = 0;
  int current = 0;  // motor current, in the device's units of 10 mA
  Contact contact = Contact::moving;
};

struct Status {
  bool activated = false;   // gACT
  Mode mode = Mode::basic;  // gMOD
  bool go = false;          // gGTO
  int imc = 0;              // gIMC: 0 reset or automatic release, 1 activating, 2 changing mode, 3 ready
  int motion = 0;           // gSTA: 0 moving, 1 one or two fingers stopped early, 2 all stopped early, 3 all at request
  int fault = 0;            // gFLT
  std::array<AxisStatus, kAxes> axes;
};

Status decode(const Registers& r);

// The manual's words for a gFLT code, e.g. "0x0D activation fault, verify that no interference or
// other error occurred (major: reset required)".
std::string fault_text(int code);
// Priority and minor faults that clear by themselves (activation or a mode change in progress, the
// communication chip booting, a short scissor interference): waiting is the answer.
bool fault_is_transient(int code);

}  // namespace fba::robotiq
