// What a component author writes against: one class that declares its ports, parameters and
// events once, as typed constants, builds spec() from them, and reaches them through the
// Context with the same constants. Registration is one line: FBA_COMPONENT(MyFilter).
//
//   class Scale final : public fba::Component {
//    public:
//     static constexpr fba::In<std::int64_t> kIn{"in", "the integers to scale"};
//     static constexpr fba::Out<std::int64_t> kOut{"out", "each integer times factor"};
//     static constexpr auto kFactor = fba::Param<std::int64_t>("factor", 2, "the factor").range(-1000, 1000);
//     static fba::Spec spec() { return fba::Spec::filter("demo.scale", "Multiplies integers.").add(kIn, kOut, kFactor); }
//
//     explicit Scale(fba::Context& ctx) : in_(ctx(kIn)), out_(ctx(kOut)), factor_(ctx(kFactor)) {}
//     void process() override { out_.emit(in_.get() * factor_); }
//    private:
//     fba::InputOf<std::int64_t> in_;
//     fba::OutputOf<std::int64_t> out_;
//     const std::int64_t factor_;
//   };
//   FBA_COMPONENT(Scale);
//
// The handles are bound in the constructor: a handle the spec does not declare throws PluginBug
// where it is used, and fba-run --check constructs a task's filters (fba::check_construction), so
// a use there is found before anything runs; a use first made in process() is found only then.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <stop_token>
#include <string>
#include <string_view>
#include <vector>

#include <spdlog/logger.h>

#include "fba/packet.hpp"
#include "fba/spec.hpp"
#include "fba/value.hpp"

namespace fba {

namespace detail {
class Node;
struct InputState;
struct OutputState;
}  // namespace detail

// A device failed rather than the task being wrong: it never answered, reported a fault, or
// answered garbled or as another device. Thrown from a constructor (or a call), it ends the run as
// a runtime error (exit 3) naming the component, not as a configuration error (exit 2), which
// stays for the task's own mistakes.
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Component {
 public:
  virtual ~Component() = default;
  // One invocation, when the trigger policy says so. An exception stops or restarts the
  // component according to the task's error policy; it never takes the process down.
  virtual void process() = 0;
  // Every input is closed (its producers finished and nothing is left): a last chance to emit.
  virtual void end_of_stream() {}
  // Actuators: bring the device to a safe state. Called on every way out of a run.
  virtual void safe_state() {}
  // Unblock a process() that waits on a device, so that shutdown never hangs. Called from
  // another thread while process() may be running; a type declared blocking must implement it.
  virtual void interrupt() {}
};

class ThreadPool;

// An input port, untyped (AnyIn gives this one); In<T> gives an InputOf<T> over it.
class Input {
 public:
  const std::string& name() const;
  bool connected() const;
  // A sample was delivered to this input for the current invocation.
  bool has() const { return has_; }
  const Packet& packet() const {
    if (!has_) throw std::logic_error("input '" + name() + "' has no sample in this invocation");
    return current_;
  }
  template <class T>
  const T& get() const { return packet().get<T>(); }
  // Hands this invocation's sample over (to Output::forward, without touching its reference
  // count); latest() no longer holds it afterwards.
  Packet take() {
    packet();
    has_ = false;
    return std::move(current_);
  }
  // The newest sample received here, even in an earlier invocation (nullptr if none, or if it
  // was taken).
  const Packet* latest() const { return current_ ? &current_ : nullptr; }
  // The producers finished and the buffer is empty.
  bool closed() const;

 private:
  friend class detail::Node;
  friend class Output;
  detail::InputState* state_ = nullptr;
  Packet current_;  // this invocation's sample when has_, else the newest one before it
  bool has_ = false;
};

// An input of type T, from ctx(kIn): the loader has checked the connection's type already.
template <class T>
class InputOf {
 public:
  explicit InputOf(Input& in) : in_(&in) {}
  const std::string& name() const { return in_->name(); }
  bool connected() const { return in_->connected(); }
  bool has() const { return in_->has(); }
  const T& get() const { return in_->get<T>(); }
  // The sample's data, shared (to keep it beyond this invocation without a copy).
  std::shared_ptr<const T> share() const { return in_->packet().share<T>(); }
  const Packet& packet() const { return in_->packet(); }
  Packet take() { return in_->take(); }
  // The newest value received, even in an earlier invocation; nullptr if none.
  const T* latest() const {
    const Packet* p = in_->latest();
    return p ? &p->get<T>() : nullptr;
  }
  bool closed() const { return in_->closed(); }

 private:
  Input* in_;
};

// An output port, untyped (OutLike gives this one); Out<T> gives an OutputOf<T> over it.
//
// Time stamps: a sample carries the capture time of what it was made from. Unless given, the
// stamp is the newest one among the inputs taken in this invocation, or the executor's clock
// when none was (a sensor, a periodic tick, end of stream).
class Output {
 public:
  const std::string& name() const;
  // Sends a received sample on unchanged: same data, same header, no copy of the data.
  void forward(const Packet& p);
  // The same, handing the sample over: the cheapest hop (see Input::take).
  void forward(Packet&& p);
  // Stamps the packet as this output's next sample (seq, time, producer) and sends it.
  void send(Packet p, std::int64_t stamp_ns = -1);
  std::uint64_t count() const;

