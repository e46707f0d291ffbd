// fba-run's console as people see it: a line per stage or view, updated in place on a terminal
// (a pseudo-terminal here), a plain line per change otherwise, the log above the progress line, the
// outcome in words last, and --log-level per component. The task's test.stepper takes each view
// when the test creates its gate file, so every step is waited for, never timed.
#include <gtest/gtest.h>

#include <signal.h>

#include <fstream>
#include <string>

#include "support/build_paths.hpp"
#include "support/child_process.hpp"
#include "support/temp_dir.hpp"

namespace {

namespace fs = std::filesystem;
using fba::test::Child;

std::string stepping_plugins() { return fba::test::binary_dir() + "/tests/tasks/stepping/plugins"; }

// A task of three views, each let through by the file gate/N.
struct StepperTask {
  fba::test::TempDir dir{"console"};
  fs::path gate = dir.path() / "gate";
  fs::path file = dir.path() / "steps.yaml";
  StepperTask() {
    fs::create_directories(gate);
    std::ofstream(file) << "components:\n"
                           "  stepper: { type: test.stepper, params: { max_views: 3, gate: " << gate.string() << " } }\n"
                           "  sink: { type: examples.sink }\n"
                           "connections: [ stepper.out -> sink.in ]\n";
  }
  void let(int view) const { std::ofstream(gate / std::to_string(view)) << "go\n"; }
  // Lets the three views through in turn, each after the run shows `line` + "N of 3" (view 1's wait
  // is the caller's).
  void let_each(const Child& run, const std::string& line) const {
    for (int view = 1; view <= 3; ++view) {
      if (view > 1) run.read_until(line + std::to_string(view) + " of 3");
      let(view);
    }
  }
  // fba-run on the task with the stepping plugins, `options` before the task's file.
  Child run(std::vector<std::string> options = {}, fba::test::ChildOptions child = {}) const {
    std::vector<std::string> args{fba::test::program("fba-run"), "-p", stepping_plugins()};
    args.insert(args.end(), options.begin(), options.end());
    args.push_back(file.string());
    return Child(std::move(args), std::move(child));
  }
};

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(Console, WithoutATerminalEachViewIsOnePlainLineAndALongCallIsSaidOnce) {
  StepperTask task;
  Child run = task.run();
  // The first view's call lasts until the test lets it end: said once as a long call.
  EXPECT_NE(run.read_until("stepper: busy in one call for").find("stepper: waiting, view 1 of 3"), std::string::npos);
  task.let_each(run, "stepper: waiting, view ");
  ASSERT_EQ(run.wait(0), 0);
  const std::string out = run.read_until("\x01", std::chrono::milliseconds(0));
  EXPECT_EQ(out.find('\r'), std::string::npos) << out;  // nothing redrawn in place
  EXPECT_EQ(out.find("\033["), std::string::npos) << out;
  // A sample may also catch a view as it starts ("looking"); the wait for its gate is one line.
  for (const char* view : {"waiting, view 1 of 3", "waiting, view 2 of 3", "waiting, view 3 of 3"})
    EXPECT_EQ(count(out, view), 1u) << view << "\n" << out;
  EXPECT_EQ(count(out, "busy in one call"), 1u) << out;
  // The last line is the outcome in words, not the final event's payload.
  const auto last = out.substr(out.rfind('\n', out.size() - 2) + 1);
  EXPECT_EQ(last.rfind("fba-run: success: ", 0), 0u) << last;
  EXPECT_NE(last.find("3 samples in "), std::string::npos) << last;
}

TEST(Console, OnATerminalTheLineIsUpdatedInPlaceAndEachViewKeepsItsOwnLine) {
  StepperTask task;
  Child run = task.run({}, {.terminal = true});
  // The first view's line is redrawn (its time in the view grows) until the call counts as long.
  run.read_until("stepper busy for");
  task.let_each(run, "view ");
  ASSERT_EQ(run.wait(0), 0);
  const std::string out = run.read_until("\x01", std::chrono::milliseconds(0));
  EXPECT_GE(count(out, "\r\033[K"), 2u) << out;  // erased and drawn again
  // Each view's line, once finished, stays: a newline ends it before the next view's.
  const auto first = out.rfind("view 1 of 3"), second = out.find("view 2 of 3");
  ASSERT_NE(first, std::string::npos) << out;
  ASSERT_NE(second, std::string::npos) << out;
  EXPECT_NE(out.substr(first, second - first).find('\n'), std::string::npos) << out;
  // The log lines come whole, never inside a progress line: each begins where a line begins, or
  // where the progress line was erased ("[12:00:00.000] [stepper] info: view 1 taken").
  ASSERT_EQ(count(out, "] [stepper] "), 3u) << out;
  for (auto at = out.find("] [stepper] "); at != std::string::npos; at = out.find("] [stepper] ", at + 1)) {
    ASSERT_GE(at, 13u);
    const std::size_t stamp = at - 13;  // "[hh:mm:ss.mmm"
    EXPECT_EQ(out[stamp], '[') << out.substr(stamp, 60);
    if (stamp == 0) continue;  // the output's first line
    EXPECT_TRUE(out[stamp - 1] == '\n' || (stamp >= 3 && out.compare(stamp - 3, 3, "\033[K") == 0)) << out.substr(stamp - std::min<std::size_t>(stamp, 20), 80);
  }
  // The progress line is cleared before the outcome, which is the last line.
  const auto outcome = out.rfind("fba-run: success: ");
  ASSERT_NE(outcome, std::string::npos) << out;
  EXPECT_EQ(out.substr(outcome - 4, 4), "\r\033[K") << out;
}

TEST(Console, OnATerminalASignalsMessageGoesAboveTheProgressLine) {
  StepperTask task;
  Child run = task.run({}, {.terminal = true});
  run.read_until("view 1 of 3 (");  // the progress line is drawn
  EXPECT_EQ(run.wait(SIGINT), 130);
  const std::string out = run.read_until("\x01", std::chrono::milliseconds(0));
  const auto at = out.find("fba-run: SIGINT received: stopping in order");
  ASSERT_NE(at, std::string::npos) << out;
  ASSERT_GE(at, 3u);
  EXPECT_EQ(out.substr(at - 3, 3), "\033[K") << out;  // the line was erased first, not written onto
}

TEST(Console, AComponentsLogLevelIsItsOwn) {
  StepperTask task;
  task.let(1);
  task.let(2);
  task.let(3);
  // sink logs its safe state at info: kept at info, dropped at warn, only for it.
  const auto with = [&](const std::string& level) {
    Child run = task.run({"--log-level", level});
    EXPECT_EQ(run.wait(0), 0);
    return run.read_until("\x01", std::chrono::milliseconds(0));
  };
  EXPECT_NE(with("sink=info").find("[sink] info: safe state reached"), std::string::npos);
  EXPECT_EQ(with("sink=warn").find("[sink] info"), std::string::npos);
  EXPECT_EQ(with("warn").find("[sink] info"), std::string::npos);
}

TEST(Console, AnUnknownComponentInLogLevelIsRefusedWithTheNames) {
  StepperTask task;
  Child run = task.run({"--log-level", "carver=debug"});
  EXPECT_EQ(run.wait(0), 2);
  const std::string out = run.read_until("\x01", std::chrono::milliseconds(0));
  EXPECT_NE(out.find("--log-level carver=debug: the task has no component 'carver'; its components are sink, stepper"),
            std::string::npos) << out;
}

TEST(Console, ALogLevelForACompositeInstanceReachesTheComponentsInside) {
  // tasks/examples/composite.yaml: the instance "relay" holds relay/first and relay/second.
  const std::string composite = fba::test::tasks_dir() + "/examples/composite.yaml";
  Child ok({fba::test::program("fba-run"), "--check", "--log-level", "relay=debug", composite});
  EXPECT_EQ(ok.wait(0), 0) << ok.read_until("\x01", std::chrono::milliseconds(0));
  Child bad({fba::test::program("fba-run"), "--check", "--log-level", "rel=debug", composite});
  EXPECT_EQ(bad.wait(0), 2);
  EXPECT_NE(bad.read_until("\x01", std::chrono::milliseconds(0)).find("the task has no component 'rel'"), std::string::npos);
  Child level({fba::test::program("fba-run"), "--log-level", "relay=loud", composite});
  EXPECT_EQ(level.wait(0), 2);
  EXPECT_NE(level.read_until("\x01", std::chrono::milliseconds(0)).find("log level 'loud' is not one of"), std::string::npos);
}

}  // namespace
