// fba-run's last line: the outcome in words, from the final event and the components' results.
#include "outcome_text.hpp"

#include <gtest/gtest.h>

namespace {

using fba_run::outcome_text;

fba::ComponentStats component(const std::string& name, fba::Kind kind, std::map<std::string, std::string> results = {}) {
  fba::ComponentStats c;
  c.name = name;
  c.kind = kind;
  c.results = std::move(results);
  return c;
}

fba::RunResult result(fba::Outcome outcome, double wall_s, std::vector<fba::ComponentStats> components = {}) {
  fba::RunResult r;
  r.outcome = outcome;
  r.wall_s = wall_s;
  r.components = std::move(components);
  return r;
}

fba::Event event(const std::string& source, const std::string& name, const std::string& payload) {
  fba::Event e;
  e.source = source;
  e.name = name;
  e.payload = payload;
  return e;
}

TEST(OutcomeText, AHeldObjectIsSaidWithItsViewsScoreEpsilonAndTime) {
  const std::string lift = R"({"held": true, "slip_m": 0.0017, "contacts": [)" + std::string(1500, ' ') + "]}";
  auto r = result(fba::Outcome::Success, 2.8,
                  {component("synthesis", fba::Kind::Filter,
                             {{"views", "5"}, {"grasp", R"({"scores": {"total": 0.5251, "symmetry": 0.05}, "model_epsilon": 0.05713})"}}),
                   component("hand", fba::Kind::Actuator, {{"lift", lift}})});
  r.final_event = event("hand", "held", lift);
  EXPECT_EQ(outcome_text(r), "held the object after 5 views, grasp score 0.53, epsilon 0.057, 2.8 s");
}

// A grasp reported without its epsilon (a synthesis of another plugin, a summary of an older
// fba) is said with what it has: the line names no number that was not reported.
TEST(OutcomeText, AGraspWithoutEpsilonIsSaidWithItsScoreOnly) {
  auto r = result(fba::Outcome::Success, 2.8,
                  {component("synthesis", fba::Kind::Filter, {{"views", "5"}, {"grasp", R"({"scores": {"total": 0.5251}})"}}),
                   component("hand", fba::Kind::Actuator, {{"lift", R"({"held": true})"}})});
  EXPECT_EQ(outcome_text(r), "held the object after 5 views, grasp score 0.53, 2.8 s");
  r.components[0].results["grasp"] = R"({"model_epsilon": 0.1234})";
  EXPECT_EQ(outcome_text(r), "held the object after 5 views, epsilon 0.12, 2.8 s");
}

TEST(OutcomeText, APlainTaskSaysItsEventAndTheSamplesOfItsSensors) {
  auto source = component("source", fba::Kind::Sensor);
  source.samples_out = 200000;
  auto r = result(fba::Outcome::Success, 0.4129, {source, component("sink", fba::Kind::Actuator)});
  r.final_event = event("sink", "done", "200000");
  EXPECT_EQ(outcome_text(r), "success: event sink.done (200000), 200000 samples in 0.41 s");
}

TEST(OutcomeText, AComponentThatGaveUpIsNamedWithItsReason) {
  auto r = result(fba::Outcome::Failure, 31,
                  {component("synthesis", fba::Kind::Filter, {{"views", "10"}, {"failure", R"("no reachable grasp")"}})});
  r.final_event = event("synthesis", "grasp_synthesis_failed", "no reachable grasp");
  EXPECT_EQ(outcome_text(r), "failed: synthesis gave up after 10 views, 31 s (no reachable grasp)");
}

TEST(OutcomeText, ADroppedObjectIsAFailureWithTheHandsReason) {
  const auto r = result(
      fba::Outcome::Failure, 3.14,
      {component("synthesis", fba::Kind::Filter, {{"views", "1"}, {"grasp", R"({"scores": {"total": 0.7}, "model_epsilon": 0.02})"}}),
       component("hand", fba::Kind::Actuator, {{"lift", R"({"held": false, "reason": "slipped 4 cm"})"}})});
  EXPECT_EQ(outcome_text(r), "failed: the object was not held after 1 view, grasp score 0.7, epsilon 0.02, 3.1 s (slipped 4 cm)");
}

TEST(OutcomeText, ALongPayloadStaysInTheSummary) {
  auto r = result(fba::Outcome::Failure, 1);
  r.final_event = event("check", "bad", std::string(2000, 'x'));
  EXPECT_EQ(outcome_text(r), "failed: event check.bad, 1 s");
}

TEST(OutcomeText, AnErrorKeepsItsReasonAndAShortenedMessage) {
  auto r = result(fba::Outcome::RuntimeError, 0.05);
  r.reason = "component 'bad' (examples.faulty) failed: injected fault";
  r.final_event = event("bad", "error", "injected \x1b[2J fault\nsecond line");
  const std::string text = outcome_text(r);
  EXPECT_EQ(text.rfind("runtime_error: component 'bad' (examples.faulty) failed: injected fault (injected ", 0), 0u) << text;
  EXPECT_EQ(text.find('\x1b'), std::string::npos) << text;  // control bytes escaped
  EXPECT_EQ(text.find('\n'), std::string::npos) << text;
  EXPECT_NE(text.find(", 0.05 s"), std::string::npos) << text;
}

TEST(OutcomeText, DurationsReadAsPeopleWriteThem) {
  EXPECT_EQ(fba_run::seconds_text(0.00173), "1.7 ms");
  EXPECT_EQ(fba_run::seconds_text(0.0304), "0.03 s");
  EXPECT_EQ(fba_run::seconds_text(2.84), "2.8 s");
  EXPECT_EQ(fba_run::seconds_text(42.4), "42 s");
  EXPECT_EQ(fba_run::seconds_text(192), "3 min 12 s");
}

}  // namespace
