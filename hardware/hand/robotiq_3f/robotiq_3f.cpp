// hw.robotiq_3f: the Robotiq 3-Finger Adaptive Gripper over Modbus RTU, the real twin of sim.hand
// (same ports and events, hand_ports.hpp). Each fba.Grasp becomes a pregrasp (the spread sets the
// scissor, or the mode does; the aperture sets how far the fingers open), then a close under force
// control; the grasp is held when every finger used reports an object contact (gDTx) and keeps
// reporting it for hold_time. A device fault, a silent or garbled line, a line that disappears, or a
// grasp the hand cannot make ends process() with an exception naming the device and the reason; the
// runtime then calls safe_state(): stop, then open. The safe state runs beside a process() still
// under way: the line carries one request at a time, so it takes the line between two of process()'s
// requests (a few milliseconds), and process() sends nothing after it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <fba/component.hpp>
#include <fba/types/grasp_execution_json.hpp>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

#include "grip_force.hpp"
#include "gripper.hpp"
#include "hand_ports.hpp"
#include "launcher.hpp"

namespace {

using fba::robotiq::AxisRequest;
using fba::robotiq::Command;
using fba::robotiq::Contact;
using fba::robotiq::DeviceError;
using fba::robotiq::Gripper;
using fba::robotiq::Mode;
using fba::robotiq::Status;
namespace rq = fba::robotiq;

std::optional<Mode> mode_named(const std::string& name) {
  for (Mode m : {Mode::basic, Mode::pinch, Mode::wide, Mode::scissor})
    if (name == rq::to_string(m)) return m;
  return std::nullopt;  // "auto"
}

std::string metres(double m) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g m", m);
  return text;
}

std::string seconds(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g s", s);
  return text;
}

// What one grasp asks of the device.
struct Plan {
  Mode mode = Mode::basic;
  bool individual_scissor = false;
  int open_position = 0;     // fingers A, B, C before closing
  int scissor_position = 0;  // with individual_scissor
  int force = 150;           // 0..255
  std::vector<int> axes;     // the axes whose contact makes the grasp: A, B, C, or the scissor alone
};

const char* action_name(fba::HandCommand::Action a) { return a == fba::HandCommand::Action::Close ? "close" : "open"; }

// A command's grasping mode as the gripper's; empty: basic mode with the scissor set from the
// spread (individual scissor control), as the 'mode' parameter's auto.
std::optional<Mode> mode_of(fba::HandCommand::Mode m) {
  switch (m) {
    case fba::HandCommand::Mode::Basic:
      return std::nullopt;
    case fba::HandCommand::Mode::Pinch:
      return Mode::pinch;
    case fba::HandCommand::Mode::Wide:
      return Mode::wide;
    case fba::HandCommand::Mode::Scissor:
      return Mode::scissor;
  }
  return std::nullopt;
}

