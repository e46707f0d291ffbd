// A component type's interface, declared once: the single source of truth for load-time
// checking, fba-inspect, the DOT picture, documentation and the test harness.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fba/packet.hpp"  // the built-in data types ports may use
#include "fba/value.hpp"

namespace fba {

class Spec;

// Names of ports, parameters, events and components: letters, digits and '_'.
bool is_valid_name(std::string_view name);

enum class Kind { Sensor, Filter, Actuator, Composite };
const char* to_string(Kind k);

enum class TriggerPolicy {
  Any,       // run when any input has a new sample
  All,       // run when every input has a new sample with the same time stamp
  Periodic,  // run every period, with whatever is new on the inputs
  Free,      // run whenever the outputs have room (sensors)
};
const char* to_string(TriggerPolicy p);

struct Trigger {
  TriggerPolicy policy = TriggerPolicy::Any;
  double period_s = 0.0;  // Periodic only
};

struct PortSpec {
  std::string name;
  const TypeInfo* type = nullptr;  // any_type() for a wildcard input
  std::string same_as;             // outputs: the type follows this input's resolved type
  bool required = true;            // inputs: must be connected
  std::string doc;
};

struct ParamSpec {
  std::string name;
  ParamType type = ParamType::Int;
  std::optional<Value> default_value;  // none: the task must set it
  std::optional<double> min, max;      // numbers, and every element of a list
  std::vector<std::string> choices;    // strings
  std::vector<std::size_t> sizes;      // lists: the allowed lengths; empty: any
  std::string doc;
  bool required() const { return !default_value.has_value(); }
};

struct EventSpec {
  std::string name;
  std::string doc;
};

// A mistake in a component's code rather than in a task file: reading a parameter, port or
// event its spec does not declare, or with another type. Names the plugin file and the type.
class PluginBug : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

// ---------------------------------------------------------------------------------------------
// Handles: a port, parameter or event declared once, as a typed constant of the component
// class, then used both to build spec() and to reach it through the Context, so that the name
// is written once and a type mismatch between declaration and use does not compile.
//
//   static constexpr fba::In<std::int64_t> kIn{"in", "the integers"};
//   static constexpr fba::Out<std::int64_t> kOut{"out", "each integer times factor"};
//   static constexpr auto kFactor = fba::Param<std::int64_t>("factor", 2, "the factor").range(-1000, 1000);

namespace detail {
// What a port or event handle holds; the handle's own type says what kind it is.
struct NameAndDoc {
  constexpr NameAndDoc(std::string_view name, std::string_view doc) : name(name), doc(doc) {}
  std::string_view name, doc;
};
}  // namespace detail

// An input of type T; get() returns const T&.
template <class T>
struct In : detail::NameAndDoc {
  using NameAndDoc::NameAndDoc;
};
// An input of type T the task may leave unconnected (a sensor's inputs are all optional).
template <class T>
struct OptionalIn : detail::NameAndDoc {
  using NameAndDoc::NameAndDoc;
};
// An input of any type: the connection decides (examples.passthrough).
struct AnyIn : detail::NameAndDoc {
  using NameAndDoc::NameAndDoc;
};
template <class T>
struct Out : detail::NameAndDoc {
  using NameAndDoc::NameAndDoc;
};
// An output whose type is whatever `like` is connected to.
struct OutLike {
  constexpr OutLike(std::string_view name, const AnyIn& like, std::string_view doc) : name(name), like(like.name), doc(doc) {}
  std::string_view name, like, doc;
};
// An event the component emits; the task's rules decide what it does.
struct EventOut : detail::NameAndDoc {
  using NameAndDoc::NameAndDoc;
};

namespace detail {
// How a parameter of C++ type T is stored in a task (ParamType) and held in a handle.
template <class T>
struct ParamTraits;
template <>
struct ParamTraits<bool> { static constexpr ParamType type = ParamType::Bool; using Held = bool; };
template <>
struct ParamTraits<std::int64_t> { static constexpr ParamType type = ParamType::Int; using Held = std::int64_t; };
// Stored as a task's int; the loader keeps it within int's range.
template <>
struct ParamTraits<int> { static constexpr ParamType type = ParamType::Int; using Held = int; };
template <>
struct ParamTraits<double> { static constexpr ParamType type = ParamType::Double; using Held = double; };
template <>
struct ParamTraits<std::string> { static constexpr ParamType type = ParamType::String; using Held = std::string_view; };
// Resolved against the task file's folder.
template <>
struct ParamTraits<std::filesystem::path> { static constexpr ParamType type = ParamType::Path; using Held = std::string_view; };
template <>
struct ParamTraits<std::vector<double>> { static constexpr ParamType type = ParamType::DoubleList; using Held = std::vector<double>; };
}  // namespace detail

struct RequiredTag {
  explicit constexpr RequiredTag(int) {}  // not from {}: Param("x", {}, "doc") is an empty default
};
// A parameter without a default: every task must set it.
inline constexpr RequiredTag required{0};

// A parameter read as T: bool, std::int64_t, int, double, std::string, std::filesystem::path
// (resolved against the task file's folder) or std::vector<double>. constexpr except lists
// (use `static inline const`).
template <class T>
class Param {
 public:
  using Held = typename detail::ParamTraits<T>::Held;
  static constexpr ParamType type = detail::ParamTraits<T>::type;

