// The task graph as Graphviz DOT.
#include <cstdio>
#include <map>
#include <sstream>

#include "fba/task.hpp"
#include "fba/task_config.hpp"

namespace fba {
namespace {

std::string id(const std::string& s) { return "\"" + s + "\""; }

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\' || c == '{' || c == '}' || c == '|' || c == '<' || c == '>') out += '\\';
    out += c;
  }
  return out;
}

const char* colour(Kind k) {
  switch (k) {
    case Kind::Sensor: return "#d8ecff";
    case Kind::Filter: return "#f2f2f2";
    case Kind::Actuator: return "#ffe3cc";
    case Kind::Composite: return "#ffffff";
  }
  return "#ffffff";
}

// What a live dump adds: counts now and, for rates, the counts of the previous dump.
struct Live {
  const RunResult* now = nullptr;
  const RunResult* earlier = nullptr;
  std::map<std::string, const ComponentStats*> components, earlier_components;
  std::map<std::string, const ConnectionStats*> connections, earlier_connections;  // "from -> to"

  Live(const RunResult* n, const RunResult* e) : now(n), earlier(e) {
    if (now) index(*now, components, connections);
    if (earlier) index(*earlier, earlier_components, earlier_connections);
  }
  static void index(const RunResult& r, std::map<std::string, const ComponentStats*>& cs,
                    std::map<std::string, const ConnectionStats*>& ns) {
    for (const auto& c : r.components) cs[c.name] = &c;
    for (const auto& c : r.connections) ns[c.from + " -> " + c.to] = &c;
  }
  // Per second since the previous dump, or since the start without one.
  double rate(std::uint64_t count, std::uint64_t before) const {
    const double dt = now->run_s() - (earlier ? earlier->run_s() : 0.0);
    return dt > 0 ? static_cast<double>(count - std::min(count, before)) / dt : 0.0;
  }
};

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, v >= 100 || v == 0 ? "%.0f" : "%.3g", v);
  return buf;
}

struct Cluster {
  std::map<std::string, Cluster> children;
  std::vector<const ComponentConfig*> components;
};

void emit_cluster(std::ostringstream& o, const Cluster& c, const std::string& path, int depth, const Live& live) {
  const std::string indent(static_cast<std::size_t>(2 * depth), ' ');
  for (const auto& [name, child] : c.children) {
    const std::string full = path.empty() ? name : path + "/" + name;
    o << indent << "subgraph " << id("cluster_" + full) << " {\n"
      << indent << "  label=" << id(escape(full)) << "; style=rounded; color=\"#888888\";\n";
    emit_cluster(o, child, full, depth + 1, live);
    o << indent << "}\n";
  }
  for (const auto* comp : c.components) {
    const Spec& s = comp->type->spec;
    std::string ins, outs;
    for (const auto& p : s.inputs()) ins += (ins.empty() ? "" : "|") + std::string("<i_") + p.name + "> " + escape(p.name);
    for (const auto& p : s.outputs()) outs += (outs.empty() ? "" : "|") + std::string("<o_") + p.name + "> " + escape(p.name);
    std::string label = "{";
    if (!ins.empty()) label += "{" + ins + "}|";
    label += escape(comp->name.substr(comp->name.rfind('/') + 1)) + "\\n" + escape(s.type_name()) + " (" + to_string(s.kind()) + ")";
    // Live: the state, the stage, calls and their rate; the outline says the state at a glance.
    std::string outline;
    if (auto it = live.components.find(comp->name); it != live.components.end()) {
      const ComponentStats& now = *it->second;
      std::uint64_t calls_before = 0;
      if (auto e = live.earlier_components.find(comp->name); e != live.earlier_components.end())
        calls_before = e->second->invocations;
      label += "\\n" + now.state + (now.stage.empty() ? "" : ", stage " + escape(now.stage)) + "\\n" +
               std::to_string(now.invocations) + " calls, " + number(live.rate(now.invocations, calls_before)) + "/s";
      if (now.errors > 0) label += ", " + std::to_string(now.errors) + " errors";
      outline = now.state == "running" ? "#2e7d32" : now.state == "queued" ? "#e65100" : now.state == "finished" ? "#9e9e9e" : "";
    }
    if (!outs.empty()) label += "|{" + outs + "}";
    label += "}";
    o << indent << id(comp->name) << " [shape=record, style=\"rounded,filled\", fillcolor=\"" << colour(s.kind()) << "\"";
    if (!outline.empty()) o << ", color=\"" << outline << "\", penwidth=2";
    o << ", label=" << id(label) << "];\n";
  }
}

