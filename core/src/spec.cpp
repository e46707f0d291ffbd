#include "fba/spec.hpp"

#include <algorithm>
#include <cctype>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "find_named.hpp"

namespace fba {

const char* to_string(Kind k) {
  switch (k) {
    case Kind::Sensor: return "sensor";
    case Kind::Filter: return "filter";
    case Kind::Actuator: return "actuator";
    case Kind::Composite: return "composite";
  }
  return "?";
}

const char* to_string(TriggerPolicy p) {
  switch (p) {
    case TriggerPolicy::Any: return "any";
    case TriggerPolicy::All: return "all";
    case TriggerPolicy::Periodic: return "periodic";
    case TriggerPolicy::Free: return "free";
  }
  return "?";
}

Spec::Spec(Kind kind, std::string type_name, std::string doc)
    : kind_(kind), type_name_(std::move(type_name)), doc_(std::move(doc)) {
  trigger_.policy = kind == Kind::Sensor ? TriggerPolicy::Free : TriggerPolicy::Any;
}

Spec& Spec::input(std::string name, const TypeInfo* type, std::string doc, bool required) {
  inputs_.push_back(PortSpec{std::move(name), type, {}, required, std::move(doc)});
  return *this;
}

Spec& Spec::output(std::string name, const TypeInfo* type, std::string doc) {
  outputs_.push_back(PortSpec{std::move(name), type, {}, true, std::move(doc)});
  return *this;
}

void Spec::add_one(const OutLike& h) {
  outputs_.push_back(PortSpec{std::string(h.name), any_type(), std::string(h.like), true, std::string(h.doc)});
}

Spec& Spec::param(std::string name, ParamType type, std::optional<Value> default_value, std::string doc) {
  ParamSpec p;
  p.name = std::move(name);
  p.type = type;
  p.default_value = std::move(default_value);
  p.doc = std::move(doc);
  params_.push_back(std::move(p));
  return *this;
}

Spec& Spec::range(std::optional<double> min, std::optional<double> max) {
  if (params_.empty()) throw std::logic_error(type_name_ + ": range() given before any parameter");
  params_.back().min = min;
  params_.back().max = max;
  return *this;
}

Spec& Spec::event(std::string name, std::string doc) {
  events_.push_back(EventSpec{std::move(name), std::move(doc)});
  return *this;
}

Spec& Spec::stages(std::vector<std::string> names, std::vector<std::pair<std::string, std::string>> transitions) {
  stage_names_ = std::move(names);
  transitions_ = std::move(transitions);
  return event("stage", "the component entered another stage; payload: the stage's name");
}

const PortSpec* Spec::find_input(std::string_view name) const { return find_named(inputs_, name); }
const PortSpec* Spec::find_output(std::string_view name) const { return find_named(outputs_, name); }
const ParamSpec* Spec::find_param(std::string_view name) const { return find_named(params_, name); }
const EventSpec* Spec::find_event(std::string_view name) const { return find_named(events_, name); }

const Value& ParamValues::value(std::string_view name, ParamType type) const {
  const ParamSpec* ps = spec_.find_param(name);
  const std::string where = "plugin bug in " + std::string(origin_.empty() ? "?" : origin_) + " (type '" + spec_.type_name() + "'): ";
  if (!ps) throw PluginBug(where + "reads parameter '" + std::string(name) + "', which its spec does not declare");
  if (ps->type != type)
    throw PluginBug(where + "reads parameter '" + std::string(name) + "' as " + to_string(type) + "; its spec declares " +
                    to_string(ps->type));
  auto it = values_.find(ps->name);
  if (it == values_.end()) throw std::logic_error("parameter '" + ps->name + "' has no value");  // the loader fills every one
  return it->second;
}

namespace {
double number(const std::map<std::string, Value>& values, const std::string& name) {
  const Value& v = values.at(name);
  if (const auto* i = std::get_if<std::int64_t>(&v)) return static_cast<double>(*i);
  return std::get<double>(v);
}
}  // namespace

std::vector<Spec::Problem> Spec::check_params(const std::map<std::string, Value>& values, std::string_view origin) const {
  std::vector<Problem> problems;
  for (const auto& p : params_) {
    auto it = values.find(p.name);
    if (p.sizes.empty() || it == values.end()) continue;
    const auto* list = std::get_if<std::vector<double>>(&it->second);
    if (!list || std::find(p.sizes.begin(), p.sizes.end(), list->size()) != p.sizes.end()) continue;
    std::vector<std::string> allowed;
    for (auto n : p.sizes) allowed.push_back(std::to_string(n));
    problems.push_back({p.name, fmt::format("parameter '{}' must have {} numbers; found {}", p.name, fmt::join(allowed, " or "),
                                            list->size())});
  }
  if (!problems.empty()) return problems;  // the checks may rely on the lengths
  const ParamValues view(*this, values, origin);
  for (const auto& c : checks_) {
    if (c.check) {
      if (std::string message = c.check(view); !message.empty()) problems.push_back({c.param, std::move(message)});
      continue;
    }
    const double x = number(values, c.param), y = number(values, c.other);
    const bool ok = std::string_view(c.op) == "<" ? x < y : x <= y;
    if (!ok) problems.push_back({c.param, fmt::format("parameter '{}' ({}) must be {} parameter '{}' ({})", c.param, x, c.op, c.other, y)});
  }
  return problems;
}

bool is_valid_name(std::string_view name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

void Spec::validate() const {
  auto fail = [this](const std::string& what) { throw std::logic_error("type '" + type_name_ + "': " + what); };
  if (type_name_.empty() || type_name_.find_first_of(" \t/") != std::string::npos) fail("a type name needs no spaces or '/'");
  std::set<std::string> names;
  for (const auto* list : {&inputs_, &outputs_})
    for (const auto& p : *list) {
      if (!is_valid_name(p.name)) fail("port name '" + p.name + "' must be letters, digits and '_'");
      if (!names.insert(p.name).second) fail("port '" + p.name + "' declared twice");
      if (!p.type) fail("port '" + p.name + "' has no type");
    }
  for (const auto& p : outputs_) {
    if (!p.same_as.empty() && !find_input(p.same_as))
      fail("output '" + p.name + "' follows the type of input '" + p.same_as + "', which is not declared");
    if (p.same_as.empty() && p.type == any_type()) fail("output '" + p.name + "' needs a type (or is an OutLike)");
  }
  if (kind_ == Kind::Sensor)
    for (const auto& p : inputs_)
      if (p.required) fail("a sensor's inputs must be optional ('" + p.name + "' is required)");
  if (kind_ == Kind::Sensor && outputs_.empty()) fail("a sensor needs at least one output");
  if (kind_ == Kind::Filter && (inputs_.empty() || outputs_.empty())) fail("a filter needs inputs and outputs");
  // An actuator may report its device's state (an arm's joints) on outputs; it is the kind told to go safe.
  if (kind_ == Kind::Actuator && inputs_.empty()) fail("an actuator needs inputs (the commands it acts on)");
  if (kind_ != Kind::Actuator && concurrent_safe_state_) fail("concurrent_safe_state() is for actuators: only they have a safe state");
  std::set<std::string> pnames;
  for (const auto& p : params_) {
    if (!is_valid_name(p.name)) fail("parameter name '" + p.name + "' must be letters, digits and '_'");
    if (!pnames.insert(p.name).second) fail("parameter '" + p.name + "' declared twice");
    if (p.default_value) {
      const Value& v = *p.default_value;
      auto in_range = [&](double x) { return (!p.min || x >= *p.min) && (!p.max || x <= *p.max); };
      if (auto* i = std::get_if<std::int64_t>(&v); i && !in_range(static_cast<double>(*i))) fail("default of '" + p.name + "' is out of its range");
      if (auto* d = std::get_if<double>(&v); d && !in_range(*d)) fail("default of '" + p.name + "' is out of its range");
      if (auto* l = std::get_if<std::vector<double>>(&v); l && !p.sizes.empty() &&
                                                          std::find(p.sizes.begin(), p.sizes.end(), l->size()) == p.sizes.end())
        fail("default of '" + p.name + "' has a length its size() does not allow");
      if (auto* s = std::get_if<std::string>(&v); s && !p.choices.empty()) {
        bool ok = false;
        for (auto& c : p.choices) ok |= c == *s;
        if (!ok) fail("default of '" + p.name + "' is not one of its choices");
      }
    }
  }
  std::set<std::string> enames{"error", "finished"};
  for (const auto& e : events_) {
    if (!is_valid_name(e.name)) fail("event name '" + e.name + "' must be letters, digits and '_'");
    if (!enames.insert(e.name).second) fail("event '" + e.name + "' declared twice (or a built-in: error, finished)");
  }
  for (const auto& [a, b] : transitions_) {
    bool fa = false, fb = false;
    for (auto& s : stage_names_) { fa |= s == a; fb |= s == b; }
    if (!fa || !fb) fail("transition " + a + " -> " + b + " names an undeclared stage");
  }
  for (const auto& c : checks_)
    for (const auto* n : {&c.param, &c.other})
      if (!n->empty() && !find_param(*n)) fail("a check is about parameter '" + *n + "', which is not declared");
  if (trigger_.policy == TriggerPolicy::Periodic && !(trigger_.period_s > 0)) fail("a periodic trigger needs a period > 0");
}

}  // namespace fba
