// The live view's messages (see live_messages.hpp), built with nlohmann/json. A view's JSON and the
// summary are spliced in as text: they are already JSON, and an image's view is large.
#include "live_messages.hpp"

#include <map>

#include <nlohmann/json.hpp>

namespace fba::serve {

using nlohmann::json;

namespace {

// `j`'s text with `"key":text` added last (j is an object).
std::string with_raw(const json& j, const std::string& key, const std::string& text) {
  std::string s = j.dump(-1, ' ', false, json::error_handler_t::replace);
  s.pop_back();
  s += (j.empty() ? "\"" : ",\"") + key + "\":" + (text.empty() ? "null" : text) + "}";
  return s;
}

json ports(const std::vector<PortSpec>& specs, const ComponentConfig* config, bool outputs) {
  json a = json::array();
  for (const auto& p : specs) {
    std::string type = p.type ? p.type->name : "any";
    if (outputs && config)
      if (const auto it = config->output_types.find(p.name); it != config->output_types.end() && it->second) type = it->second->name;
    a.push_back({{"name", p.name}, {"type", type}});
  }
  return a;
}

double rate(std::uint64_t now, std::uint64_t before, double dt) { return dt > 0 && now >= before ? (now - before) / dt : 0.0; }

}  // namespace

std::string task_message(const TaskConfig& task, const std::string& run_id) {
  json j{{"type", "task"}, {"run_id", run_id}, {"task", task.name}, {"file", task.file.string()}};
  json components = json::array();
  for (const auto& c : task.components) {
    const Spec& spec = c.type->spec;
    const char* kind = spec.kind() == Kind::Sensor ? "sensor" : spec.kind() == Kind::Actuator ? "actuator" : "filter";
    components.push_back({{"name", c.name}, {"type", spec.type_name()}, {"kind", kind}, {"doc", spec.doc()},
                          {"inputs", ports(spec.inputs(), &c, false)}, {"outputs", ports(spec.outputs(), &c, true)}});
  }
  j["components"] = components;
  json connections = json::array();
  for (const auto& c : task.connections)
    connections.push_back({{"from", c.from + "." + c.from_port}, {"to", c.to + "." + c.to_port}, {"policy", to_string(c.policy)},
                           {"capacity", c.capacity}, {"feedback", c.feedback}});
  j["connections"] = connections;
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string stats_message(const RunResult& now, const RunResult* previous) {
  const double dt = now.run_s() - (previous ? previous->run_s() : 0.0);
  std::map<std::string, const ComponentStats*> before_components;
  std::map<std::pair<std::string, std::string>, const ConnectionStats*> before_connections;
  if (previous) {
    for (const auto& c : previous->components) before_components[c.name] = &c;
    for (const auto& c : previous->connections) before_connections[{c.from, c.to}] = &c;
  }
  json components = json::array();
  for (const auto& c : now.components) {
    const auto b = before_components.find(c.name);
    const std::uint64_t calls_before = b == before_components.end() ? 0 : b->second->invocations;
    components.push_back({{"name", c.name}, {"state", c.state}, {"stage", c.stage}, {"invocations", c.invocations},
                          {"samples_in", c.samples_in}, {"samples_out", c.samples_out}, {"errors", c.errors},
                          {"rate_hz", rate(c.invocations, calls_before, dt)}});
  }
  json connections = json::array();
  for (const auto& c : now.connections) {
    const auto b = before_connections.find({c.from, c.to});
    const std::uint64_t delivered_before = b == before_connections.end() ? 0 : b->second->delivered;
    connections.push_back({{"from", c.from}, {"to", c.to}, {"queued", c.left}, {"capacity", c.capacity},
                           {"delivered", c.delivered}, {"dropped", c.dropped}, {"rate_hz", rate(c.delivered, delivered_before, dt)}});
  }
  const json j{{"type", "stats"}, {"t", now.wall_s}, {"components", components}, {"connections", connections}};
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string event_message(std::size_t index, const Event& event) {
  json payload = json::parse(event.payload, nullptr, false);
  if (payload.is_discarded()) payload = event.payload;
  const json j{{"type", "event"}, {"index", index},   {"t", static_cast<double>(event.stamp_ns) * 1e-9},
               {"source", event.source}, {"name", event.name}, {"payload", payload}};
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string view_message(const std::string& port, const std::string& data_type, const Header& header, const std::string& view) {
  const json j{{"type", "view"}, {"port", port}, {"data_type", data_type}, {"seq", header.seq},
               {"t", static_cast<double>(header.stamp_ns) * 1e-9}};
  return with_raw(j, "view", view);
}

std::string end_message(const RunResult& result, const std::string& summary) {
  const json j{{"type", "end"}, {"outcome", to_string(result.outcome)}, {"exit_code", result.exit_code()}, {"reason", result.reason}};
  return with_raw(j, "summary", summary);
}

}  // namespace fba::serve
