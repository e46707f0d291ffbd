// The task graph as Graphviz DOT.
#include <map>
#include <sstream>

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

struct Cluster {
  std::map<std::string, Cluster> children;
  std::vector<const ComponentConfig*> components;
};

void emit_cluster(std::ostringstream& o, const Cluster& c, const std::string& path, int depth) {
  const std::string indent(static_cast<std::size_t>(2 * depth), ' ');
  for (const auto& [name, child] : c.children) {
    const std::string full = path.empty() ? name : path + "/" + name;
    o << indent << "subgraph " << id("cluster_" + full) << " {\n"
      << indent << "  label=" << id(escape(full)) << "; style=rounded; color=\"#888888\";\n";
    emit_cluster(o, child, full, depth + 1);
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
    if (!outs.empty()) label += "|{" + outs + "}";
    label += "}";
    o << indent << id(comp->name) << " [shape=record, style=\"rounded,filled\", fillcolor=\"" << colour(s.kind())
      << "\", label=" << id(label) << "];\n";
  }
}

}  // namespace

std::string to_dot(const TaskConfig& task) {
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
  emit_cluster(o, root, "", 1);
  for (const auto& c : task.connections) {
    std::string label = c.type ? c.type->name : "";
    label += "\\n" + std::string(to_string(c.policy));
    if (c.policy != BufferPolicy::Latest) label += " " + std::to_string(c.capacity);
    o << "  " << id(c.from) << ":" << id("o_" + c.from_port) << " -> " << id(c.to) << ":" << id("i_" + c.to_port) << " [label="
      << id(label);
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

}  // namespace fba
