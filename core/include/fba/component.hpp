// What a component author writes against: one class with a static spec(), a constructor
// taking the Context, and process(). Registration is one line: FBA_COMPONENT(MyFilter).
//
//   class Passthrough final : public fba::Component {
//    public:
//     static fba::Spec spec() {
//       return fba::Spec::filter("examples.passthrough", "Forwards each sample unchanged.")
//           .any_input("in", "samples to forward")
//           .output_like("out", "in", "the same samples, headers untouched");
//     }
//     explicit Passthrough(fba::Context& ctx) : in_(ctx.input("in")), out_(ctx.output("out")) {}
//     void process() override { out_.forward(in_.packet()); }
//    private:
//     fba::Input& in_;
//     fba::Output& out_;
//   };
//   FBA_COMPONENT(Passthrough);
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
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
  // Unblock a process() that waits on a device, so that shutdown never hangs.
  virtual void interrupt() {}
};

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
  template <class T>
  std::shared_ptr<const T> share() const { return packet().share<T>(); }
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
  detail::InputState* state_ = nullptr;
  Packet current_;  // this invocation's sample when has_, else the newest one before it
  bool has_ = false;
};

class Output {
 public:
  const std::string& name() const;
  template <class T>
  void emit(std::shared_ptr<const T> value, std::int64_t stamp_ns = -1) {
    send(Packet::make<T>(std::move(value)), stamp_ns);
  }
  template <class T>
  void emit(T value, std::int64_t stamp_ns = -1) {
    emit(std::shared_ptr<const T>(std::make_shared<T>(std::move(value))), stamp_ns);
  }
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

class Context {
 public:
  explicit Context(detail::Node& node) : node_(node) {}

  const std::string& name() const;
  const Spec& spec() const;
  Input& input(std::string_view name);
  Output& output(std::string_view name);

  template <class T>
  T param(std::string_view name) const {
    static_assert(is_param_type_v<T> || std::is_same_v<T, int>, "unsupported parameter type");
    if constexpr (std::is_same_v<T, int>) return static_cast<int>(std::get<std::int64_t>(value(name, ParamType::Int)));
    else return std::get<T>(value(name, param_type_of<T>()));
  }
  // A path parameter, resolved against the task file's folder.
  std::filesystem::path path(std::string_view name) const;

  // Emits a declared event; the task's rules decide what it does.
  void emit_event(std::string_view name, std::string payload = {});
  // A sensor has produced its last sample.
  void finish();
  // Current time on the executor's clock (virtual under the deterministic executor).
  std::int64_t now_ns() const;
  spdlog::logger& log() const;
  // Where the run writes artefacts; empty when it writes none.
  const std::filesystem::path& output_dir() const;
  const std::filesystem::path& task_dir() const;
  // Overrides the trigger, during construction only (a counter with a rate runs periodically).
  void set_trigger(Trigger t);
  // Set by Stages; reported in summaries.
  void set_stage(const std::string& stage);

 private:
  const Value& value(std::string_view name, ParamType expected) const;
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
};
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
            }}),                                                                          \
       true)
