#include "fba/component.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "graph.hpp"

namespace fba {

using detail::Node;

const std::string& Input::name() const { return state_->spec->name; }
bool Input::connected() const { return state_->buffer != nullptr; }
bool Input::closed() const { return state_->closed(); }

const std::string& Output::name() const { return state_->spec->name; }
std::uint64_t Output::count() const { return state_->next_seq; }

namespace {
void check_type(const detail::OutputState& s, const Packet& p) {
  if (p.type() != s.type)
    throw std::logic_error("output '" + s.producer + "' carries '" + s.type->name + "' but was given '" +
                           (p.type() ? p.type()->name : std::string("nothing")) + "'");
}
void deliver(detail::OutputState& s, Packet&& p) {
  const std::size_t n = s.consumers.size();
  for (std::size_t i = 0; i < n; ++i) {
    detail::Buffer* b = s.consumers[i];
    if (i + 1 < n) b->push(Packet(p));
    else b->push(std::move(p));  // the last consumer takes it over: no reference-count traffic
    if (b->consumer) s.node->graph.notify(b->consumer);
  }
}
}  // namespace

void Output::send(Packet p, std::int64_t stamp_ns) {
  auto& s = *state_;
  check_type(s, p);
  Header& h = p.header();
  h.seq = s.next_seq++;
  h.stamp_ns = stamp_ns >= 0 ? stamp_ns : s.node->graph.now_ns();
  h.producer = &s.producer;
  deliver(s, std::move(p));
}

void Output::forward(const Packet& p) { forward(Packet(p)); }

void Output::forward(Packet&& p) {
  auto& s = *state_;
  check_type(s, p);
  ++s.next_seq;
  deliver(s, std::move(p));
}

const std::string& Context::name() const { return node_.config.name; }
const Spec& Context::spec() const { return node_.spec; }

Input& Context::input(std::string_view name) {
  for (std::size_t i = 0; i < node_.input_states.size(); ++i)
    if (node_.input_states[i]->spec->name == name) return node_.inputs[i];
  throw std::logic_error("component type '" + node_.spec.type_name() + "' declares no input '" + std::string(name) + "'");
}

Output& Context::output(std::string_view name) {
  for (std::size_t i = 0; i < node_.output_states.size(); ++i)
    if (node_.output_states[i]->spec->name == name) return node_.outputs[i];
  throw std::logic_error("component type '" + node_.spec.type_name() + "' declares no output '" + std::string(name) + "'");
}

const Value& Context::value(std::string_view name, ParamType expected) const {
  const ParamSpec* ps = node_.spec.find_param(name);
  if (!ps)
    throw std::logic_error("component type '" + node_.spec.type_name() + "' declares no parameter '" + std::string(name) + "'");
  const bool compatible = ps->type == expected || (ps->type == ParamType::Path && expected == ParamType::String);
  if (!compatible)
    throw std::logic_error("parameter '" + std::string(name) + "' of '" + node_.spec.type_name() + "' is " +
                           to_string(ps->type) + ", read as " + to_string(expected));
  auto it = node_.config.params.find(std::string(name));
  if (it == node_.config.params.end())
    throw std::logic_error("parameter '" + std::string(name) + "' has no value");  // the loader fills every one
  return it->second;
}

std::filesystem::path Context::path(std::string_view name) const {
  return std::get<std::string>(value(name, ParamType::String));
}

void Context::emit_event(std::string_view name, std::string payload) {
  if (!node_.spec.find_event(name) && name != "error" && name != "finished")
    throw std::logic_error("component type '" + node_.spec.type_name() + "' declares no event '" + std::string(name) + "'");
  node_.emit_event(name, std::move(payload));
}

void Context::finish() { node_.finish_requested = true; }
std::int64_t Context::now_ns() const { return node_.graph.now_ns(); }
spdlog::logger& Context::log() const { return *node_.logger; }
const std::filesystem::path& Context::output_dir() const { return node_.graph.options.output_dir; }
const std::filesystem::path& Context::task_dir() const { return node_.graph.task_dir; }

void Context::set_trigger(Trigger t) {
  if (!node_.constructing) throw std::logic_error("set_trigger is only allowed in a component's constructor");
  // Periods become int64 nanoseconds: the task files' limit, so that no deadline can wrap around.
  if (t.policy == TriggerPolicy::Periodic && !(t.period_s > 0 && t.period_s <= 1e9))
    throw std::invalid_argument(fmt::format("a periodic trigger's period must be in (0, 1000000000] seconds; found {}", t.period_s));
  node_.trigger = t;
}

void Context::set_stage(const std::string& stage) {
  std::lock_guard lock(node_.stage_mutex);
  node_.stage = stage;
}

Stages::Stages(Context& ctx) : ctx_(ctx) {
  const auto& names = ctx.spec().stage_names();
  if (names.empty()) throw std::logic_error("type '" + ctx.spec().type_name() + "' declares no stages");
  current_ = names.front();
  ctx_.set_stage(current_);
}

void Stages::go(std::string_view next) {
  const auto& tr = ctx_.spec().transitions();
  const bool allowed = std::any_of(tr.begin(), tr.end(), [&](const auto& t) { return t.first == current_ && t.second == next; });
  if (!allowed)
    throw std::logic_error("type '" + ctx_.spec().type_name() + "' allows no transition from stage '" + current_ +
                           "' to '" + std::string(next) + "'");
  current_ = std::string(next);
  ctx_.set_stage(current_);
  ctx_.emit_event("stage", current_);
}

}  // namespace fba