class Robotiq3f final : public fba::Component {
 public:
  static constexpr auto kGrasp = fba::hand::kGrasp;
  static constexpr auto kResult = fba::hand::kResult;
  static constexpr auto kHeld = fba::hand::kHeld;
  static constexpr auto kDropped = fba::hand::kDropped;
  static constexpr auto kCommands = fba::hand::kCommands;
  static constexpr auto kTrajectory = fba::hand::kTrajectory;
  static constexpr fba::Param<std::string> kDevice{"device", fba::required,
                                                   "the serial line of the gripper, e.g. /dev/ttyUSB0"};
  static constexpr auto kBaud =
      fba::Param<int>("baud", 115200, "the line's speed, bit/s (8N1); the gripper's default is 115200")
          .range(1200, 4000000);
  static constexpr auto kSlave =
      fba::Param<int>("slave_id", 9, "the gripper's Modbus slave id (default 9)").range(1, 247);
  static constexpr auto kResponseTimeout =
      fba::Param<double>("response_timeout", 0.5, "how long to wait for each answer, seconds").range(0.01, 10);
  static constexpr auto kRetries =
      fba::Param<int>("retries", 2,
                      "requests repeated after a timeout or a garbled answer before the device counts as failed")
          .range(0, 10);
  static constexpr auto kPollPeriod =
      fba::Param<double>("poll_period", 0.05, "status polling period while waiting, seconds").range(0.005, 1);
  static constexpr auto kSpeed =
      fba::Param<int>("speed", 255, "finger speed, 0 (22 mm/s) to 255 (110 mm/s)").range(0, 255);
  static constexpr auto kForce = fba::Param<int>("force", 150, "closing force, 0 (15 N) to 255 (60 N)").range(0, 255);
  static constexpr auto kMode =
      fba::Param<std::string>(
          "mode", "auto",
          "grasping mode: basic, pinch, wide or scissor (the mode places the scissor), or auto: basic "
          "mode with the scissor set from each grasp's spread (individual scissor control)")
          .choices({"auto", "basic", "pinch", "wide", "scissor"});
  static constexpr auto kMaxAperture =
      fba::Param<double>("max_aperture", 0.155,
                         "thumb-to-fingers opening with the fingers at position 0 (fully open), metres; "
                         "positions scale linearly to 0 at 255")
          .range(0.01, 1);
  static constexpr auto kMaxSpread =
      fba::Param<double>("max_spread", 0.12,
                         "distance between fingers B and C with the scissor at 0 (apart), metres; it "
                         "scales linearly to 0 at 255")
          .range(0.01, 1);
  static constexpr auto kHoldTime =
      fba::Param<double>("hold_time", 0.5,
                         "how long every finger must keep its contact for the grasp to count as held, seconds")
          .range(0, 60);
  static constexpr auto kActivationTimeout =
      fba::Param<double>("activation_timeout", 30, "the longest activation or mode change, seconds").range(0.1, 120);
  static constexpr auto kMotionTimeout =
      fba::Param<double>("motion_timeout", 10, "the longest pregrasp or close, seconds").range(0.1, 120);
  static constexpr fba::Param<std::string> kEmulator{
      "emulator", "",
      "an emulator program, with its options, started when the device does not exist or does not answer: it "
      "plays the gripper on a pseudo-terminal linked at the device's path and is stopped at the end (the emulated "
      "profile: fba-robotiq-3f-emulator); empty: never"};
  static constexpr auto kSafeTimeout =
      fba::Param<double>("safe_state_timeout", 5, "the longest the hand may take to open in safe_state(), seconds")
          .range(0.1, 60);

  static fba::Spec spec() {
    return fba::Spec::actuator(
               "hw.robotiq_3f",
               "The Robotiq 3-Finger Adaptive Gripper over Modbus RTU (libmodbus): executes grasps as a "
               "pregrasp then a close under force control, and reports the fingers' object contacts "
               "(the twin of sim.hand).")
        .add(kGrasp, kCommands, kTrajectory, kResult, kHeld, kDropped, kDevice, kBaud, kSlave, kResponseTimeout, kRetries, kPollPeriod, kSpeed,
             kForce, kMode, kMaxAperture, kMaxSpread, kHoldTime, kActivationTimeout, kMotionTimeout, kSafeTimeout, kEmulator)
        .blocking()
        .concurrent_safe_state();
  }

