#include "fba/component.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

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
  s.node->emitted_in_call.store(true, std::memory_order_relaxed);
  const std::size_t n = s.consumers.size();
  for (std::size_t i = 0; i < n; ++i) {
    detail::Buffer* b = s.consumers[i];
    if (i + 1 < n) b->push(Packet(p));
    else b->push(std::move(p));  // the last consumer takes it over: no reference-count traffic
    if (b->consumer) s.node->graph.notify(b->consumer);
  }
}

// A filter's output carries the capture time of what this invocation took in: the newest stamp
// among its inputs; none taken (a tick, end of stream): now. A sensor captures now.
std::int64_t default_stamp(const Node& n) {
  if (n.is_sensor) return n.graph.now_ns();
  std::int64_t stamp = -1;
  for (const Input& in : n.inputs)
    if (in.has()) stamp = std::max(stamp, in.packet().header().stamp_ns);
  return stamp >= 0 ? stamp : n.graph.now_ns();
}
}  // namespace

void Output::send(Packet p, std::int64_t stamp_ns) {
  auto& s = *state_;
  check_type(s, p);
  Header& h = p.header();
  h.seq = s.next_seq++;
  h.stamp_ns = stamp_ns >= 0 ? stamp_ns : default_stamp(*s.node);
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

void Context::plugin_bug(const std::string& what) const {
  throw PluginBug("plugin bug in " + node_.config.type->origin + " (type '" + node_.spec.type_name() + "'): " + what);
}

Input& Context::input(std::string_view name, const TypeInfo* type) {
  for (std::size_t i = 0; i < node_.input_states.size(); ++i) {
    const PortSpec& ps = *node_.input_states[i]->spec;
    if (ps.name != name) continue;
    if (ps.type != type)
      plugin_bug("uses input '" + ps.name + "' as '" + type->name + "'; its spec declares '" + ps.type->name + "'");
    return node_.inputs[i];
  }
  plugin_bug("uses input '" + std::string(name) + "', which its spec does not declare");
}

Output& Context::output(std::string_view name, const TypeInfo* type, std::string_view like) {
  for (std::size_t i = 0; i < node_.output_states.size(); ++i) {
    const PortSpec& ps = *node_.output_states[i]->spec;
    if (ps.name != name) continue;
    if (ps.type != type || ps.same_as != like)
      plugin_bug("uses output '" + ps.name + "' with another type than its spec declares");
    return node_.outputs[i];
  }
  plugin_bug("uses output '" + std::string(name) + "', which its spec does not declare");
}

ParamValues Context::params() const { return ParamValues(node_.spec, node_.config.params, node_.config.type->origin); }

void Context::emit(const EventOut& e, std::string payload) {
  if (!node_.spec.find_event(e.name)) plugin_bug("emits event '" + std::string(e.name) + "', which its spec does not declare");
  node_.emit_event(e.name, std::move(payload));
}

void Context::emit_event(std::string_view name, std::string payload) { node_.emit_event(name, std::move(payload)); }

void Context::finish() { node_.finish_requested = true; }
std::int64_t Context::now_ns() const { return node_.graph.now_ns(); }
std::stop_token Context::stop_token() const { return node_.graph.stop_token(); }
spdlog::logger& Context::log() const { return *node_.logger; }
const std::filesystem::path& Context::output_dir() const { return node_.graph.options.output_dir; }
const std::filesystem::path& Context::task_dir() const { return node_.graph.task_dir; }
ThreadPool& Context::thread_pool() const { return node_.graph.thread_pool(); }

void Context::set_trigger(Trigger t) {
  if (!node_.constructing) throw std::logic_error("set_trigger is only allowed in a component's constructor");
  // Periods become int64 nanoseconds: the task files' limit, so that no deadline can wrap around.
  if (t.policy == TriggerPolicy::Periodic && !(t.period_s > 0 && t.period_s <= 1e9))
    throw std::invalid_argument(fmt::format("a periodic trigger's period must be in (0, 1000000000] seconds; found {}", t.period_s));
  node_.trigger = t;
}

void Context::set_stage(const std::string& stage) { node_.enter_stage(stage); }

void Context::report(std::string_view name, std::string json) {
  if (name.empty()) plugin_bug("reported a result with no name");
  if (!nlohmann::json::accept(json))
    plugin_bug(fmt::format("reported result '{}' is not one JSON value; it begins: {}", name, json.substr(0, 120)));
  std::lock_guard lock(node_.stage_mutex);
  node_.results[std::string(name)] = std::move(json);
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
