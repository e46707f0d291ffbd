// A run's row: its summary.json taken only when it carries the run's own id, and its grasp placed
// on the true mesh where the run stood it.
#include "batch_row.hpp"

#include <sys/wait.h>

#include <cstring>
#include <fstream>
#include <numbers>

#include "grasp_evaluation.hpp"
#include "object_placement.hpp"
#include "options.hpp"
#include "run_summary.hpp"

namespace fba::evaluate::batch {

namespace fs = std::filesystem;
namespace {

// The mesh where the run had it: stood on the table (z = 0) at (x, y), turned by yaw, and laid on
// its side when the run's command line set scene.rest=side (a variant's or the run's own --set),
// exactly as sim.camera and sim.hand place it with frame: table (the grasps' frame).
TriangleMesh placed_on_table(const RunSpec& r, const std::vector<std::string>& argv) {
  sim_hand::ObjectPlacement p;
  p.x = r.x;
  p.y = r.y;
  p.yaw = r.yaw * std::numbers::pi / 180;
  for (std::size_t i = 0; i + 1 < argv.size(); ++i)
    if (argv[i] == "--set" && argv[i + 1].rfind("scene.rest=", 0) == 0) p.rest = argv[i + 1].substr(11);
  return sim_hand::place_on_table(load_closed_mesh(r.mesh), p);
}

std::string last_line(const fs::path& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

// A JSON event payload, or null when it is not JSON.
nlohmann::json payload_json(const nlohmann::json& e) {
  if (!e.contains("payload") || !e["payload"].is_string()) return nullptr;
  return nlohmann::json::parse(e["payload"].get<std::string>(), nullptr, false);
}

}  // namespace

// Reads the run's summary.json and evaluates its grasp on the placed mesh.
Row evaluate_job(const Job& j, const grasp::QualityParams& quality) {
  Row row;
  row.variant = j.variant->name;
  row.object = j.object;
  row.mesh = j.run->mesh;
  row.pose = number(j.run->x) + " " + number(j.run->y) + " " + number(j.run->yaw);
  row.dir = j.dir.string();
  row.unfinished = j.stopped_by != 0;
  if (!j.setup_error.empty()) {
    row.outcome = "not run";  // could not start, or the batch was stopped first
    row.reason = j.setup_error;
    return row;
  }
  row.cpu_s = j.cpu_s;
  std::string ended;
  if (WIFSIGNALED(j.status)) ended = std::string("killed by signal ") + std::to_string(WTERMSIG(j.status)) + " (" + strsignal(WTERMSIG(j.status)) + ")";
  if (j.term_sent) ended = "timed out (stopped after the list's timeout_s)" + (ended.empty() ? "" : "; " + ended);
  if (j.stopped_by)
    ended = "interrupted (the batch was stopped by " + signal_name(j.stopped_by) + ", which it passed on)" + (ended.empty() ? "" : "; " + ended);
  // Only this run's own summary counts: one left by an earlier run (the batch removed it, but a
  // run that fails early might not write its own) carries another run_id.
  const fs::path summary = j.dir / "summary.json";
  nlohmann::json s;
  std::string refused;
  if (!fs::exists(summary)) {
    refused = "no summary.json";
  } else if (!fs::is_regular_file(summary)) {  // opening a FIFO would wait for a writer
    refused = "summary.json is " + file_kind(summary) + ", not a regular file";
  } else {
    std::ifstream in(summary);
    s = nlohmann::json::parse(in, nullptr, false);
    if (!s.is_object()) refused = "summary.json is not a JSON object";
    else if (!s.contains("run_id") || !s["run_id"].is_string()) refused = "summary.json is not this run's: no run_id, expected " + j.run_id;
    else if (s["run_id"] != j.run_id) refused = "summary.json is not this run's: run_id " + s["run_id"].get<std::string>() + ", expected " + j.run_id;
    else if (s.value("outcome", "") == "running") refused = "summary.json still says running (fba-run ended before writing its outcome)";
  }
  if (!refused.empty()) {
    row.outcome = j.stopped_by ? "interrupted" : j.term_sent ? "timed out" : WIFSIGNALED(j.status) ? "crashed" : "no summary";
    row.wall_s = j.elapsed_s;
    const std::string said = last_line(j.dir / "log.txt");
    row.reason = (ended.empty() ? "exit " + std::to_string(WEXITSTATUS(j.status)) : ended) + ", " + refused + "; " +
                 (said.empty() ? std::string("log.txt is empty") : "fba-run said: " + said);
    return row;
  }
  row.outcome = s.value("outcome", "?");
  row.wall_s = s.value("wall_time_s", j.elapsed_s);
  row.reason = s.value("reason", "");
  if (!ended.empty()) row.reason = ended + "; " + row.reason;

  // What the components reported (summary.json's results): the task's names are its own, so a
  // result is found by its name; the carver's comparison with uniform refinement (compare_uniform)
  // is its last `detail` event.
  int model_views = -1;
  const nlohmann::json components = s.contains("components") && s["components"].is_object() ? s["components"] : nlohmann::json::object();
  for (const auto& [name, c] : components.items()) {
    if (!c.is_object() || !c.contains("results") || !c["results"].is_object()) continue;
    const auto& r = c["results"];
    if (r.contains("carving") && r["carving"].is_object()) {
      row.nodes = r["carving"].value("nodes_visited", 0LL);
      model_views = r["carving"].value("views", model_views);
    }
    if (r.contains("lift") && r["lift"].is_object()) {
      row.held = r["lift"].value("held", false);
      if (!*row.held) row.reason = "dropped: " + r["lift"].value("reason", std::string("?"));
    }
    if (r.contains("failure") && r["failure"].is_string()) row.reason = "synthesis failed: " + r["failure"].get<std::string>();
    if (r.contains("resolved") && r["resolved"].is_string()) row.resolved = r["resolved"].get<std::string>();
    if (r.contains("seconds_per_view") && r["seconds_per_view"].is_array())
      for (const auto& x : r["seconds_per_view"])
        if (x.is_number()) row.synthesis_s.push_back(x.get<double>());
  }
  if (s.contains("events") && s["events"].is_array())
    for (const auto& e : s["events"]) {
      if (!e.is_object() || e.value("name", "") != "detail") continue;
      const auto c = components.find(e.value("source", ""));
      if (c != components.end() && c->is_object() && c->value("type", "") == "vision.octree_carver")
        if (const auto p = payload_json(e); p.is_object()) row.detail = p;
    }
  row.views = model_views;
  if (row.resolved == "contacts") row.reason += (row.reason.empty() ? "" : "; ") + std::string("selected on its contacts alone, the surface around them not all resolved");
  try {
    if (const auto g = summary_grasp(s, summary.string())) {
      row.selected = true;
      row.score = g->scores.total;
      if (!g->views.empty()) row.views = static_cast<int>(g->views.size());
      const grasp::ObjectSurface surface(placed_on_table(*j.run, j.argv));
      row.on_mesh = grasp::place_grasp(surface, g->contacts, quality);
      const grasp::GraspQuality& q = row.on_mesh->worse().quality;
      row.force_closure = q.force_closure;
      row.epsilon = q.epsilon;
    }
  } catch (const std::exception& e) {
    row.reason = std::string("grasp not evaluated: ") + e.what() + (row.reason.empty() ? "" : "; " + row.reason);
  }
  return row;
}

}  // namespace fba::evaluate::batch