  // Activation waits for the hand (seconds); a stop of the task ends it at once. A gripper that
  // fails to start is a device error, reset (rACT = 0) when it still hears the line.
  explicit Robotiq3f(fba::Context& ctx)
      : ctx_(ctx),
        mode_(mode_named(ctx(kMode))),
        commanded_(ctx(kCommands).connected()),
        timed_(ctx(kTrajectory).connected()),
        on_stop_(ctx.stop_token(), [this] { stop_.request_stop(); }) {
    try {
      try {
        start(ctx);
      } catch (const DeviceError& e) {
        // Nothing there, or nothing answering: the emulator, when one is configured, and never in
        // place of a real device (only where nothing is, or a symbolic link).
        const bool absent = e.kind == DeviceError::Kind::line_gone || e.kind == DeviceError::Kind::no_answer;
        if (ctx(kEmulator).empty() || !absent || ctx.stop_token().stop_requested() ||
            !fba::emulators::free_for_emulator(ctx(kDevice)))
          throw;
        ctx.log().info("{}; starting the emulator: {}", e.what(), ctx(kEmulator));
        gripper_.reset();
        emulator_.emplace(ctx(kEmulator), ctx(kDevice), ctx.stop_token());
        ctx.log().info("{}: played by {} (pid {})", ctx(kDevice), emulator_->program(), emulator_->pid());
        start(ctx);
      }
    } catch (const DeviceError& e) {
      if (ctx.stop_token().stop_requested()) throw;  // the task is stopping: an interrupted start
      throw fba::DeviceError(std::string(e.what()) + reset_after_failed_start(e));
    } catch (const std::runtime_error& e) {  // the emulator did not start
      if (ctx.stop_token().stop_requested()) throw;
      throw fba::DeviceError("hw.robotiq_3f on " + ctx(kDevice) + ": " + e.what());
    }
    ctx.log().info("{}: activated in {} mode{}", gripper_->name(), ctx(kMode),
                   commanded_ ? "; it follows a reach plan's commands" : "");
  }

  void process() override {
    if (auto in = ctx_(kTrajectory); in.has()) {
      trajectory_ns_ = ctx_.now_ns();  // the trajectory's time 0, as for the arm it went to
      ctx_.log().info("{}: the arm's trajectory ({:.2f} s) arrived: the commands' times count from now",
                      gripper_->name(), in.get().points.empty() ? 0.0 : in.get().points.back().time);
    }
    if (commanded_) {
      if (auto in = ctx_(kCommands); in.has()) run(in.get());
      return;  // a grasp alone only names the contacts a close reports
    }
    if (auto in = ctx_(kGrasp); in.has()) execute(in.get());
  }

  void interrupt() override { stop_.request_stop(); }

  // Stop (rGTO = 0), then open; a hand with a fault that needs a reset stays stopped. Beside a
  // process() still running: its request on the line finishes first (without retries), then it
  // sends nothing more.
  void safe_state() override {
    Gripper::SafeState line(*gripper_);
    Command c = line.last_command();
    c.go = false;
    line.write(c, "safe state (stop)");
    const Status s = line.read("safe state");
    if (!s.activated || (s.fault != 0 && !rq::fault_is_transient(s.fault))) {
      ctx_.log().warn("{}: safe state: stopped, not opened ({})", gripper_->name(),
                      s.activated ? "fault " + rq::fault_text(s.fault) : "the gripper is not activated");
      return;
    }
    c.go = true;
    c.individual_fingers = c.mode != Mode::scissor;  // in scissor mode A's request opens the scissor
    for (int axis : {rq::kA, rq::kB, rq::kC}) c.axes[axis] = AxisRequest{0, ctx_(kSpeed), ctx_(kForce)};
    line.write(c, "safe state (open)");
    line.wait_until([&](const Status& st) { return echoed(st, c) && st.motion != 0; }, ctx_(kSafeTimeout),
                    ctx_(kPollPeriod), "safe state (open)");
    ctx_.log().info("{}: safe state: stopped and opened", gripper_->name());
  }

 private:
  // Opens the line and activates the gripper.
  void start(fba::Context& ctx) {
    gripper_ = std::make_unique<Gripper>(rq::LineOptions{ctx(kDevice), ctx(kBaud), ctx(kSlave), ctx(kResponseTimeout),
                                                         ctx(kRetries), stop_.get_token()});
    ctx.log().info("{}: activating ({} mode, within {} s)", gripper_->name(), ctx(kMode), ctx(kActivationTimeout));
    gripper_->activate(mode_.value_or(Mode::basic), ctx(kActivationTimeout), ctx(kPollPeriod));
  }

  // A grasp on its own: the pregrasp, the close, the verdict.
  void execute(const fba::Grasp& grasp) {
    const Plan plan = plan_for(grasp.aperture, grasp.spread, mode_, ctx_(kForce), "grasp");
    change_mode(plan);
    move(plan, plan.open_position, "pregrasp");
    verdict(plan, move(plan, 255, "closing"), &grasp);
  }