  constexpr Param(std::string_view name, Held default_value, std::string_view doc)
      : name(name), doc(doc), default_value(std::move(default_value)) {}
  constexpr Param(std::string_view name, RequiredTag, std::string_view doc) : name(name), doc(doc) {}

  // Numbers, and every element of a list, must lie in [min, max].
  constexpr Param range(std::optional<double> lo, std::optional<double> hi) const {
    Param p = *this;
    p.min = lo;
    p.max = hi;
    return p;
  }
  constexpr Param at_least(double lo) const { return range(lo, std::nullopt); }
  // Strings: the allowed values.
  constexpr Param choices(std::initializer_list<std::string_view> allowed) const {
    static_assert(std::is_same_v<T, std::string>, "choices() is for string parameters");
    Param p = *this;
    p.n_choices = 0;
    for (auto c : allowed) p.choice[p.n_choices++] = c;
    return p;
  }
  // Lists: the allowed lengths (e.g. {0, 6}: empty or six numbers).
  constexpr Param size(std::initializer_list<std::size_t> allowed) const {
    static_assert(std::is_same_v<T, std::vector<double>>, "size() is for list parameters");
    Param p = *this;
    p.n_sizes = 0;
    for (auto n : allowed) p.sizes[p.n_sizes++] = n;
    return p;
  }

  ParamSpec spec() const {
    ParamSpec p;
    p.name = std::string(name);
    p.type = type;
    if (default_value) p.default_value = to_value(*default_value);
    p.min = min;
    p.max = max;
    if constexpr (std::is_same_v<T, int>) {  // the loader refuses what an int cannot hold
      constexpr double lo = std::numeric_limits<int>::min(), hi = std::numeric_limits<int>::max();
      p.min = min ? std::max(*min, lo) : lo;
      p.max = max ? std::min(*max, hi) : hi;
    }
    for (std::size_t i = 0; i < n_choices; ++i) p.choices.emplace_back(choice[i]);
    p.sizes.assign(sizes.begin(), sizes.begin() + n_sizes);
    p.doc = std::string(doc);
    return p;
  }

  std::string_view name, doc;
  std::optional<Held> default_value;
  std::optional<double> min, max;
  std::array<std::string_view, 16> choice{};
  std::size_t n_choices = 0;
  std::array<std::size_t, 4> sizes{};
  std::size_t n_sizes = 0;

 private:
  static Value to_value(const Held& v) {
    if constexpr (std::is_same_v<Held, std::string_view>) return Value(std::string(v));
    else if constexpr (std::is_same_v<T, int>) return Value(static_cast<std::int64_t>(v));
    else return Value(v);
  }
};

// Resolved parameter values, read through the handles (a spec's checks get one).
class ParamValues {
 public:
  ParamValues(const Spec& spec, const std::map<std::string, Value>& values, std::string_view origin)
      : spec_(spec), values_(values), origin_(origin) {}
  template <class T>
  T operator()(const Param<T>& p) const {
    const Value& v = value(p.name, Param<T>::type);
    if constexpr (std::is_same_v<T, int>) return static_cast<int>(std::get<std::int64_t>(v));
    else if constexpr (std::is_same_v<T, std::filesystem::path>) return std::filesystem::path(std::get<std::string>(v));
    else return std::get<T>(v);
  }

 private:
  const Value& value(std::string_view name, ParamType type) const;  // throws PluginBug
  const Spec& spec_;
  const std::map<std::string, Value>& values_;
  std::string_view origin_;
};

// A check of the resolved parameters, run by the loader (so `fba-run --check` sees it): an
// empty string when they are fine, else what is wrong. A plain function, not a closure: a spec
// outlives nothing of its plugin's code but may outlive the plugin being mapped.
using CheckFn = std::string (*)(const ParamValues&);

struct ParamCheck {
  std::string param;     // reported at this parameter (empty: the component)
  CheckFn check = nullptr;
  const char* op = nullptr;  // or a comparison: param op other, "<" or "<="
  std::string other;
};

// Cross-parameter checks of numbers: `.add(kMinElevation <= kMaxElevation)`.
template <class A, class B>
ParamCheck operator<=(const Param<A>& a, const Param<B>& b) {
  static_assert(std::is_arithmetic_v<A> && std::is_arithmetic_v<B>, "only numbers compare");
  return {std::string(a.name), nullptr, "<=", std::string(b.name)};
}
template <class A, class B>
ParamCheck operator<(const Param<A>& a, const Param<B>& b) {
  static_assert(std::is_arithmetic_v<A> && std::is_arithmetic_v<B>, "only numbers compare");
  return {std::string(a.name), nullptr, "<", std::string(b.name)};
}

class Spec {
 public:
  static Spec sensor(std::string type_name, std::string doc) { return Spec(Kind::Sensor, std::move(type_name), std::move(doc)); }
  static Spec filter(std::string type_name, std::string doc) { return Spec(Kind::Filter, std::move(type_name), std::move(doc)); }
  static Spec actuator(std::string type_name, std::string doc) { return Spec(Kind::Actuator, std::move(type_name), std::move(doc)); }
  static Spec composite(std::string type_name, std::string doc) { return Spec(Kind::Composite, std::move(type_name), std::move(doc)); }

