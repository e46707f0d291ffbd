// grasp.synthesis's bookkeeping of the arm's reach on one model: which candidates the reach
// planner's check passed over and why (PassedOver), and which it was asked about (ReachCheck).
// The checks themselves are the component's (fba::motion's planner, when the build has it).
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <spdlog/logger.h>

#include <fba/parallel_for.hpp>

namespace fba::grasp {

// The candidates passed over because the arm cannot reach them, on one model: how many of each
// refusal (motion::Refusal's names), with the first one's reason.
struct PassedOver {
  struct Kind {
    int count = 0;
    std::string example;
  };
  std::map<std::string, Kind> kinds;
  std::size_t checked = 0;  // candidates checked
  int total = 0;            // passed over
  double seconds = 0;       // the checks' wall time, the model's obstacles included

  void add(const std::string& kind, const std::string& why) {
    Kind& k = kinds[kind];
    if (k.count++ == 0) k.example = why;
    ++total;
  }
  nlohmann::json json() const {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& [name, k] : kinds) j[name] = {{"count", k.count}, {"example", k.example}};
    return j;
  }
  // "2 (ik 1: no IK solution ...; approach 1: the straight approach fails: ...)"
  std::string text() const {
    std::string t = std::to_string(total) + " (";
    bool first = true;
    for (const auto& [name, k] : kinds) {
      t += (first ? "" : "; ") + name + " " + std::to_string(k.count) + ", e.g. " + k.example;
      first = false;
    }
    return t + ")";
  }
};

// Which candidates the arm reaches from where it stands: each checked when the selection first
// asks, and remembered; inactive (everything reachable) without the reach check or a joint state.
// The candidates after the one asked for are checked with it on the task's other threads (their
// verdicts count once asked for: the results do not depend on the threads). At most `budget`
// checks on a model get as far as inverse kinematics (the costly ones, tens of milliseconds each
// when the solver finds no solution); beyond them the rest are not checked, so not selected on
// this model, nor passed over.
struct ReachCheck {
  struct Verdict {
    bool ok = true;
    bool costly = false;  // it needed inverse kinematics
    std::string refusal, why;
    bool model = false;  // the carved model refused it (ReachPlan::model_blocked)
    bool start = false;  // the arm cannot start from where it stands (Refusal::Start): the same for every candidate
  };
  bool active = false;
  PassedOver passed;
  std::size_t budget = 0, costly = 0;
  std::size_t unchecked = 0;       // candidates asked for once the budget was spent
  std::vector<signed char> state;  // per candidate: -1 not asked yet, 0 passed over, 1 reachable, 2 not checked
  std::vector<std::size_t> model_blocked;  // passed over, the robot in the model (occupied or not yet carved), in order
  std::vector<std::optional<Verdict>> ahead;
  std::function<void()> prepare;  // once, before the first check (the model's obstacles)
  std::function<Verdict(std::size_t)> check;  // thread-safe
  std::function<Verdict(std::size_t)> check_plan;  // the whole plan, from where the arm stands
  nlohmann::json start;  // for the candidate selected: whether the arm starts from where it stands
  std::optional<std::size_t> selected;  // the candidate selected on this model
  fba::ParallelFor parallel_for;
  std::size_t batch = 1;
  spdlog::logger* log = nullptr;

  bool reachable(std::size_t i) {
    if (!active) return true;
    if (state[i] >= 0) return state[i] == 1;
    if (costly >= budget) {
      state[i] = 2;
      ++unchecked;
      return false;
    }
    if (!ahead[i]) run(i);
    const Verdict v = *ahead[i];
    log->debug("candidate {}: {}{}{}", i, v.ok ? "reachable" : "passed over, " + v.refusal, v.ok ? "" : ": ", v.why);
    ++passed.checked;
    costly += v.costly ? 1 : 0;
    state[i] = v.ok ? 1 : 0;
    if (!v.ok) passed.add(v.refusal, v.why);
    if (!v.ok && v.model) model_blocked.push_back(i);
    return v.ok;
  }
  bool passed_over(std::size_t i) const { return active && state[i] == 0; }
  // The whole plan for a candidate about to be selected (the path search is too costly for every
  // candidate): one whose path the planner does not find is passed over like the others. One the
  // arm cannot start from where it stands (its hand, opened for the candidate's pregrasp, in the
  // model with no way to back out, or in the table or the arm itself) is `start`: the opening is
  // the candidate's, so the caller tries the ones after it, and takes the first such (first_start)
  // all the same only when none of them starts either (start_anyway), saying so.
  enum class Plan { ok, passed_over, start };
  Plan plannable(std::size_t i) {
    if (!active || !check_plan) return Plan::ok;
    const Verdict v = check_plan(i);
    if (v.ok) {
      start = "clear";
      return Plan::ok;
    }
    if (v.start) {
      log->debug("candidate {}: the arm cannot start its reach from where it stands, {}: {}", i, v.refusal, v.why);
      if (!first_start) first_start = FirstStart{i, v.refusal, v.why};
      return Plan::start;
    }
    log->debug("candidate {}: passed over at selection, {}: {}", i, v.refusal, v.why);
    state[i] = 0;
    passed.add(v.refusal, v.why);
    return Plan::passed_over;
  }
  struct FirstStart {
    std::size_t candidate;
    std::string refusal, why;
  };
  std::optional<FirstStart> first_start;  // since the selection began
  // The first candidate the arm could not start for, taken all the same: its refusal is the result's
  // `start`.
  std::size_t start_anyway() {
    start = nlohmann::json{{"refusal", first_start->refusal}, {"reason", first_start->why}};
    log->warn("the arm cannot start the selected grasp's reach from where it stands ({}): {}", first_start->refusal, first_start->why);
    return first_start->candidate;
  }
  std::string unchecked_text() const {
    return unchecked == 0 ? "" : "; " + std::to_string(unchecked) + " not checked (reach_checks: " + std::to_string(budget) + ")";
  }

 private:
  // Candidate i and the next ones not asked for yet, one per thread.
  void run(std::size_t i) {
    const auto start = std::chrono::steady_clock::now();
    if (prepare) std::exchange(prepare, nullptr)();
    std::vector<std::size_t> next{i};
    for (std::size_t j = i + 1; j < state.size() && next.size() < batch; ++j)
      if (state[j] < 0 && !ahead[j]) next.push_back(j);
    auto one = [&](std::size_t k) { ahead[next[k]] = check(next[k]); };
    if (parallel_for && next.size() > 1) parallel_for(next.size(), one);
    else for (std::size_t k = 0; k < next.size(); ++k) one(k);
    passed.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
};

}  // namespace fba::grasp