  // A reach plan's command at its time on the arm's trajectory: waits for it (a stop ends the
  // wait), then opens or closes; a close ends in the verdict. The command's opening and spread are
  // mapped as a grasp's aperture and spread are (the positions over max_aperture and max_spread),
  // its force over the gripper's 15..60 N, its mode as the 'mode' parameter's (basic: the scissor
  // from the spread, individual scissor control).
  void run(const fba::HandCommand& c) {
    const std::string what = std::string(action_name(c.action)) + " at " + seconds(c.time) + " on the trajectory";
    if (timed_) {
      if (!trajectory_ns_)
        throw DeviceError(gripper_->name() + ": hand command (" + what +
                          ") before any trajectory: its time counts from the trajectory's arrival");
      const std::int64_t due = *trajectory_ns_ + static_cast<std::int64_t>(std::llround(c.time * 1e9));
      if (const std::int64_t wait = due - ctx_.now_ns(); wait > 0) gripper_->pause(static_cast<double>(wait) * 1e-9);
      if (gripper_->stopping()) return;  // the task is stopping: the safe state follows
      const double late = static_cast<double>(ctx_.now_ns() - due) * 1e-9;
      ctx_.log().info("{}: {}{}", gripper_->name(), what, late > 0.05 ? " (" + seconds(late) + " late)" : "");
    } else {
      ctx_.log().info("{}: {} (run as it arrived: no trajectory connected)", gripper_->name(), what);
    }
    const bool close = c.action == fba::HandCommand::Action::Close;
    int force = ctx_(kForce);
    if (close) {
      const double grip = rq::grip_force(c.force);
      force = std::clamp(static_cast<int>(std::lround(255.0 * (grip - rq::kMinForce) / (rq::kMaxForce - rq::kMinForce))), 0, 255);
      if (grip != c.force)
        ctx_.log().warn("{}: a close with {} N: the gripper pushes with {} to {} N, so with {} N", gripper_->name(),
                        c.force, rq::kMinForce, rq::kMaxForce, grip);
    }
    const Plan plan = plan_for(c.opening, c.spread, mode_of(c.mode), force, "hand command (" + what + ")");
    change_mode(plan);
    if (!close) {
      move(plan, plan.open_position, "opening (" + what + ")");
      return;
    }
    verdict(plan, move(plan, 255, "closing (" + what + ")"), ctx_(kGrasp).latest());
  }

  // The gripper's failed start: reset (rACT = 0) when it hears the line, so that whatever it was
  // doing (activating, a fault) stops. Returns what happened, for the message.
  std::string reset_after_failed_start(const DeviceError& e) {
    if (!gripper_ || e.kind == DeviceError::Kind::line_gone) return "";  // nothing to send it on
    if (e.kind == DeviceError::Kind::no_answer) return "; it never answered, so nothing was sent to stop it";
    try {
      Gripper::SafeState line(*gripper_);
      line.write(Command{}, "reset after the failed start");
      ctx_.log().info("{}: reset (rACT = 0) after the failed start", gripper_->name());
      return "; the gripper was reset (rACT = 0): stopped";
    } catch (const DeviceError& x) {
      if (x.kind == DeviceError::Kind::device)  // it heard it; what came back could not be read
        return std::string("; the gripper was sent a reset (rACT = 0), its answer unreadable: ") + x.what();
      return std::string("; resetting it failed too: ") + x.what();
    }
  }

  void change_mode(const Plan& plan) {
    const Status s = gripper_->read("before the grasp");
    if (s.mode == plan.mode) return;
    Command c = gripper_->last_command();
    c.mode = plan.mode;
    c.go = false;
    const std::string doing = "changing to " + std::string(rq::to_string(plan.mode)) + " mode";
    gripper_->write(c, doing);
    gripper_->wait_until([&](const Status& st) { return st.imc == 3 && st.mode == plan.mode; }, ctx_(kActivationTimeout),
                         ctx_(kPollPeriod), doing);
  }