  // Declares the handles, in the order given: Spec::filter("t", "doc").add(kIn, kOut, kFactor).
  template <class... H>
  Spec& add(const H&... handles) {
    (add_one(handles), ...);
    return *this;
  }

  // Untyped declarations, for composites (whose interface comes from YAML).
  Spec& input(std::string name, const TypeInfo* type, std::string doc, bool required = true);
  Spec& output(std::string name, const TypeInfo* type, std::string doc);
  Spec& param(std::string name, ParamType type, std::optional<Value> default_value, std::string doc);
  Spec& range(std::optional<double> min, std::optional<double> max);  // of the parameter declared last
  Spec& event(std::string name, std::string doc);

  // A general check of the resolved parameters: a message when they are wrong, else "".
  // A captureless lambda will do: `.check(kBounds, [](const fba::ParamValues& p) { ... })`.
  Spec& check(CheckFn fn) { return add(ParamCheck{{}, fn, nullptr, {}}); }
  template <class T>
  Spec& check(const Param<T>& at, CheckFn fn) { return add(ParamCheck{std::string(at.name), fn, nullptr, {}}); }

  // Declares the component's stages and allowed transitions (first stage is the initial one);
  // adds the event "stage", emitted on every transition with the new stage as payload.
  Spec& stages(std::vector<std::string> names, std::vector<std::pair<std::string, std::string>> transitions);
  Spec& trigger(Trigger t) { trigger_ = t; return *this; }
  // The component may block in process() (device I/O): it gets a thread of its own, and must
  // implement Component::interrupt() (checked when it registers).
  Spec& blocking() { blocking_ = true; return *this; }
  // Actuators: safe_state() may run while process() runs (a quick stop is a bus message of its
  // own, sent beside the motion), so a stop calls it at once instead of after process() returns.
  // The component then guards what process() and safe_state() share.
  Spec& concurrent_safe_state() { concurrent_safe_state_ = true; return *this; }

  Kind kind() const { return kind_; }
  const std::string& type_name() const { return type_name_; }
  const std::string& doc() const { return doc_; }
  const std::vector<PortSpec>& inputs() const { return inputs_; }
  const std::vector<PortSpec>& outputs() const { return outputs_; }
  const std::vector<ParamSpec>& params() const { return params_; }
  const std::vector<EventSpec>& events() const { return events_; }
  const std::vector<std::string>& stage_names() const { return stage_names_; }
  const std::vector<std::pair<std::string, std::string>>& transitions() const { return transitions_; }
  const Trigger& default_trigger() const { return trigger_; }
  bool is_blocking() const { return blocking_; }
  bool has_concurrent_safe_state() const { return concurrent_safe_state_; }

  const PortSpec* find_input(std::string_view name) const;
  const PortSpec* find_output(std::string_view name) const;
  const ParamSpec* find_param(std::string_view name) const;
  const EventSpec* find_event(std::string_view name) const;

  // Throws std::logic_error when the declaration contradicts itself (a sensor with a required
  // input, a default outside its range, a duplicate name...). Checked when a plugin registers.
  void validate() const;

  struct Problem {
    std::string param;  // the parameter it is about; empty: the component
    std::string message;
  };
  // Runs the declared checks (list lengths, then the ParamChecks in order) on a complete set of
  // resolved values; `origin` names the plugin in plugin-bug messages.
  std::vector<Problem> check_params(const std::map<std::string, Value>& values, std::string_view origin = {}) const;

 private:
  Spec(Kind kind, std::string type_name, std::string doc);

  template <class T>
  void add_one(const In<T>& h) { input(std::string(h.name), type_of<T>(), std::string(h.doc)); }
  template <class T>
  void add_one(const OptionalIn<T>& h) { input(std::string(h.name), type_of<T>(), std::string(h.doc), false); }
  void add_one(const AnyIn& h) { input(std::string(h.name), any_type(), std::string(h.doc)); }
  template <class T>
  void add_one(const Out<T>& h) { output(std::string(h.name), type_of<T>(), std::string(h.doc)); }
  void add_one(const OutLike& h);
  template <class T>
  void add_one(const Param<T>& h) { params_.push_back(h.spec()); }
  void add_one(const EventOut& h) { event(std::string(h.name), std::string(h.doc)); }
  void add_one(ParamCheck c) { checks_.push_back(std::move(c)); }

  Kind kind_;
  std::string type_name_;
  std::string doc_;
  std::vector<PortSpec> inputs_, outputs_;
  std::vector<ParamSpec> params_;
  std::vector<EventSpec> events_;
  std::vector<ParamCheck> checks_;
  std::vector<std::string> stage_names_;
  std::vector<std::pair<std::string, std::string>> transitions_;
  Trigger trigger_;
  bool blocking_ = false;
  bool concurrent_safe_state_ = false;
};

}  // namespace fba
