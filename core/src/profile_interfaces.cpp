// Profile interfaces: what a component type offers the task around it (its ports and events), and
// what differs between two of them, so that `fba-run --check` can say whether two profiles that
// bind a task's device slots are interchangeable. Apart from loading: it compares specs, whatever
// file they came from.
#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "fba/task_config.hpp"

namespace fba {

Interface interface_of(const Spec& spec) {
  Interface i;
  i.type = spec.type_name();
  auto port = [](const PortSpec& p) {
    return PortInterface{p.name, p.same_as.empty() ? p.type->name : "like input '" + p.same_as + "'", p.required};
  };
  for (const auto& p : spec.inputs()) i.inputs.push_back(port(p));
  for (const auto& p : spec.outputs()) i.outputs.push_back(port(p));
  for (const auto& e : spec.events()) i.events.push_back(e.name);
  auto by_name = [](const PortInterface& a, const PortInterface& b) { return a.name < b.name; };
  std::sort(i.inputs.begin(), i.inputs.end(), by_name);
  std::sort(i.outputs.begin(), i.outputs.end(), by_name);
  std::sort(i.events.begin(), i.events.end());
  return i;
}

Interface slot_interface(const TaskConfig& task, std::string_view slot) {
  const SlotConfig* s = task.find_slot(slot);
  if (!s || !s->type) throw std::out_of_range("the task has no bound slot '" + std::string(slot) + "'");
  return interface_of(s->type->spec);
}

namespace {
std::string port_text(const PortInterface& p, bool input) {
  return p.type + (input && !p.required ? ", optional" : "");
}

void port_differences(const std::vector<PortInterface>& a, const std::vector<PortInterface>& b, const Interface& ia,
                      const Interface& ib, bool input, std::vector<std::string>& out) {
  const std::string what = input ? "input" : "output";
  for (const auto& p : a) {
    auto q = std::find_if(b.begin(), b.end(), [&](const PortInterface& x) { return x.name == p.name; });
    if (q == b.end()) out.push_back(what + " '" + p.name + "' (" + port_text(p, input) + "): only " + ia.type + " has it");
    else if (!(*q == p))
      out.push_back(what + " '" + p.name + "': " + port_text(p, input) + " in " + ia.type + ", " + port_text(*q, input) + " in " + ib.type);
  }
  for (const auto& q : b)
    if (std::none_of(a.begin(), a.end(), [&](const PortInterface& x) { return x.name == q.name; }))
      out.push_back(what + " '" + q.name + "' (" + port_text(q, input) + "): only " + ib.type + " has it");
}
}  // namespace

std::vector<std::string> interface_differences(const Interface& a, const Interface& b) {
  std::vector<std::string> out;
  port_differences(a.inputs, b.inputs, a, b, true, out);
  port_differences(a.outputs, b.outputs, a, b, false, out);
  for (const auto& e : a.events)
    if (std::find(b.events.begin(), b.events.end(), e) == b.events.end()) out.push_back("event '" + e + "': only " + a.type + " emits it");
  for (const auto& e : b.events)
    if (std::find(a.events.begin(), a.events.end(), e) == a.events.end()) out.push_back("event '" + e + "': only " + b.type + " emits it");
  return out;
}

std::string describe(const Interface& i) {
  auto ports = [](const std::vector<PortInterface>& v, bool input) {
    std::string s;
    for (const auto& p : v) s += (s.empty() ? "" : ", ") + p.name + " (" + port_text(p, input) + ")";
    return s.empty() ? std::string("(none)") : s;
  };
  std::string events;
  for (const auto& e : i.events) events += e + ", ";
  return "    inputs:  " + ports(i.inputs, true) + "\n    outputs: " + ports(i.outputs, false) + "\n    events:  " + events +
         "error, finished\n";
}

}  // namespace fba
