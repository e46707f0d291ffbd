// A signal at any moment of a run, from fba-run's start to its steady state, ends in order: every
// catchable signal whose default action ends the process (SIGHUP from a closed terminal, SIGQUIT,
// SIGALRM, a SIGSEGV sent by kill...) exits 128 + N with a valid summary.json that says so.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <set>

#include <nlohmann/json.hpp>

#include "support/fba_run.hpp"
#include "support/build_paths.hpp"

namespace {

using namespace fba::test;

const char* kTask = R"(
components:
  src: { type: examples.counter, params: { count: 1000000000, rate: 1000 } }
  act: { type: test.misbehaving_actuator }
connections: [ src.out -> act.in ]
)";

TEST(RandomSignal, EveryTerminatingSignalAtRandomMomentsEndsTheRunInOrder) {
  const fs::path dir = temp_dir("random-signal");
  const fs::path task = dir / "task.yaml";
  std::ofstream(task) << kTask;
  std::mt19937 random(20261124);  // seeded: a failure can be replayed
  // From 10 us to 0.4 s, log-uniform: as many signals in the first milliseconds (plugins
  // loading, components constructing) as while running; under AddressSanitizer, where loading
  // alone takes most of a second, most land while loading.
  std::uniform_real_distribution<double> log_delay(std::log(10.0), std::log(400'000.0));
  auto delay_us = [&](std::mt19937& r) { return static_cast<long>(std::exp(log_delay(r))); };
  int in_loading = 0, in_running = 0;
  const std::vector<int> signals = terminating_signals();
  std::set<int> sent;
  for (int i = 0; i < 150; ++i) {
    // Each signal at least once (the first rounds take them in turn), then drawn at random.
    const int sig = i < static_cast<int>(signals.size()) ? signals[i] : signals[random() % signals.size()];
    sent.insert(sig);
    const auto delay = std::chrono::microseconds(delay_us(random));
    const fs::path out = dir / std::to_string(i);
    Child p(fba_run_command({task.string(), "--plugin-path", misbehaving_plugins(), "--output-dir", out.string()}), {.signals_blocked = true});
    std::this_thread::sleep_for(delay);
    p.signal(sig);
    const auto r = p.wait();
    const std::string what = "run " + std::to_string(i) + ", signal " + std::to_string(sig) + " (" + strsignal(sig) +
                             ") after " + std::to_string(delay.count()) + " us:\n" + r.output;
    ASSERT_EQ(r.status, 128 + sig) << what;
    const auto summary = nlohmann::json::parse(read_file(out / "summary.json"), nullptr, false);
    ASSERT_TRUE(summary.is_object()) << what;
    EXPECT_EQ(summary["outcome"], "interrupted") << what;
    EXPECT_EQ(summary["exit_code"], r.status) << what;
    const std::string phase = summary.value("phase", "");
    EXPECT_TRUE(phase == "loading" || phase == "constructing" || phase == "running") << what;
    if (phase == "running") {
      ++in_running;
      EXPECT_TRUE(fs::exists(out / "safe_state.act")) << what;  // constructed actuators go safe
    } else {
      ++in_loading;
    }
  }
  EXPECT_EQ(sent.size(), signals.size());
  std::cout << "signals during loading or construction: " << in_loading << ", while running: " << in_running << "\n";
}

// A fault signal sent by kill(2) while fba-run is still being loaded (blocked from exec, as a
// supervisor may start it) arrives when its first code unblocks the faults, before any library's
// initialiser has run: it is a stop request like any other. Its handler once built fba-run's state
// from there, before libstdc++'s initialisation, and the run then ignored the signal for good.
TEST(RandomSignal, AFaultSignalPendingSinceExecStopsTheRunInOrder) {
  const fs::path dir = temp_dir("pending-fault");
  const fs::path task = dir / "task.yaml";
  std::ofstream(task) << kTask;
  for (const int sig : {SIGSYS, SIGTRAP, SIGSEGV, SIGABRT, SIGBUS, SIGFPE, SIGILL}) {
    const fs::path out = dir / std::to_string(sig);
    Child p(fba_run_command({task.string(), "--plugin-path", misbehaving_plugins(), "--output-dir", out.string()}), {.signals_blocked = true});
    p.signal(sig);
    const auto r = p.wait();
    const std::string what = std::string(strsignal(sig)) + ":\n" + r.output;
    EXPECT_EQ(r.status, 128 + sig) << what;
    const auto summary = nlohmann::json::parse(read_file(out / "summary.json"), nullptr, false);
    ASSERT_TRUE(summary.is_object()) << what;
    EXPECT_EQ(summary["outcome"], "interrupted") << what;
    EXPECT_EQ(summary["signal"], sig) << what;
  }
}

}  // namespace