std::string dot(const TaskConfig& task, const Live& live) {
  std::ostringstream o;
  o << "digraph " << id(task.name.empty() ? "task" : task.name) << " {\n"
    << "  rankdir=LR;\n  node [fontname=\"Helvetica\", fontsize=10];\n  edge [fontname=\"Helvetica\", fontsize=9];\n";
  Cluster root;
  for (const auto& c : task.components) {
    Cluster* at = &root;
    std::string rest = c.name;
    for (auto slash = rest.find('/'); slash != std::string::npos; slash = rest.find('/')) {
      at = &at->children[rest.substr(0, slash)];
      rest = rest.substr(slash + 1);
    }
    at->components.push_back(&c);
  }
  emit_cluster(o, root, "", 1, live);
  for (const auto& c : task.connections) {
    std::string label = c.type ? c.type->name : "";
    label += "\\n" + std::string(to_string(c.policy));
    if (c.policy != BufferPolicy::Latest) label += " " + std::to_string(c.capacity);
    // Live: queue fill against capacity, delivery rate, drops; a full queue is drawn red and thick.
    std::string style;
    const std::string key = c.from + "." + c.from_port + " -> " + c.to + "." + c.to_port;
    if (auto it = live.connections.find(key); it != live.connections.end()) {
      const ConnectionStats& now = *it->second;
      std::uint64_t before = 0;
      if (auto e = live.earlier_connections.find(key); e != live.earlier_connections.end()) before = e->second->delivered;
      label = c.type ? c.type->name : "";
      label += "\\n" + std::string(to_string(c.policy)) + " " + std::to_string(now.left) + "/" + std::to_string(now.capacity) +
               "\\n" + number(live.rate(now.delivered, before)) + "/s";
      if (now.dropped > 0) label += ", " + std::to_string(now.dropped) + " dropped";
      if (now.capacity > 0 && now.left >= now.capacity) style = ", color=\"#c62828\", penwidth=3";
    }
    o << "  " << id(c.from) << ":" << id("o_" + c.from_port) << " -> " << id(c.to) << ":" << id("i_" + c.to_port) << " [label="
      << id(label) << style;
    if (c.feedback) o << ", style=dashed, constraint=false, color=\"#aa3333\"";
    o << "];\n";
  }
  bool stop_ok = false, stop_fail = false;
  for (const auto& r : task.rules) {
    std::string target;
    if (r.action == RuleAction::StopSuccess) { target = "stop: success"; stop_ok = true; }
    else if (r.action == RuleAction::StopFailure) { target = "stop: failure"; stop_fail = true; }
    o << "  " << id(r.source) << " -> " << (target.empty() ? id(r.target) + ":" + id("i_" + r.target_port) : id(target))
      << " [style=dotted, label=" << id("on " + r.event) << "];\n";
  }
  if (stop_ok) o << "  " << id("stop: success") << " [shape=doublecircle, color=\"#338833\", fontsize=9];\n";
  if (stop_fail) o << "  " << id("stop: failure") << " [shape=doublecircle, color=\"#aa3333\", fontsize=9];\n";
  o << "}\n";
  return o.str();
}

}  // namespace

std::string to_dot(const TaskConfig& task) { return dot(task, Live(nullptr, nullptr)); }

std::string to_dot(const TaskConfig& task, const RunResult& now, const RunResult* earlier) {
  return dot(task, Live(&now, earlier));
}

}  // namespace fba
