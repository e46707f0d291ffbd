// Graph checking (see graph_checking.hpp): each connection, trigger, error policy and event rule
// as it is read, then the whole graph.
#include "graph_checking.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <string>
#include <utility>

#include "fba/message_text.hpp"
#include "fba/task.hpp"
#include "loader.hpp"

namespace fba::loader {

namespace {

bool is_rule_location(const TaskConfig& task, const Location* where) {
  for (const auto& r : task.rules)
    if (&r.where == where) return true;
  return false;
}

}  // namespace

std::vector<Diagnostic> check_graph(TaskConfig& task, bool require_inputs) {
  std::vector<Diagnostic> found;
  auto error = [&found](const Location& where, std::string message) { found.push_back(Diagnostic{where, std::move(message)}); };
  std::map<std::string, const ComponentConfig*> comps;
  for (const auto& c : task.components) comps[c.name] = &c;
  // One producer per input.
  std::map<std::pair<std::string, std::string>, const Location*> fed;
  for (const auto& c : task.connections) {
    auto key = std::make_pair(c.to, c.to_port);
    if (auto it = fed.find(key); it != fed.end())
      error(c.where, "input '" + c.to + "." + c.to_port + "' is connected already (at " + it->second->str() + "); an input takes one connection");
    else fed[key] = &c.where;
  }
  for (const auto& r : task.rules) {
    if (r.action != RuleAction::Deliver) continue;
    auto key = std::make_pair(r.target, r.target_port);
    if (auto it = fed.find(key); it != fed.end() && !is_rule_location(task, it->second))
      error(r.where, "input '" + r.target + "." + r.target_port + "' is fed by a connection (at " + it->second->str() + "); events need an input of their own");
    fed.emplace(key, &r.where);
    const PortSpec* ps = comps.at(r.target)->type->spec.find_input(r.target_port);
    if (ps->type != type_of<Event>() && ps->type != any_type())
      error(r.where, "events are delivered as 'fba.Event'; input '" + r.target + "." + r.target_port + "' takes '" + ps->type->name + "'");
  }
  // Required inputs.
  for (const auto& c : task.components)
    for (const auto& in : c.type->spec.inputs())
      if (require_inputs && in.required && !fed.count({c.name, in.name}))
        error(c.where, "input '" + in.name + "' of '" + c.name + "' (" + c.type->spec.type_name() + ", " + in.type->name +
                           ") is required but not connected; add a connection 'producer.output -> " + c.name + "." + in.name + "'");
  // Cycles must be marked: a back edge says the loop is intended. Checked before the types,
  // which cannot resolve along an unmarked cycle: one error says why.
  std::map<std::string, std::vector<const ConnectionConfig*>> out_edges;
  for (const auto& c : task.connections)
    if (!c.feedback) out_edges[c.from].push_back(&c);
  std::map<std::string, int> color;  // 0 white, 1 grey, 2 black
  std::vector<std::string> path;
  std::function<bool(const std::string&)> dfs = [&](const std::string& n) {
    color[n] = 1;
    path.push_back(n);
    for (const auto* e : out_edges[n]) {
      if (color[e->to] == 1) {
        std::string cycle;
        auto start = std::find(path.begin(), path.end(), e->to);
        for (auto i = start; i != path.end(); ++i) cycle += *i + " -> ";
        cycle += e->to;
        error(e->where, "cycle " + cycle + " is not marked; mark one of its connections as a back edge with 'feedback: true'");
        return true;
      }
      if (color[e->to] == 0 && dfs(e->to)) return true;
    }
    path.pop_back();
    color[n] = 2;
    return false;
  };
  for (const auto& c : task.components)
    if (color[c.name] == 0 && dfs(c.name)) return found;
  // Types: outputs typed like an input take that input's resolved type; iterate to a fixpoint.
  std::map<std::pair<std::string, std::string>, const TypeInfo*> in_type, out_type;
  for (const auto& c : task.components)
    for (const auto& o : c.type->spec.outputs())
      if (o.same_as.empty()) out_type[{c.name, o.name}] = o.type;
  // Events arrive as fba.Event: outputs typed like an input that takes delivered events carry that.
  for (const auto& r : task.rules)
    if (r.action == RuleAction::Deliver) {
      in_type[{r.target, r.target_port}] = type_of<Event>();
      for (const auto& o : comps.at(r.target)->type->spec.outputs())
        if (o.same_as == r.target_port) out_type[{r.target, o.name}] = type_of<Event>();
    }
  for (std::size_t pass = 0; pass <= task.components.size() + 1; ++pass) {
    bool changed = false;
    for (auto& c : task.connections) {
      auto ot = out_type.find({c.from, c.from_port});
      if (ot == out_type.end()) continue;
      auto& it = in_type[{c.to, c.to_port}];
      if (!it) { it = ot->second; changed = true; }
      const ComponentConfig* dst = comps.at(c.to);
      for (const auto& o : dst->type->spec.outputs())
        if (o.same_as == c.to_port && !out_type.count({c.to, o.name})) { out_type[{c.to, o.name}] = ot->second; changed = true; }
    }
    if (!changed) break;
  }
  // The runtime checks every sample sent against its output's type, connected or not.
  for (auto& c : task.components)
    for (const auto& o : c.type->spec.outputs())
      if (auto t = out_type.find({c.name, o.name}); t != out_type.end()) c.output_types[o.name] = t->second;
  for (auto& c : task.connections) {
    auto ot = out_type.find({c.from, c.from_port});
    if (ot == out_type.end()) {
      error(c.where, "the type of '" + c.from + "." + c.from_port + "' cannot be resolved: it follows an input that is not connected, or only through a cycle");
      continue;
    }
    c.type = ot->second;
    const PortSpec* in = comps.at(c.to)->type->spec.find_input(c.to_port);
    if (in->type != any_type() && in->type != c.type)
      error(c.where, "type mismatch: '" + c.from + "." + c.from_port + "' carries '" + c.type->name + "' but '" + c.to + "." + c.to_port +
                         "' takes '" + in->type->name + "'");
  }
  return found;
}

std::optional<Diagnostic> check_thread_limit(const TaskConfig& task) {
  std::vector<const ComponentConfig*> own;
  for (const auto& c : task.components)
    if (c.dedicated_thread || c.type->spec.is_blocking()) own.push_back(&c);
  if (own.size() > kMaxDedicatedThreads)
    return Diagnostic{own[kMaxDedicatedThreads]->where, "at most " + std::to_string(kMaxDedicatedThreads) +
                                                           " components can have a thread of their own ('thread: dedicated', or a blocking type); found " +
                                                           std::to_string(own.size())};
  return std::nullopt;
}

Endpoint Loader::resolve(const Endpoint& e, bool input) const {
  auto it = exports_.find(e.comp);
  if (it == exports_.end()) return e;
  const auto& m = input ? it->second.inputs : it->second.outputs;
  auto p = m.find(e.port);
  if (p == m.end()) return Endpoint{"", e.port};
  return resolve(p->second, input);
}

std::optional<Endpoint> Loader::endpoint(const std::string& text, const YAML::Node& n, const Source& src, const std::string& prefix) {
  const auto dot = text.rfind('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == text.size()) {
    error(at(src, n), "expected component.port; found '" + text + "'");
    return std::nullopt;
  }
  return Endpoint{prefix + text.substr(0, dot), text.substr(dot + 1)};
}

bool Loader::check_port(const Endpoint& e, bool input, const YAML::Node& n, const Source& src, const std::string& prefix) {
  const std::string shown = e.comp.substr(prefix.size());
  auto kind = kinds_.find(e.comp);
  if (kind == kinds_.end()) {
    std::vector<std::string> known;
    for (const auto& [name, _] : kinds_)
      if (name.rfind(prefix, 0) == 0 && name.find('/', prefix.size()) == std::string::npos) known.push_back(name.substr(prefix.size()));
    error(at(src, n), "no component '" + shown + "'; components here: " + list_of(known));
    return false;
  }
  if (!kind->second) return false;  // a component that could not be read; its error is reported
  const Spec& spec = *kind->second;
  const PortSpec* ps = input ? spec.find_input(e.port) : spec.find_output(e.port);
  if (!ps) {
    error(at(src, n), "component '" + shown + "' (" + spec.type_name() + ") has no " + (input ? "input" : "output") + " '" + e.port +
                          "'; its " + (input ? "inputs" : "outputs") + ": " + list_of(names_of(input ? spec.inputs() : spec.outputs())));
    return false;
  }
  return true;
}

void Loader::read_trigger(const YAML::Node& t, const Source& src, const Bindings& bindings, ComponentConfig& cc) {
  const std::string valid = "any, all, free, or {policy: periodic, period: SECONDS}";
  std::string policy;
  if (t.IsScalar()) policy = text_of(t, bindings, src, "trigger");
  else if (t.IsMap()) {
    check_keys(t, src, {"policy", "period"});
    policy = t["policy"] ? text_of(t["policy"], bindings, src, "policy") : "";
  } else {
    error(at(src, t), "trigger: " + valid + "; found " + node_kind(t));
    return;
  }
  if (policy == "any") cc.trigger = {TriggerPolicy::Any, 0};
  else if (policy == "all") cc.trigger = {TriggerPolicy::All, 0};
  else if (policy == "free") cc.trigger = {TriggerPolicy::Free, 0};
  else if (policy == "periodic") {
    if (!t.IsMap() || !t["period"]) {
      error(at(src, t), "a periodic trigger needs period: SECONDS, in (0, " + number_text(kMaxPeriodSeconds) + "]");
      return;
    }
    const YAML::Node p = t["period"];
    const auto v = substituted(p, bindings, src);
    if (!v) return;
    const std::string range = "(0, " + number_text(kMaxPeriodSeconds) + "] seconds";
    const std::string text = v->IsScalar() ? v->Scalar() : node_kind(*v);
    double period = 0;
    if (!v->IsScalar() || !parse_double(text, period)) {
      error(at(src, p), "period must be a number in " + range + "; found '" + text + "'");
      return;
    }
    // Periods are kept in int64 nanoseconds: beyond about 9.2e9 s they would wrap around.
    if (!(period > 0 && period <= kMaxPeriodSeconds)) {
      error(at(src, p), "period must be in " + range + "; found " + text);
      return;
    }
    cc.trigger = {TriggerPolicy::Periodic, period};
  } else {
    error(at(src, t), "trigger '" + policy + "' is not one of: " + valid);
    return;
  }
  if (cc.trigger.policy == TriggerPolicy::Free && cc.type->spec.kind() != Kind::Sensor)
    error(at(src, t), "only sensors can be free-running; '" + cc.name + "' is a " + to_string(cc.type->spec.kind()));
}

void Loader::read_error_policy(const YAML::Node& e, const Source& src, const Bindings& bindings, ComponentConfig& cc) {
  std::string policy = e.IsScalar() ? text_of(e, bindings, src, "on_error")
                                    : (e.IsMap() && e["policy"] ? text_of(e["policy"], bindings, src, "policy") : "");
  if (e.IsMap()) check_keys(e, src, {"policy", "max_restarts"});
  if (policy == "stop") cc.on_error = ErrorPolicy::Stop;
  else if (policy == "restart") {
    cc.on_error = ErrorPolicy::Restart;
    cc.max_restarts = 3;
    if (e.IsMap() && e["max_restarts"])
      if (const auto v = substituted(e["max_restarts"], bindings, src))
        cc.max_restarts = static_cast<int>(integer(*v, e["max_restarts"], src, "max_restarts", 0, 1000000));
  } else {
    error(at(src, e), "on_error: stop, restart, or {policy: restart, max_restarts: N}; found '" + (e.IsScalar() ? e.Scalar() : std::string(node_kind(e))) + "'");
  }
}

void Loader::read_connection(const YAML::Node& n, const Source& src, const std::string& prefix, const Bindings& bindings, TaskConfig& task) {
  ConnectionConfig c;
  c.where = at(src, n);
  std::string from, to;
  // Node::operator= would write into the tree; reset() rebinds the handle.
  YAML::Node from_node, to_node;
  from_node.reset(n);
  to_node.reset(n);
  if (n.IsScalar()) {
    const std::string s = n.Scalar();
    const auto arrow = s.find("->");
    if (arrow == std::string::npos) {
      error(c.where, "a connection reads 'component.output -> component.input'; found '" + s + "'");
      return;
    }
    auto trim = [](std::string x) {
      x.erase(0, x.find_first_not_of(" \t"));
      x.erase(x.find_last_not_of(" \t") + 1);
      return x;
    };
    from = trim(s.substr(0, arrow));
    to = trim(s.substr(arrow + 2));
  } else if (n.IsMap()) {
    check_keys(n, src, {"from", "to", "buffer", "capacity", "max_bytes", "feedback"});
    // Checked before reset(), which throws on a missing key.
    if (!n["from"] || !n["to"]) {
      error(c.where, "a connection needs from: component.output and to: component.input");
      return;
    }
    from_node.reset(n["from"]);
    to_node.reset(n["to"]);
    from = scalar(from_node, src, "from");
    to = scalar(to_node, src, "to");
    if (const YAML::Node b = n["buffer"]) {
      const std::string p = text_of(b, bindings, src, "buffer");
      if (p == "lossless") c.policy = BufferPolicy::Lossless;
      else if (p == "drop_oldest") c.policy = BufferPolicy::DropOldest;
      else if (p == "latest") c.policy = BufferPolicy::Latest;
      else error(at(src, b), "buffer '" + p + "' is not one of: lossless (bounded queue, holds the producer back), drop_oldest, latest");
    }
    if (const YAML::Node cap = n["capacity"])
      if (const auto v = substituted(cap, bindings, src)) c.capacity = static_cast<std::size_t>(integer(*v, cap, src, "capacity", 1, kMaxCapacity));
    if (const YAML::Node mb = n["max_bytes"])
      if (const auto v = substituted(mb, bindings, src)) c.max_bytes = static_cast<std::size_t>(integer(*v, mb, src, "max_bytes", 0, kMaxBytesBudget));
    if (const YAML::Node fb = n["feedback"]) {
      const std::string f = text_of(fb, bindings, src, "feedback");
      if (f == "true") c.feedback = true;
      else if (f != "false") error(at(src, fb), "feedback is true or false; found '" + f + "'");
    }
  } else {
    error(c.where, std::string("a connection is 'a.out -> b.in' or {from, to, buffer, capacity, max_bytes, feedback}; found ") + node_kind(n));
    return;
  }
  auto a = endpoint(from, from_node, src, prefix);
  auto b = endpoint(to, to_node, src, prefix);
  if (!a || !b) return;
  if (!check_port(*a, false, from_node, src, prefix) || !check_port(*b, true, to_node, src, prefix)) return;
  const Endpoint ra = resolve(*a, false), rb = resolve(*b, true);
  if (ra.comp.empty() || rb.comp.empty()) {
    error(c.where, "a composite's exported port leads nowhere; check its inputs/outputs section");
    return;
  }
  c.from = ra.comp;
  c.from_port = ra.port;
  c.to = rb.comp;
  c.to_port = rb.port;
  task.connections.push_back(std::move(c));
}

void Loader::read_rule(const YAML::Node& key, const YAML::Node& value, const Source& src, const std::string& prefix, TaskConfig& task) {
  EventRule r;
  r.where = at(src, key);
  const std::string k = key.IsScalar() ? key.Scalar() : "";
  const auto dot = k.rfind('.');
  if (dot == std::string::npos || dot == 0) {
    error(r.where, "an event rule's key is component.event; found '" + k + "'");
    return;
  }
  Endpoint src_ev{prefix + k.substr(0, dot), k.substr(dot + 1)};
  // Events exported by composite instances resolve to the inner component.
  for (int depth = 0; depth < 64; ++depth) {
    auto it = exports_.find(src_ev.comp);
    if (it == exports_.end()) break;
    auto e = it->second.events.find(src_ev.port);
    if (e == it->second.events.end()) {
      error(r.where, "composite '" + k.substr(0, dot) + "' exports no event '" + src_ev.port + "'");
      return;
    }
    src_ev = e->second;
  }
  auto kind = kinds_.find(src_ev.comp);
  if (kind == kinds_.end()) {
    error(r.where, "no component '" + k.substr(0, dot) + "' for event rule '" + k + "'");
    return;
  }
  if (!kind->second) return;  // a component that could not be read; its error is reported
  const Spec& spec = *kind->second;
  if (!spec.find_event(src_ev.port) && src_ev.port != "error" && src_ev.port != "finished") {
    std::vector<std::string> evs = names_of(spec.events());
    evs.push_back("error");
    evs.push_back("finished");
    error(r.where, "component '" + k.substr(0, dot) + "' (" + spec.type_name() + ") emits no event '" + src_ev.port + "'; its events: " + list_of(evs));
    return;
  }
  r.source = src_ev.comp;
  r.event = src_ev.port;
  const std::string actions = "stop_success, stop_failure, or {deliver: component.input}";
  if (value.IsScalar()) {
    if (value.Scalar() == "stop_success") r.action = RuleAction::StopSuccess;
    else if (value.Scalar() == "stop_failure") r.action = RuleAction::StopFailure;
    else {
      error(at(src, value), "event action '" + value.Scalar() + "' is not one of: " + actions);
      return;
    }
  } else if (value.IsMap() && value["deliver"] && value["deliver"].IsScalar()) {
    check_keys(value, src, {"deliver"});
    auto target = endpoint(value["deliver"].Scalar(), value["deliver"], src, prefix);
    if (!target || !check_port(*target, true, value["deliver"], src, prefix)) return;
    const Endpoint t = resolve(*target, true);
    r.action = RuleAction::Deliver;
    r.target = t.comp;
    r.target_port = t.port;
  } else {
    error(at(src, value), "event action: " + actions);
    return;
  }
  task.rules.push_back(std::move(r));
}

}  // namespace fba::loader