  // After a close: held when every finger used stopped on the object and keeps its contact for
  // hold_time; the result, the report and the event. `grasp`: the planned contacts, if known.
  void verdict(const Plan& plan, Status s, const fba::Grasp* grasp) {
    fba::GraspExecution result;
    nlohmann::json fingers = nlohmann::json::array();
    std::string missing;
    for (int axis : plan.axes)
      if (s.axes[axis].contact != Contact::while_closing)
        missing += std::string(missing.empty() ? "" : ", ") + rq::axis_name(axis);
    if (!missing.empty()) {
      result.reason = count_contacts(s, plan) == 0
                          ? "no contact: the fingers closed without touching anything (" + rq::describe(s) + ")"
                          : "no contact on " + missing + " (" + rq::describe(s) + ")";
    } else {
      hold(plan, s, result);
    }
    result.held = result.reason.empty();
    for (int axis : plan.axes)
      if (s.axes[axis].contact == Contact::while_closing) result.contacts.push_back(contact_for(axis, grasp));
    for (int axis = 0; axis < rq::kAxes; ++axis)
      fingers.push_back({{"axis", rq::axis_name(axis)},
                         {"position", s.axes[axis].position},
                         {"requested", s.axes[axis].requested},
                         {"current", s.axes[axis].current},
                         {"object", rq::to_string(s.axes[axis].contact)}});
    result.stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
    ctx_.log().info("{}: {}{}", gripper_->name(), result.held ? "held" : "not held",
                    result.reason.empty() ? "" : ": " + result.reason);
    const std::string json = to_json(result, fingers).dump();
    ctx_.report("lift", json);  // the field's ground truth for "the grasp works"
    ctx_.emit(result.held ? kHeld : kDropped, json);
    ctx_(kResult).emit(std::move(result));
  }

  // The device's answer is about our command once it echoes the requested positions.
  static bool echoed(const Status& s, const Command& c) {
    if (!s.go) return false;
    for (int axis : {rq::kA, rq::kB, rq::kC}) {
      if (s.axes[axis].requested != c.axes[axis].position) return false;
      if (!c.individual_fingers) break;  // all follow A's request
    }
    return true;
  }

  static int count_contacts(const Status& s, const Plan& plan) {
    int n = 0;
    for (int axis : plan.axes) n += s.axes[axis].contact == Contact::while_closing;
    return n;
  }

  // What the gripper does for an aperture (thumb to fingers, m) and a spread (B to C, m) in a mode
  // (empty: basic mode, the scissor from the spread under individual scissor control), closing with
  // `force` (0..255): positions linear over the hand's stroke, max_aperture at 0 and closed at 255,
  // the scissor max_spread at 0 and together at 255. Refuses what the hand cannot make, before
  // anything is sent; `what` names it ("grasp", or the hand command).
  Plan plan_for(double aperture, double spread, std::optional<Mode> mode, int force, const std::string& what) const {
    const std::string who = gripper_->name() + ": " + what + " refused before sending: ";
    const bool grasp = what == "grasp";
    const double max_aperture = ctx_(kMaxAperture), max_spread = ctx_(kMaxSpread);
    if (!std::isfinite(aperture) || aperture <= 0 || aperture > max_aperture)
      throw DeviceError(who + (grasp ? "the pregrasp aperture" : "the opening") + " must be in (0, " +
                        metres(max_aperture) + "] (max_aperture), not " + metres(aperture));
    Plan p;
    p.force = force;
    p.open_position = static_cast<int>(std::lround(255.0 * (1.0 - aperture / max_aperture)));
    if (mode) {
      p.mode = *mode;
    } else {
      if (!std::isfinite(spread) || spread < 0 || spread > max_spread)
        throw DeviceError(who + (grasp ? "the pregrasp spread" : "the spread") + " must be in [0, " + metres(max_spread) +
                          "] (max_spread), not " + metres(spread));
      p.individual_scissor = true;
      p.scissor_position = static_cast<int>(std::lround(255.0 * (1.0 - spread / max_spread)));
    }
    if (p.mode == Mode::scissor) {  // B and C pinch: the scissor opens fully, then closes
      p.axes = {rq::kScissor};
      p.open_position = 0;
    } else {
      p.axes = {rq::kA, rq::kB, rq::kC};
    }
    return p;
  }

