// A component type's interface, declared once: the single source of truth for load-time
// checking, fba-inspect, the DOT picture, documentation and the test harness.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fba/packet.hpp"  // the built-in data types ports may use
#include "fba/value.hpp"

namespace fba {

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
  std::string doc;
  bool required() const { return !default_value.has_value(); }
};

struct EventSpec {
  std::string name;
  std::string doc;
};

class Spec {
 public:
  static Spec sensor(std::string type_name, std::string doc) { return Spec(Kind::Sensor, std::move(type_name), std::move(doc)); }
  static Spec filter(std::string type_name, std::string doc) { return Spec(Kind::Filter, std::move(type_name), std::move(doc)); }
  static Spec actuator(std::string type_name, std::string doc) { return Spec(Kind::Actuator, std::move(type_name), std::move(doc)); }
  static Spec composite(std::string type_name, std::string doc) { return Spec(Kind::Composite, std::move(type_name), std::move(doc)); }

  template <class T>
  Spec& input(std::string name, std::string doc) { return input(std::move(name), type_of<T>(), std::move(doc)); }
  Spec& input(std::string name, const TypeInfo* type, std::string doc);
  template <class T>
  Spec& optional_input(std::string name, std::string doc) { input<T>(std::move(name), std::move(doc)); inputs_.back().required = false; return *this; }
  Spec& any_input(std::string name, std::string doc) { return input(std::move(name), any_type(), std::move(doc)); }

  template <class T>
  Spec& output(std::string name, std::string doc) { return output(std::move(name), type_of<T>(), std::move(doc)); }
  Spec& output(std::string name, const TypeInfo* type, std::string doc);
  // An output whose type is whatever the named input is connected to.
  Spec& output_like(std::string name, std::string input_name, std::string doc);

  template <class T>
  Spec& param(std::string name, T default_value, std::string doc) {
    return param(std::move(name), param_type_of<T>(), Value(std::move(default_value)), std::move(doc));
  }
  Spec& param(std::string name, const char* default_value, std::string doc) { return param<std::string>(std::move(name), default_value, std::move(doc)); }
  Spec& param(std::string name, int default_value, std::string doc) { return param<std::int64_t>(std::move(name), default_value, std::move(doc)); }
  Spec& param(std::string name, ParamType type, std::optional<Value> default_value, std::string doc);
  template <class T>
  Spec& required_param(std::string name, std::string doc) { return param(std::move(name), param_type_of<T>(), std::nullopt, std::move(doc)); }
  Spec& path_param(std::string name, std::optional<std::string> default_value, std::string doc);
  // Constraints on the parameter declared last.
  Spec& range(std::optional<double> min, std::optional<double> max);
  Spec& choices(std::vector<std::string> allowed);

  Spec& event(std::string name, std::string doc);
  // Declares the component's stages and allowed transitions (first stage is the initial one);
  // adds the event "stage", emitted on every transition with the new stage as payload.
  Spec& stages(std::vector<std::string> names, std::vector<std::pair<std::string, std::string>> transitions);
  Spec& trigger(Trigger t) { trigger_ = t; return *this; }
  // The component may block in process() (device I/O): it gets a thread of its own.
  Spec& blocking() { blocking_ = true; return *this; }

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

  const PortSpec* find_input(std::string_view name) const;
  const PortSpec* find_output(std::string_view name) const;
  const ParamSpec* find_param(std::string_view name) const;
  const EventSpec* find_event(std::string_view name) const;

  // Throws std::logic_error when the declaration contradicts itself (a sensor with a required
  // input, a default outside its range, a duplicate name...). Checked when a plugin registers.
  void validate() const;

 private:
  Spec(Kind kind, std::string type_name, std::string doc);
  ParamSpec& last_param(const char* what);

  Kind kind_;
  std::string type_name_;
  std::string doc_;
  std::vector<PortSpec> inputs_, outputs_;
  std::vector<ParamSpec> params_;
  std::vector<EventSpec> events_;
  std::vector<std::string> stage_names_;
  std::vector<std::pair<std::string, std::string>> transitions_;
  Trigger trigger_;
  bool blocking_ = false;
};

}  // namespace fba
