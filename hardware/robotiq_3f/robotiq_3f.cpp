// hw.robotiq_3f: the Robotiq 3-Finger Adaptive Gripper over Modbus RTU, the real twin of sim.hand
// (same ports and events, hand_ports.hpp). Each fba.Grasp becomes a pregrasp (the spread sets the
// scissor, or the mode does; the aperture sets how far the fingers open), then a close under force
// control; the grasp is held when every finger used reports an object contact (gDTx) and keeps
// reporting it for hold_time. A device fault, a silent or garbled line, a line that disappears, or a
// grasp the hand cannot make ends process() with an exception naming the device and the reason; the
// runtime then calls safe_state(): stop, then open. The safe state runs beside a process() still
// under way: the line carries one request at a time, so it takes the line between two of process()'s
// requests (a few milliseconds), and process() sends nothing after it.
#include <chrono>
#include <cmath>
#include <fba/component.hpp>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

#include "gripper.hpp"
#include "hand_ports.hpp"

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

// What one grasp asks of the device.
struct Plan {
  Mode mode = Mode::basic;
  bool individual_scissor = false;
  int open_position = 0;     // fingers A, B, C before closing
  int scissor_position = 0;  // with individual_scissor
  std::vector<int> axes;     // the axes whose contact makes the grasp: A, B, C, or the scissor alone
};

class Robotiq3f final : public fba::Component {
 public:
  static constexpr auto kGrasp = fba::hand::kGrasp;
  static constexpr auto kResult = fba::hand::kResult;
  static constexpr auto kHeld = fba::hand::kHeld;
  static constexpr auto kDropped = fba::hand::kDropped;
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
  static constexpr auto kSafeTimeout =
      fba::Param<double>("safe_state_timeout", 5, "the longest the hand may take to open in safe_state(), seconds")
          .range(0.1, 60);

  static fba::Spec spec() {
    return fba::Spec::actuator(
               "hw.robotiq_3f",
               "The Robotiq 3-Finger Adaptive Gripper over Modbus RTU (libmodbus): executes grasps as a "
               "pregrasp then a close under force control, and reports the fingers' object contacts "
               "(the twin of sim.hand).")
        .add(kGrasp, kResult, kHeld, kDropped, kDevice, kBaud, kSlave, kResponseTimeout, kRetries, kPollPeriod, kSpeed,
             kForce, kMode, kMaxAperture, kMaxSpread, kHoldTime, kActivationTimeout, kMotionTimeout, kSafeTimeout)
        .blocking()
        .concurrent_safe_state();
  }

  // Activation waits for the hand (seconds); a stop of the task ends it at once.
  explicit Robotiq3f(fba::Context& ctx)
      : ctx_(ctx), mode_(mode_named(ctx(kMode))), on_stop_(ctx.stop_token(), [this] { stop_.request_stop(); }) {
    gripper_ = std::make_unique<Gripper>(rq::LineOptions{ctx(kDevice), ctx(kBaud), ctx(kSlave), ctx(kResponseTimeout),
                                                         ctx(kRetries), stop_.get_token()});
    ctx.log().info("{}: activating ({} mode, within {} s)", gripper_->name(), ctx(kMode), ctx(kActivationTimeout));
    gripper_->activate(mode_.value_or(Mode::basic), ctx(kActivationTimeout), ctx(kPollPeriod));
    ctx.log().info("{}: activated in {} mode", gripper_->name(), ctx(kMode));
  }

  void process() override {
    const fba::Grasp& grasp = ctx_(kGrasp).get();
    const Plan plan = plan_for(grasp);
    const double poll = ctx_(kPollPeriod);

    Status s = gripper_->read("before the grasp");
    if (s.mode != plan.mode) {
      Command c = gripper_->last_command();
      c.mode = plan.mode;
      c.go = false;
      gripper_->write(c, "changing to " + std::string(rq::to_string(plan.mode)) + " mode");
      gripper_->wait_until([&](const Status& st) { return st.imc == 3 && st.mode == plan.mode; },
                           ctx_(kActivationTimeout), poll,
                           "changing to " + std::string(rq::to_string(plan.mode)) + " mode");
    }
    move(plan, plan.open_position, "pregrasp");
    s = move(plan, 255, "closing");

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

  // Refuses a grasp the hand cannot make, before anything is sent.
  Plan plan_for(const fba::Grasp& g) const {
    const std::string who = gripper_->name() + ": grasp refused before sending: ";
    const double max_aperture = ctx_(kMaxAperture), max_spread = ctx_(kMaxSpread);
    if (!std::isfinite(g.aperture) || g.aperture <= 0 || g.aperture > max_aperture)
      throw DeviceError(who + "the pregrasp aperture must be in (0, " + metres(max_aperture) +
                        "] (max_aperture), not " + metres(g.aperture));
    Plan p;
    p.open_position = static_cast<int>(std::lround(255.0 * (1.0 - g.aperture / max_aperture)));
    if (mode_) {
      p.mode = *mode_;
    } else {
      if (!std::isfinite(g.spread) || g.spread < 0 || g.spread > max_spread)
        throw DeviceError(who + "the pregrasp spread must be in [0, " + metres(max_spread) + "] (max_spread), not " +
                          metres(g.spread));
      p.individual_scissor = true;
      p.scissor_position = static_cast<int>(std::lround(255.0 * (1.0 - g.spread / max_spread)));
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
    for (int axis : {rq::kA, rq::kB, rq::kC}) c.axes[axis] = AxisRequest{position, ctx_(kSpeed), ctx_(kForce)};
    c.axes[rq::kScissor] = AxisRequest{plan.scissor_position, ctx_(kSpeed), ctx_(kForce)};
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
  // finger (A is the thumb, contacts[0]); scissor mode pinches between B and C.
  static fba::ExecutedContact contact_for(int axis, const fba::Grasp& g) {
    fba::ExecutedContact c;
    const int planned = axis == rq::kScissor ? 1 : axis;
    c.link = axis == rq::kScissor ? "scissor" : std::string("finger_") + static_cast<char>('a' + axis);
    c.position = g.contacts[planned].position;
    c.normal = g.contacts[planned].normal;
    return c;
  }

  static nlohmann::json to_json(const fba::GraspExecution& e, const nlohmann::json& fingers) {
    nlohmann::json contacts = nlohmann::json::array();
    for (const auto& c : e.contacts)
      contacts.push_back({{"link", c.link},
                          {"position", {c.position.x(), c.position.y(), c.position.z()}},
                          {"normal", {c.normal.x(), c.normal.y(), c.normal.z()}},
                          {"force", c.force}});
    return {{"held", e.held},
            {"hold_s", e.hold_s},
            {"reason", e.reason},
            {"contacts", std::move(contacts)},
            {"fingers", fingers}};
  }

  fba::Context& ctx_;
  const std::optional<Mode> mode_;  // empty: auto
  std::stop_source stop_;           // the task's stop, or interrupt(): the gripper's waits end
  std::stop_callback<std::function<void()>> on_stop_;
  std::unique_ptr<Gripper> gripper_;
};

}  // namespace

FBA_COMPONENT(Robotiq3f);