  // Moves the fingers (A, B and C, or in scissor mode the scissor through A's request) to
  // `position` and waits until they stop, at the request or on contact.
  Status move(const Plan& plan, int position, const std::string& doing) {
    Command c;
    c.activate = true;
    c.mode = plan.mode;
    c.go = true;
    c.individual_fingers = plan.mode != Mode::scissor;  // in scissor mode A's request drives the scissor
    c.individual_scissor = plan.individual_scissor;
    for (int axis : {rq::kA, rq::kB, rq::kC}) c.axes[axis] = AxisRequest{position, ctx_(kSpeed), plan.force};
    c.axes[rq::kScissor] = AxisRequest{plan.scissor_position, ctx_(kSpeed), plan.force};
    gripper_->write(c, doing);
    return gripper_->wait_until([&](const Status& s) { return echoed(s, c) && s.motion != 0; }, ctx_(kMotionTimeout),
                                ctx_(kPollPeriod), doing);
  }

  // Every finger must keep its contact for hold_time.
  void hold(const Plan& plan, Status& s, fba::GraspExecution& result) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    const auto held_for = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
    while (held_for() < ctx_(kHoldTime)) {
      gripper_->pause(ctx_(kPollPeriod));
      s = gripper_->read("holding");  // after a stop: "interrupted"
      if (s.fault != 0 && !rq::fault_is_transient(s.fault))
        throw DeviceError(gripper_->name() + ": holding: the gripper reports fault " + rq::fault_text(s.fault));
      for (int axis : plan.axes)
        if (s.axes[axis].contact != Contact::while_closing) {
          char text[160];
          std::snprintf(text, sizeof text, "dropped: finger %s lost its contact after %.2f s of the hold (%s, %d/255)",
                        rq::axis_name(axis), held_for(), rq::to_string(s.axes[axis].contact), s.axes[axis].position);
          result.reason = text;
          result.hold_s = held_for();
          return;
        }
    }
    result.hold_s = held_for();
  }

  // The gripper cannot tell where it touched: a contact is reported at the planned contact of that
  // finger (A is the thumb, contacts[0]); scissor mode pinches between B and C. Without a grasp (a
  // reach plan's close with no grasp connected), at the origin.
  static fba::ExecutedContact contact_for(int axis, const fba::Grasp* g) {
    fba::ExecutedContact c;
    const int planned = axis == rq::kScissor ? 1 : axis;
    c.link = axis == rq::kScissor ? "scissor" : std::string("finger_") + static_cast<char>('a' + axis);
    if (g && static_cast<std::size_t>(planned) < g->contacts.size()) {
      c.position = g->contacts[planned].position;
      c.normal = g->contacts[planned].normal;
    }
    return c;
  }

  static nlohmann::json to_json(const fba::GraspExecution& e, const nlohmann::json& fingers) {
    nlohmann::json out = fba::grasp_execution_json(e);
    out["fingers"] = fingers;
    return out;
  }

  fba::Context& ctx_;
  const std::optional<Mode> mode_;  // empty: auto
  const bool commanded_;            // a reach plan's commands drive the hand, not the grasps
  const bool timed_;                // the commands' times count from the trajectory's arrival
  std::optional<std::int64_t> trajectory_ns_;  // when the last trajectory arrived, on the task's clock
  std::stop_source stop_;           // the task's stop, or interrupt(): the gripper's waits end
  std::stop_callback<std::function<void()>> on_stop_;
  // The emulator this driver started, if any: stopped after the line (declared first, gone last).
  std::optional<fba::emulators::LaunchedEmulator> emulator_;
  std::unique_ptr<Gripper> gripper_;
};

}  // namespace

FBA_COMPONENT(Robotiq3f);
