#include "fba/testing.hpp"

#include <algorithm>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "graph.hpp"

namespace fba::testing {

namespace {

// The harness's clock: time moves only when the test says so; invocations are run by hand.
class HarnessClock final : public detail::Executor {
 public:
  void enqueue(detail::Node*) override {}
  std::int64_t now_ns() const override { return now; }
  void run() override { throw std::logic_error("a component harness is driven by hand, not run"); }
  bool join(double) override { return true; }  // no threads of its own
  void wake_all() override {}
  void poke() override {}
  std::int64_t now = 0;
};

// A typed value as YAML text the loader reads back: the harness's values go through the same
// checks as a task file's.
YAML::Node to_yaml(const Value& v) {
  struct Visitor {
    YAML::Node operator()(bool b) const { return YAML::Node(b ? "true" : "false"); }
    YAML::Node operator()(std::int64_t i) const { return YAML::Node(std::to_string(i)); }
    YAML::Node operator()(double d) const { return YAML::Node(fmt::format("{}", d)); }
    YAML::Node operator()(const std::string& s) const { return YAML::Node(s); }
    YAML::Node operator()(const std::vector<double>& l) const {
      YAML::Node n(YAML::NodeType::Sequence);
      for (double d : l) n.push_back(fmt::format("{}", d));
      n.SetStyle(YAML::EmitterStyle::Flow);
      return n;
    }
  };
  return std::visit(Visitor{}, v);
}

const char* kind_of(const Value& v) {
  static const char* const names[] = {"a bool", "an int", "a double", "a string", "a list of double"};
  return names[v.index()];
}

// What a task file would refuse to read as this type: text for a number, a number for a flag.
bool fits(ParamType t, const Value& v) {
  switch (t) {
    case ParamType::Bool: return std::holds_alternative<bool>(v);
    case ParamType::Int: return std::holds_alternative<std::int64_t>(v);
    case ParamType::Double: return std::holds_alternative<double>(v) || std::holds_alternative<std::int64_t>(v);
    case ParamType::String:
    case ParamType::Path: return std::holds_alternative<std::string>(v);
    case ParamType::DoubleList: return std::holds_alternative<std::vector<double>>(v);
  }
  return false;
}

}  // namespace

struct ComponentHarness::Impl {
  TaskConfig config;
  std::unique_ptr<detail::Graph> graph;
  HarnessClock* clock = nullptr;
  detail::Node* node = nullptr;
  std::map<std::string, detail::Buffer*> inputs;
  std::map<std::string, std::vector<Packet>*> outputs;
};

ComponentHarness::ComponentHarness(const Registry& registry, const std::string& type, const Params& params,
                                   const std::vector<std::string>& optional_inputs)
    : impl_(std::make_unique<Impl>()) {
  const std::string name = "harness(" + type + ")";
  YAML::Node yaml_params(YAML::NodeType::Map);
  if (const auto entry = registry.find(type)) {
    std::vector<Diagnostic> wrong;
    for (const auto& [k, v] : params)
      if (const ParamSpec* ps = entry->spec.find_param(k); ps && !fits(ps->type, v))
        wrong.push_back({Location{name}, "parameter '" + k + "' expects a " + to_string(ps->type) + "; found " + kind_of(v) +
                                             " '" + to_string(v) + "'"});
    if (!wrong.empty()) throw ConfigError(std::move(wrong));
  }
  for (const auto& [k, v] : params) yaml_params[k] = to_yaml(v);
  YAML::Node doc;
  doc["components"]["dut"]["type"] = type;
  doc["components"]["dut"]["params"] = yaml_params;
  LoadOptions options;
  options.require_inputs = false;
  impl_->config = load_task_text(YAML::Dump(doc), name, std::filesystem::current_path(), registry, options);
  RunOptions run;
  run.executor = ExecutorKind::Deterministic;
  impl_->graph = std::make_unique<detail::Graph>(impl_->config, run);
  auto clock = std::make_unique<HarnessClock>();
  impl_->clock = clock.get();
  impl_->graph->executor_ = std::move(clock);
  impl_->node = impl_->graph->nodes.front().get();
  auto& g = *impl_->graph;
  for (const auto& name : optional_inputs)
    if (!impl_->node->spec.find_input(name))
      throw std::invalid_argument("'" + type + "' has no input '" + name + "'");
  for (auto& in : impl_->node->input_states) {
    const bool wanted = in->spec->required ||
                        std::find(optional_inputs.begin(), optional_inputs.end(), in->spec->name) != optional_inputs.end();
    if (!wanted) continue;
    auto b = std::make_unique<detail::Buffer>();
    b->policy = BufferPolicy::Lossless;
    b->consumer = impl_->node;
    b->from = "harness";
    b->to = "dut." + in->spec->name;
    in->buffer = b.get();
    impl_->inputs[in->spec->name] = b.get();
    g.buffers.push_back(std::move(b));
  }
  for (auto& out : impl_->node->output_states) impl_->outputs[out->spec->name] = &g.tap("dut." + out->spec->name);
  g.construct();
}

ComponentHarness::~ComponentHarness() = default;

void ComponentHarness::push_packet(const std::string& input, Packet p) {
  auto it = impl_->inputs.find(input);
  if (it == impl_->inputs.end())
    throw std::invalid_argument("the component has no connected input '" + input + "' (optional inputs are connected when named)");
  auto& node = *impl_->node;
  for (auto& in : node.input_states) {
    if (in->spec->name != input) continue;
    if (in->spec->type != any_type() && in->spec->type != p.type())
      throw std::invalid_argument("input '" + input + "' takes '" + in->spec->type->name + "', not '" + p.type()->name + "'");
    for (auto& out : node.output_states)  // outputs typed like this input follow the pushed type
      if (out->spec->same_as == input) out->type = p.type();
  }
  it->second->push(std::move(p));
}

void ComponentHarness::close(const std::string& input) {
  auto it = impl_->inputs.find(input);
  if (it == impl_->inputs.end()) throw std::invalid_argument("the component has no input '" + input + "'");
  it->second->producer_done.store(true);
}

std::int64_t ComponentHarness::now_ns() const { return impl_->clock->now; }
void ComponentHarness::advance(std::int64_t ns) { set_time(impl_->clock->now + ns); }
void ComponentHarness::set_time(std::int64_t ns) {
  if (ns < impl_->clock->now)
    throw std::invalid_argument("the harness clock cannot go back (from " + std::to_string(impl_->clock->now) + " to " +
                                std::to_string(ns) + " ns)");
  impl_->clock->now = ns;
}

void ComponentHarness::tick() {
  const Trigger& t = impl_->node->trigger;
  if (t.policy != TriggerPolicy::Periodic) throw std::logic_error("tick(): the component is not periodic");
  advance(static_cast<std::int64_t>(t.period_s * 1e9));
  impl_->node->tick_pending.store(true);
}

bool ComponentHarness::step() {
  auto& n = *impl_->node;
  if (impl_->graph->stopping() || !n.ready()) return false;
  n.invoke();
  return true;
}

int ComponentHarness::run() {
  int count = 0;
  while (step()) ++count;
  return count;
}

const std::vector<Packet>& ComponentHarness::packets(const std::string& output) {
  auto it = impl_->outputs.find(output);
  if (it == impl_->outputs.end()) throw std::invalid_argument("the component has no output '" + output + "'");
  return *it->second;
}

std::vector<Event> ComponentHarness::events() const { return impl_->graph->events(); }
bool ComponentHarness::finished() const { return impl_->node->finished.load(); }
std::string ComponentHarness::failure() const { return impl_->graph->stopping() ? impl_->graph->stop_reason() : std::string(); }
std::string ComponentHarness::stage() const {
  std::lock_guard lock(impl_->node->stage_mutex);
  return impl_->node->stage;
}
void ComponentHarness::safe_state() { impl_->node->component->safe_state(); }
void ComponentHarness::interrupt() { impl_->node->component->interrupt(); }

}  // namespace fba::testing
