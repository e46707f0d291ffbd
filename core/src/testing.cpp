#include "fba/testing.hpp"

#include <algorithm>

#include "graph.hpp"

namespace fba::testing {

struct ComponentHarness::Impl {
  TaskConfig config;
  std::unique_ptr<detail::Graph> graph;
  detail::Node* node = nullptr;
  std::map<std::string, detail::Buffer*> inputs;
  std::map<std::string, std::vector<Packet>*> outputs;
};

ComponentHarness::ComponentHarness(const Registry& registry, const std::string& type,
                                   const std::map<std::string, std::string>& params,
                                   const std::vector<std::string>& optional_inputs)
    : impl_(std::make_unique<Impl>()) {
  std::string yaml = "components:\n  dut:\n    type: \"" + type + "\"\n    params:\n";
  for (const auto& [k, v] : params) yaml += "      " + k + ": " + v + "\n";
  LoadOptions options;
  options.require_inputs = false;
  impl_->config = load_task_text(yaml, "harness(" + type + ")", std::filesystem::current_path(), registry, options);
  RunOptions run;
  run.executor = ExecutorKind::Deterministic;
  impl_->graph = std::make_unique<detail::Graph>(impl_->config, run);
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

void ComponentHarness::tick() { impl_->node->tick_pending.store(true); }

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

}  // namespace fba::testing