 private:
  friend class detail::Node;
  detail::OutputState* state_ = nullptr;
};

template <class T>
class OutputOf {
 public:
  explicit OutputOf(Output& out) : out_(&out) {}
  const std::string& name() const { return out_->name(); }
  void emit(std::shared_ptr<const T> value, std::int64_t stamp_ns = -1) {
    out_->send(Packet::make<T>(std::move(value)), stamp_ns);
  }
  void emit(T value, std::int64_t stamp_ns = -1) { emit(std::shared_ptr<const T>(std::make_shared<T>(std::move(value))), stamp_ns); }
  std::uint64_t count() const { return out_->count(); }

 private:
  Output* out_;
};

class Context {
 public:
  explicit Context(detail::Node& node) : node_(node) {}

  const std::string& name() const;
  const Spec& spec() const;

  // The component's ports and parameters, through the handles its spec was built from. A
  // handle the spec does not declare (or declares with another type) throws PluginBug.
  template <class T>
  InputOf<T> operator()(const In<T>& h) { return InputOf<T>(input(h.name, type_of<T>())); }
  template <class T>
  InputOf<T> operator()(const OptionalIn<T>& h) { return InputOf<T>(input(h.name, type_of<T>())); }
  Input& operator()(const AnyIn& h) { return input(h.name, any_type()); }
  template <class T>
  OutputOf<T> operator()(const Out<T>& h) { return OutputOf<T>(output(h.name, type_of<T>(), {})); }
  Output& operator()(const OutLike& h) { return output(h.name, any_type(), h.like); }
  template <class T>
  T operator()(const Param<T>& p) const { return params()(p); }
  ParamValues params() const;

  // Emits a declared event; the task's rules decide what it does.
  void emit(const EventOut& e, std::string payload = {});
  // Records one of the run's results under `name`, replacing an earlier one: the summary lists it
  // whole, as JSON, under the component's "results" (a grasp, the views used, a lift test), where a
  // person or a script finds it without replaying the events. `json` must be one JSON value;
  // anything else throws PluginBug.
  void report(std::string_view name, std::string json);
  // A sensor has produced its last sample.
  void finish();
  // Requested once the task is asked to stop (a signal, a stop event, a failure, a time-out), during
  // construction too: a constructor or a call that waits on a device polls it, or waits on it
  // (std::condition_variable_any, std::stop_callback), so that a stop never waits out a device's
  // time-out.
  std::stop_token stop_token() const;
  // Current time on the executor's clock (virtual under the deterministic executor).
  std::int64_t now_ns() const;
  spdlog::logger& log() const;
  // Where the run writes artefacts; empty when it writes none.
  const std::filesystem::path& output_dir() const;
  const std::filesystem::path& task_dir() const;
  // The task's threads for data-parallel work (carving, rendering): shared by every component,
  // sized like the executor, so components do not each start a thread per core.
  ThreadPool& thread_pool() const;
  // Overrides the trigger, during construction only (a counter with a rate runs periodically).
  void set_trigger(Trigger t);
  // Set by Stages; reported in summaries.
  void set_stage(const std::string& stage);

 private:
  friend class Stages;
  Input& input(std::string_view name, const TypeInfo* type);
  Output& output(std::string_view name, const TypeInfo* type, std::string_view like);
  void emit_event(std::string_view name, std::string payload);
  [[noreturn]] void plugin_bug(const std::string& what) const;
  detail::Node& node_;
};

// A component's internal stages, declared in its spec; the current one is observable as the
// event "stage" (payload: the stage's name) and in the run summary.
class Stages {
 public:
  explicit Stages(Context& ctx);
  // Moves to the next stage; throws std::logic_error for a transition the spec does not allow.
  void go(std::string_view next);
  const std::string& current() const { return current_; }

 private:
  Context& ctx_;
  std::string current_;
};

namespace detail {
struct ComponentEntry {
  Spec (*spec)();
  std::unique_ptr<Component> (*make)(Context&);
  bool implements_interrupt;  // a blocking type must (Registry::add checks)
};
template <class T>
constexpr bool overrides_interrupt() {
  return !std::is_same_v<decltype(&T::interrupt), decltype(&Component::interrupt)>;
}
// One list per shared object (hidden visibility): a plugin hands its own list to the core.
[[gnu::visibility("hidden")]] inline std::vector<ComponentEntry>& plugin_entries() {
  static std::vector<ComponentEntry> entries;
  return entries;
}
}  // namespace detail

}  // namespace fba

#define FBA_CONCAT_INNER(a, b) a##b
#define FBA_CONCAT(a, b) FBA_CONCAT_INNER(a, b)
// Registers a component class with the plugin (or test program) it is compiled into.
#define FBA_COMPONENT(T)                                                                  \
  [[maybe_unused]] static const bool FBA_CONCAT(fba_registered_, __LINE__) =             \
      (::fba::detail::plugin_entries().push_back(                                         \
           {&T::spec,                                                                     \
            [](::fba::Context& ctx) -> std::unique_ptr<::fba::Component> {                \
              return std::make_unique<T>(ctx);                                            \
            },                                                                            \
            ::fba::detail::overrides_interrupt<T>()}),                                    \
       true)
