// summary.json and the outcome names and exit codes.
#include <sys/resource.h>

#include <nlohmann/json.hpp>

#include "fba/task.hpp"

namespace fba {

const char* to_string(Outcome o) {
  switch (o) {
    case Outcome::Success: return "success";
    case Outcome::Failure: return "failure";
    case Outcome::ConfigError: return "configuration_error";
    case Outcome::RuntimeError: return "runtime_error";
    case Outcome::Interrupted: return "interrupted";
  }
  return "?";
}

int exit_code(Outcome o) {
  switch (o) {
    case Outcome::Success: return 0;
    case Outcome::Failure: return 1;
    case Outcome::ConfigError: return 2;
    case Outcome::RuntimeError: return 3;
    case Outcome::Interrupted: return 130;
  }
  return 3;
}

std::string summary_json(const RunResult& r, const TaskConfig& task) {
  using nlohmann::json;
  json j;
  j["task"] = task.name;
  j["task_file"] = task.file.string();
  if (!task.profile.empty()) j["profile"] = {{"name", task.profile}, {"file", task.profile_file.string()}};
  if (!task.params.empty()) {
    json params = json::object();
    for (const auto& p : task.params) {
      json v;
      std::visit([&](const auto& x) { v = x; }, p.value);
      params[p.name] = {{"value", v}, {"source", p.source}};
    }
    j["params"] = params;
  }
  if (!r.run_id.empty()) j["run_id"] = r.run_id;
  j["outcome"] = to_string(r.outcome);
  j["exit_code"] = r.exit_code();
  j["reason"] = r.reason;
  if (!r.phase.empty()) j["phase"] = r.phase;
  if (r.signal > 0) j["signal"] = r.signal;
  if (r.forced) j["forced"] = true;
  if (!r.artefacts.empty()) j["artefacts"] = r.artefacts;
  j["wall_time_s"] = r.wall_s;
  j["construct_time_s"] = r.construct_s;
  // The process's peak resident memory so far (the whole fba-run process when it writes this).
  if (rusage u{}; getrusage(RUSAGE_SELF, &u) == 0) j["peak_resident_mib"] = static_cast<double>(u.ru_maxrss) / 1024.0;
  j["lost_to_restarts"] = r.lost_to_restarts;
  // The final event is written once: by its index in `events` when it is listed there.
  j["final_event"] = nullptr;
  if (r.final_event) {
    json fe{{"source", r.final_event->source}, {"name", r.final_event->name}, {"time_s", r.final_event->stamp_ns * 1e-9}};
    if (r.final_event_index) fe["index"] = *r.final_event_index;
    else fe["payload"] = r.final_event->payload;
    j["final_event"] = fe;
  }
  json comps = json::object();
  const double wall = r.run_s() > 0 ? r.run_s() : 1e-9;
  for (const auto& c : r.components) {
    json cj{{"type", c.type},
            {"kind", to_string(c.kind)},
            {"invocations", c.invocations},
            {"samples_in", c.samples_in},
            {"samples_out", c.samples_out},
            {"invocations_per_s", c.invocations / wall},
            {"samples_out_per_s", c.samples_out / wall},
            {"errors", c.errors},
            {"restarts", c.restarts},
            {"lost_to_restarts", c.lost_to_restarts}};
    if (!c.stage.empty()) cj["stage"] = c.stage;
    if (!c.stages.empty()) {
      json stages = json::object();
      for (const auto& [name, t] : c.stages)
        stages[name] = {{"entered", t.entered}, {"busy_s", t.busy_s}, {"clock_s", t.clock_s}};
      cj["stages"] = stages;
    }
    if (!c.results.empty()) {
      json results = json::object();
      for (const auto& [name, text] : c.results) results[name] = json::parse(text);  // checked by Context::report
      cj["results"] = results;
    }
    comps[c.name] = cj;
  }
  j["components"] = comps;
  json conns = json::array();
  for (const auto& c : r.connections)
    conns.push_back({{"from", c.from},
                     {"to", c.to},
                     {"buffer", to_string(c.policy)},
                     {"pushed", c.pushed},
                     {"delivered", c.delivered},
                     {"dropped", c.dropped},
                     {"left", c.left},
                     {"peak", c.peak},
                     {"peak_bytes", c.peak_bytes}});
  j["connections"] = conns;
  json events = json::array();
  for (const auto& e : r.events) events.push_back({{"source", e.source}, {"name", e.name}, {"payload", e.payload}, {"time_s", e.stamp_ns * 1e-9}});
  j["events"] = events;
  json stuck = json::array();
  for (const auto& c : r.stuck) stuck.push_back({{"component", c.component}, {"type", c.type}, {"call", c.call}});
  j["stuck"] = stuck;
  json safe = json::object();
  for (const auto& s : r.safe_states) safe[s.component] = {{"status", s.status}, {"message", s.message}};
  j["safe_states"] = safe;
  // Payloads are free-form bytes: invalid UTF-8 is replaced rather than failing the summary.
  return j.dump(2, ' ', false, json::error_handler_t::replace) + "\n";
}

}  // namespace fba
