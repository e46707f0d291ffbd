// fba-run's last line (see outcome_text.hpp). The words come from what the task's components
// report (Context::report) under the names the grasp loop's components use: "views" (the views a
// model was made of), "grasp" (the selected grasp, its scores and its epsilon), "lift" (the hand's lift test:
// held or not) and "failure" (why a component gave up). A task whose components report none of them
// gets the final event and the samples its sensors produced.
#include "outcome_text.hpp"

#include <cmath>
#include <cstdio>
#include <optional>

#include <nlohmann/json.hpp>

#include "fba/message_text.hpp"

namespace fba_run {

namespace {

using json = nlohmann::json;

// Longer payloads and reasons are summary.json's to hold: the line stays one line.
constexpr std::size_t kMaxShown = 160;

std::string shortened(const std::string& s) {
  std::string one_line = s.substr(0, s.find('\n'));
  if (one_line.size() > kMaxShown) one_line = one_line.substr(0, kMaxShown) + "...";
  else if (one_line.size() < s.size()) one_line += " ...";
  return fba::escape_controls(one_line);
}

std::string number(double v, int significant) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*g", significant, v);
  return text;
}

struct Reported {
  json value;
  std::string component;
};

// The first component's result of that name that is valid JSON.
std::optional<Reported> reported(const fba::RunResult& r, const std::string& name) {
  for (const auto& c : r.components)
    if (const auto it = c.results.find(name); it != c.results.end()) {
      json j = json::parse(it->second, nullptr, false);
      if (!j.is_discarded()) return Reported{std::move(j), c.name};
    }
  return std::nullopt;
}

// "after 5 views", when a component reported how many views its model was made of.
std::string views_text(const fba::RunResult& r) {
  const auto views = reported(r, "views");
  if (!views || !views->value.is_number_integer()) return {};
  const auto n = views->value.get<long long>();
  return "after " + std::to_string(n) + (n == 1 ? " view" : " views");
}

// "grasp score 0.53, epsilon 0.057", from the selected grasp's scores and its force-closure
// quality (the Ferrari-Canny epsilon on the model, "model_epsilon"), each when reported.
std::string grasp_text(const fba::RunResult& r) {
  const auto grasp = reported(r, "grasp");
  if (!grasp || !grasp->value.is_object()) return {};
  std::string s;
  const json& scores = grasp->value.value("scores", json::object());
  if (scores.is_object() && scores.contains("total") && scores["total"].is_number())
    s = "grasp score " + number(scores["total"].get<double>(), 2);
  if (const auto eps = grasp->value.find("model_epsilon"); eps != grasp->value.end() && eps->is_number())
    s += (s.empty() ? "" : ", ") + std::string("epsilon ") + number(eps->get<double>(), 2);
  return s;
}

// Joins the parts that are not empty: "held the object after 5 views, grasp score 0.53".
std::string joined(const std::string& head, const std::string& after, std::initializer_list<std::string> rest) {
  std::string s = head;
  if (!after.empty()) s += " " + after;
  for (const auto& part : rest)
    if (!part.empty()) s += ", " + part;
  return s;
}

// "event sink.done (100000)": the event, and its payload when it is short enough for the line.
std::string event_text(const fba::RunResult& r) {
  if (!r.final_event) return shortened(r.reason);
  std::string s = "event " + fba::escape_controls(r.final_event->source + "." + r.final_event->name);
  const std::string& payload = r.final_event->payload;
  if (!payload.empty() && payload.size() <= 40 && payload.find('\n') == std::string::npos) s += " (" + fba::escape_controls(payload) + ")";
  return s;
}

// "200000 samples": what the task's sensors produced.
std::string samples_text(const fba::RunResult& r) {
  std::uint64_t samples = 0;
  bool sensors = false;
  for (const auto& c : r.components)
    if (c.kind == fba::Kind::Sensor) {
      sensors = true;
      samples += c.samples_out;
    }
  if (!sensors) return {};
  return std::to_string(samples) + (samples == 1 ? " sample" : " samples");
}

std::string success_text(const fba::RunResult& r) {
  const std::string took = seconds_text(r.wall_s);
  if (const auto lift = reported(r, "lift"); lift && lift->value.is_object() && lift->value.value("held", false))
    return joined("held the object", views_text(r), {grasp_text(r), took});
  const std::string samples = samples_text(r);
  return "success: " + event_text(r) + ", " + (samples.empty() ? took : samples + " in " + took);
}

std::string failure_text(const fba::RunResult& r) {
  const std::string took = seconds_text(r.wall_s);
  if (const auto gave_up = reported(r, "failure"); gave_up && gave_up->value.is_string())
    return joined("failed: " + gave_up->component + " gave up", views_text(r), {took}) + " (" +
           shortened(gave_up->value.get<std::string>()) + ")";
  if (const auto lift = reported(r, "lift"); lift && lift->value.is_object() && !lift->value.value("held", true)) {
    std::string why = lift->value.value("reason", std::string());
    return joined("failed: the object was not held", views_text(r), {grasp_text(r), took}) + (why.empty() ? "" : " (" + shortened(why) + ")");
  }
  return "failed: " + event_text(r) + ", " + took;
}

}  // namespace

std::string seconds_text(double s) {
  if (!(s >= 0) || !std::isfinite(s)) return "? s";
  if (s > 0 && s < 0.01) return number(s * 1000, 2) + " ms";
  if (s < 10) return number(s, 2) + " s";
  if (s < 120) return std::to_string(static_cast<long long>(std::lround(s))) + " s";
  const long long whole = std::llround(s);
  return std::to_string(whole / 60) + " min " + std::to_string(whole % 60) + " s";
}

std::string outcome_text(const fba::RunResult& r) {
  switch (r.outcome) {
    case fba::Outcome::Success: return success_text(r);
    case fba::Outcome::Failure: return failure_text(r);
    default: break;
  }
  // Errors and interruptions: their reason already says what happened, the final event's payload
  // (an error's message) what went wrong.
  std::string s = std::string(fba::to_string(r.outcome)) + ": " + fba::escape_controls(r.reason);
  if (r.final_event && !r.final_event->payload.empty()) s += " (" + shortened(r.final_event->payload) + ")";
  return s + ", " + seconds_text(r.wall_s);
}

}  // namespace fba_run
