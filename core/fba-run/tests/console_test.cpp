// fba-run's console on its own: what it writes for a run's samples, on a terminal and not, read
// back from a pipe.
#include "console.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <string>

namespace {

using fba_run::Console;

// Samples of a task whose component "synthesis" has stages and reports views, with max_views 10.
struct ConsoleRun {
  fba::TaskConfig config;
  int fds[2] = {-1, -1};
  ConsoleRun() {
    fba::ComponentConfig c;
    c.name = "synthesis";
    c.params["max_views"] = std::int64_t{10};
    config.components.push_back(c);
    EXPECT_EQ(::pipe2(fds, O_NONBLOCK), 0);
  }
  ~ConsoleRun() {
    ::close(fds[0]);
    ::close(fds[1]);
  }
  static fba::RunResult sample(double t, const std::string& stage, int views, const std::string& state = "idle",
                               std::uint64_t calls = 0) {
    fba::RunResult r;
    r.wall_s = t;
    fba::ComponentStats c;
    c.name = "synthesis";
    c.stage = stage;
    c.state = state;
    c.invocations = calls;
    if (views > 0) c.results["views"] = std::to_string(views);
    r.components.push_back(c);
    return r;
  }
  std::string written() const {
    std::string s;
    char buffer[4096];
    for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) > 0;) s.append(buffer, static_cast<std::size_t>(n));
    return s;
  }
};

TEST(ConsoleSteps, AStepIsAComponentsStageAndItsViewOfItsLimit) {
  ConsoleRun run;
  const auto steps = fba_run::steps_of(ConsoleRun::sample(1, "exploration_movement", 3), run.config);
  ASSERT_EQ(steps.size(), 1u);
  EXPECT_EQ(fba_run::step_text(steps[0]), "synthesis: exploration_movement, view 3 of 10");
  EXPECT_TRUE(fba_run::steps_of(ConsoleRun::sample(1, "", 0), run.config).empty());
}

TEST(Console, WithoutATerminalALineIsWrittenPerChangeNotPerSample) {
  ConsoleRun run;
  Console console(run.config, run.fds[1], false);
  fba::RunResult previous = ConsoleRun::sample(0.1, "visual_analysis", 0);
  console.update(previous, nullptr);
  for (double t = 0.2; t < 1; t += 0.1) console.update(ConsoleRun::sample(t, "visual_analysis", 0), &previous);
  console.update(ConsoleRun::sample(1.5, "grasp_synthesis", 1), &previous);
  console.update(ConsoleRun::sample(1.6, "grasp_synthesis", 1), &previous);
  EXPECT_EQ(run.written(), "[0.1 s] synthesis: visual_analysis\n[1.5 s] synthesis: grasp_synthesis, view 1 of 10\n");
}

TEST(Console, WithoutATerminalALongCallIsSaidOnce) {
  ConsoleRun run;
  Console console(run.config, run.fds[1], false);
  fba::RunResult a = ConsoleRun::sample(0.1, "exploration_movement", 2, "running", 7);
  console.update(a, nullptr);
  fba::RunResult b = ConsoleRun::sample(1.2, "exploration_movement", 2, "running", 7);
  console.update(b, &a);
  console.update(ConsoleRun::sample(2.5, "exploration_movement", 2, "running", 7), &b);
  EXPECT_EQ(run.written(),
            "[0.1 s] synthesis: exploration_movement, view 2 of 10\n[1.2 s] synthesis: busy in one call for 1.1 s\n");
}

TEST(Console, OnATerminalTheLineIsRedrawnAndAFinishedStepKeepsItsLine) {
  ConsoleRun run;
  Console console(run.config, run.fds[1], true);
  fba::RunResult a = ConsoleRun::sample(0.1, "visual_analysis", 0);
  console.update(a, nullptr);
  console.update(ConsoleRun::sample(0.6, "visual_analysis", 0), &a);
  console.update(ConsoleRun::sample(0.9, "grasp_synthesis", 1), &a);
  console.close();
  EXPECT_EQ(run.written(),
            "[0.1 s] synthesis: visual_analysis (0 s)"
            "\r\033[K[0.1 s] synthesis: visual_analysis (0.5 s)"
            "\n[0.9 s] synthesis: grasp_synthesis, view 1 of 10 (0 s)"
            "\r\033[K");
}

TEST(Console, TextWrittenAboveTheLineClearsItAndDrawsItAgain) {
  ConsoleRun run;
  Console console(run.config, run.fds[1], true);
  console.update(ConsoleRun::sample(0.1, "visual_analysis", 0), nullptr);
  console.above([&] { ASSERT_EQ(::write(run.fds[1], "a log line\n", 11), 11); });
  EXPECT_EQ(run.written(),
            "[0.1 s] synthesis: visual_analysis (0 s)"
            "\r\033[Ka log line\n"
            "[0.1 s] synthesis: visual_analysis (0 s)");
}

TEST(Console, NothingIsDrawnAfterClose) {
  ConsoleRun run;
  Console console(run.config, run.fds[1], true);
  console.close();
  console.update(ConsoleRun::sample(0.1, "visual_analysis", 0), nullptr);
  console.above([&] { ASSERT_EQ(::write(run.fds[1], "last\n", 5), 5); });
  EXPECT_EQ(run.written(), "last\n");
}

}  // namespace
