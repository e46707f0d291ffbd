// fba-run's contract with the shell: exit statuses, signals, --check, --dot, --output-dir.
#include <gtest/gtest.h>

#include <chrono>

#include <thread>

#include <nlohmann/json.hpp>

#include "support/fba_run.hpp"
#include "support/build_paths.hpp"

namespace {

using namespace fba::test;

std::string task(const std::string& name) { return fba::test::tasks_dir() + "/examples/" + name; }

std::string write_task(const std::string& name, const std::string& text) {
  const fs::path p = temp_dir("task") / name;
  std::ofstream(p) << text;
  return p.string();
}

const char* kLong = R"(
components:
  src: { type: examples.counter, params: { count: 1000000000 } }
  slow: { type: examples.sink, params: { delay: 0.001 } }
connections: [ src.out -> slow.in ]
)";

}  // namespace

TEST(Cli, SuccessExitsZero) {
  const auto r = fba_run({task("chain.yaml")});
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("success: event sink.done"), std::string::npos) << r.output;
}

TEST(Cli, FailureEventExitsOne) {
  const auto r = fba_run({task("chain.yaml"), "--set", "sink.expected=0", "--set", "source.count=3"});
  EXPECT_EQ(r.status, 0) << r.output;  // no done event, but every sensor finished
  const auto f = write_task("fail.yaml", R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  sink: { type: examples.sink }
connections: [ src.out -> sink.in ]
on: { src.finished: stop_failure }
)");
  EXPECT_EQ(fba_run({f}).status, 1);
}

TEST(Cli, ConfigurationErrorExitsTwoWithFileLineColumn) {
  const auto f = write_task("bad.yaml", "components:\n  a: { type: examples.counter, params: { count: x } }\n");
  const std::string out = refusal({f});
  EXPECT_NE(out.find("bad.yaml:2:"), std::string::npos) << out;
  EXPECT_EQ(fba_run({"--no-such-option"}).status, 2);
  EXPECT_EQ(fba_run({"/nonexistent/task.yaml"}).status, 2);
}

TEST(Cli, RuntimeErrorExitsThree) {
  const auto f = write_task("fault.yaml", R"(
components:
  src: { type: examples.counter, params: { count: 100 } }
  bad: { type: examples.faulty, params: { fail_after: 3 } }
  sink: { type: examples.sink }
connections: [ src.out -> bad.in, bad.out -> sink.in ]
)");
  const auto r = fba_run({f});
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.output.find("component 'bad' (examples.faulty) failed: injected fault"), std::string::npos) << r.output;
}

TEST(Cli, ControlBytesInARuntimeErrorReachTheTerminalEscaped) {
  // The component's message echoes a parameter with an ESC sequence that would clear the screen.
  const auto f = write_task("fault.yaml", "components:\n"
                                          "  src: { type: examples.counter, params: { count: 100 } }\n"
                                          "  bad: { type: examples.faulty, params: { fail_after: 1, message: \"bad\\e[2Jmsg\" } }\n"
                                          "  sink: { type: examples.sink }\n"
                                          "connections: [ src.out -> bad.in, bad.out -> sink.in ]\n");
  const fs::path out = temp_dir("escaped");
  const auto r = fba_run({f, "-o", out.string()});
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_EQ(r.output.find('\x1b'), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("fba-run: runtime_error: component 'bad' (examples.faulty) failed: bad\\x1b[2Jmsg"), std::string::npos)
      << r.output;
}

TEST(Cli, ARestartThatRecoveredSucceedsAndTheLastLineCountsTheLostSamples) {
  const fs::path out = temp_dir("restart");
  const auto f = write_task("restart.yaml", R"(
components:
  src: { type: examples.counter, params: { count: 12 } }
  bad: { type: examples.faulty, params: { fail_after: 5 }, on_error: { policy: restart, max_restarts: 2 } }
  act: { type: test.misbehaving_actuator }
connections: [ src.out -> bad.in, bad.out -> act.in ]
)");
  const auto r = fba_run({f, "--output-dir", out.string(), "--plugin-path", misbehaving_plugins()});
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("; 2 sample(s) lost to 2 restart(s)"), std::string::npos) << r.output;
  const auto summary = nlohmann::json::parse(read_file(out / "summary.json"));
  EXPECT_EQ(summary["lost_to_restarts"], 2);
  EXPECT_EQ(summary["components"]["bad"]["lost_to_restarts"], 2);
}

TEST(Cli, TimeoutExitsThree) {
  const auto r = fba_run({write_task("long.yaml", kLong), "--timeout", "0.2"});
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.output.find("timed out"), std::string::npos) << r.output;
}

// At once, while fba-run is still starting: the signal waits for the watcher, which stops the
// run in order whatever the phase (the summary says which).
TEST(Cli, ATimeoutThatIsNotANumberIsRefused) {
  // NaN compares false with every bound: it was taken as "no limit".
  const std::string nan = refusal({task("chain.yaml"), "--timeout", "nan"});
  EXPECT_NE(nan.find("--timeout must be a number of seconds >= 0"), std::string::npos) << nan;
  // The value found is shown as written, not rounded to six decimals ("-0.250000", or "-0.000000"
  // for a value that is not zero).
  const std::string small = refusal({task("chain.yaml"), "--timeout", "-0.25"});
  EXPECT_NE(small.find("(0: none); found '-0.25'\n"), std::string::npos) << small;
  const auto tiny = fba_run({task("chain.yaml"), "--timeout", "-1e-9"});
  EXPECT_NE(tiny.output.find("found '-1e-9'\n"), std::string::npos) << tiny.output;
}

// A number too large for a double is as much "no limit" as inf, which is taken: 1e400 was refused
// by the option parser. A stop grace too long for the clock likewise waits for ever (it overflowed
// the nanoseconds and acted as no grace at all: core/tests/shutdown_test.cpp).
TEST(Cli, TimesTooLargeForADoubleAreNoLimitLikeInfinity) {
  for (const char* option : {"--timeout", "--stop-grace"})
    for (const char* value : {"1e400", "inf", "1e10"}) {
      const auto r = fba_run({task("chain.yaml"), option, value});
      EXPECT_EQ(r.status, 0) << option << " " << value << ":\n" << r.output;
    }
  const std::string grace = refusal({task("chain.yaml"), "--stop-grace", "-1"});
  EXPECT_NE(grace.find("--stop-grace must be a number of seconds >= 0; found '-1'"), std::string::npos) << grace;
}

// An empty --output-dir or --profile is a mistake, not "none" or "the default".
TEST(Cli, AnEmptyOutputDirOrProfileIsRefused) {
  const std::string out = refusal({task("chain.yaml"), "-o", ""});
  EXPECT_NE(out.find("--output-dir is empty"), std::string::npos) << out;
  const std::string profile = refusal({task("chain.yaml"), "--profile", ""});
  EXPECT_NE(profile.find("--profile expects a profile's name (profiles/NAME.yaml beside the task) or a file; found an empty name"), std::string::npos)
      << profile;
}

// An option is refused as the option, before anything loads: it was checked only when the task
// started, and reported against the task file, which does not say --threads.
TEST(Cli, ThreadsOutOfRangeIsRefusedAsTheOption) {
  for (const char* value : {"-1", "257", "100000"}) {
    const std::string out = refusal({task("chain.yaml"), "--threads", value});
    EXPECT_NE(out.find(std::string("--threads must be in [0, 256] (0: the task file's, else one per core); found ") + value),
              std::string::npos)
        << out;
  }
  const auto ok = fba_run({task("chain.yaml"), "--threads", "256", "--check"});
  EXPECT_EQ(ok.status, 0) << ok.output;
}

TEST(Cli, SigintAndSigtermStopInOrderWith130And143) {
  for (int sig : {SIGINT, SIGTERM}) {
    const fs::path out = temp_dir("sig");
    Child p(fba_run_command({write_task("long.yaml", kLong), "--output-dir", out.string()}), {.signals_blocked = true});
    p.signal(sig);
    const auto r = p.wait();
    EXPECT_EQ(r.status, sig == SIGINT ? 130 : 143) << r.output;
    const std::string summary = read_file(out / "summary.json");
    EXPECT_NE(summary.find("\"outcome\": \"interrupted\""), std::string::npos) << summary;
    EXPECT_NE(summary.find("\"phase\": "), std::string::npos) << summary;
    EXPECT_NE(summary.find(sig == SIGINT ? "interrupted by SIGINT" : "interrupted by SIGTERM"), std::string::npos)
        << summary;
  }
}

// ---------------------------------------------------------------------------------------------
// Misbehaving components (tests/tasks/misbehaving): every way out ends with the documented
// exit status, a valid summary.json naming the cause, and the actuator's safe state attempted.

const char* kMisbehaving = R"(
components:
  act: { type: test.misbehaving_actuator, params: { mode: none } }
  src: { type: examples.counter, params: { count: 1000000000 } }
  bad: { type: test.misbehaving, params: { mode: none, after: 3 } }
connections: [ src.out -> bad.in, bad.out -> act.in ]
)";

struct Misbehaved {
  Result run;
  nlohmann::json summary;  // null when missing or not valid JSON
  bool safe_state = false;
  fs::path out;
};

// Runs kMisbehaving (or `task`) with the test plugin, a short grace, and extra arguments.
Misbehaved misbehave(std::vector<std::string> args, const std::string& task = kMisbehaving,
                     const std::vector<std::string>& env = {}) {
  Misbehaved m;
  m.out = temp_dir("misbehaving");
  args.insert(args.begin(), {write_task("misbehaving.yaml", task), "--plugin-path", misbehaving_plugins(),
                             "--output-dir", m.out.string(), "--stop-grace", "0.2"});
  m.run = fba_run(args, env);
  m.summary = nlohmann::json::parse(read_file(m.out / "summary.json"), nullptr, false);
  if (m.summary.is_discarded()) m.summary = nullptr;
  m.safe_state = fs::exists(m.out / "safe_state.act");
  return m;
}

std::string reason(const Misbehaved& m) { return m.summary.is_object() ? m.summary.value("reason", "") : ""; }

TEST(CliMisbehaving, AnExceptionFromProcessExitsThreeNamingTheComponent) {
  const auto m = misbehave({"--set", "bad.mode=throw_exception"});
  EXPECT_EQ(m.run.status, 3) << m.run.output;
  ASSERT_TRUE(m.summary.is_object()) << m.run.output;
  EXPECT_EQ(m.summary["outcome"], "runtime_error");
  EXPECT_EQ(reason(m), "component 'bad' (test.misbehaving) failed: misbehaving on purpose");
  EXPECT_TRUE(m.safe_state);
}

TEST(CliMisbehaving, ANonExceptionFromProcessExitsThreeNamingTheComponentAndTheCall) {
  const auto m = misbehave({"--set", "bad.mode=throw_int"});
  EXPECT_EQ(m.run.status, 3) << m.run.output;
  EXPECT_EQ(
      reason(m),
      "component 'bad' (test.misbehaving) threw a non-exception (not derived from std::exception) from process()");
  EXPECT_TRUE(m.safe_state);
}

TEST(CliMisbehaving, AConstructorThrowingAnIntIsAConfigurationErrorAndEarlierActuatorsGoSafe) {
  const auto m = misbehave({"--set", "bad.mode=throw_in_constructor_int"});
  EXPECT_EQ(m.run.status, 2) << m.run.output;
  ASSERT_TRUE(m.summary.is_object()) << m.run.output;
  EXPECT_EQ(m.summary["outcome"], "configuration_error");
  EXPECT_EQ(m.summary["phase"], "constructing");
  EXPECT_NE(reason(m).find("component 'bad' (test.misbehaving) refused its configuration: it threw a non-exception"),
            std::string::npos)
      << reason(m);
  EXPECT_TRUE(m.safe_state);  // 'act' was constructed first
  // And the summary says so, as after a run (it listed no safe state at all before).
  const auto& safe = m.summary["safe_states"];
  ASSERT_TRUE(safe.is_object() && safe.contains("act")) << m.summary.dump(2);
  EXPECT_EQ(safe["act"].value("status", ""), "reached") << safe.dump(2);
}

TEST(CliMisbehaving, ASegfaultExitsThreeNamingTheComponentAfterTheSafeStates) {
  const auto m = misbehave({"--set", "bad.mode=segfault"});
  EXPECT_EQ(m.run.status, 3) << m.run.output;
  EXPECT_NE(m.run.output.find("fatal signal SIGSEGV in component 'bad' (test.misbehaving) during process()"),
            std::string::npos)
      << m.run.output;
  EXPECT_NE(reason(m).find("in component 'bad' (test.misbehaving) during process()"), std::string::npos) << reason(m);
  EXPECT_TRUE(m.safe_state);
}

TEST(CliMisbehaving, AProcessThatNeverReturnsIsNamedAndTheRunStillEnds) {
  const auto m = misbehave({"--set", "bad.mode=block_process", "--timeout", "0.3"});
  EXPECT_EQ(m.run.status, 3) << m.run.output;
  ASSERT_TRUE(m.summary.is_object()) << m.run.output;
  EXPECT_NE(reason(m).find("component 'bad' (test.misbehaving) did not return from process()"), std::string::npos)
      << reason(m);
  ASSERT_EQ(m.summary["stuck"].size(), 1u);
  EXPECT_EQ(m.summary["stuck"][0]["component"], "bad");
  EXPECT_EQ(m.summary["stuck"][0]["call"], "process()");
  EXPECT_TRUE(m.safe_state);
}

TEST(CliMisbehaving, ASafeStateThatNeverReturnsIsNamedAndTheRunStillEnds) {
  const auto m = misbehave({"--set", "act.mode=block_safe_state", "--set", "src.count=5"});
  EXPECT_EQ(m.run.status, 3) << m.run.output;
  ASSERT_TRUE(m.summary.is_object()) << m.run.output;
  EXPECT_NE(reason(m).find("component 'act' (test.misbehaving_actuator) did not return from safe_state()"),
            std::string::npos)
      << reason(m);
  EXPECT_EQ(m.summary["safe_states"]["act"]["status"], "did not return");
  EXPECT_TRUE(m.safe_state);
}

TEST(CliMisbehaving, ExitZeroFromProcessExitsThreeNamingTheComponent) {
  const auto m = misbehave({"--set", "bad.mode=exit_zero"});
  EXPECT_EQ(m.run.status, 3) << m.run.output;
  EXPECT_NE(reason(m).find("component 'bad' (test.misbehaving) called exit() from process()"), std::string::npos)
      << reason(m);
  EXPECT_TRUE(m.safe_state);
}

TEST(CliMisbehaving, ExitZeroWhileLoadingThePluginExitsThree) {
  const auto m = misbehave({}, kMisbehaving, {"FBA_TEST_EXIT_IN_STATIC_INIT=1"});
  EXPECT_EQ(m.run.status, 3) << m.run.output;
  ASSERT_TRUE(m.summary.is_object()) << m.run.output;
  EXPECT_EQ(m.summary["phase"], "loading");
  // The plugin is named by its file, which is all a user has to find it.
  EXPECT_NE(reason(m).find("the plugin " + misbehaving_plugins()), std::string::npos) << reason(m);
  EXPECT_NE(reason(m).find(" called exit() while it was loaded"), std::string::npos) << reason(m);
  EXPECT_FALSE(m.safe_state);  // nothing was constructed
}

TEST(CliMisbehaving, AFaultWhileLoadingThePluginExitsThreeNamingItsFile) {
  const auto m = misbehave({}, kMisbehaving, {"FBA_TEST_SEGFAULT_IN_STATIC_INIT=1"});
  EXPECT_EQ(m.run.status, 3) << m.run.output;
  EXPECT_NE(m.run.output.find("fatal signal SIGSEGV while loading the plugin " + misbehaving_plugins()), std::string::npos)
      << m.run.output;
  ASSERT_TRUE(m.summary.is_object()) << m.run.output;
  EXPECT_EQ(m.summary["phase"], "loading");
  EXPECT_NE(reason(m).find("while loading the plugin " + misbehaving_plugins()), std::string::npos) << reason(m);
  EXPECT_FALSE(m.safe_state);  // nothing was constructed
}

TEST(CliMisbehaving, ASensorThatNeverFinishesEndsAtTheTimeout) {
  const auto m = misbehave({"--timeout", "0.3"}, R"(
components:
  act: { type: test.misbehaving_actuator }
  src: { type: test.misbehaving_sensor, params: { mode: never_finish } }
connections: [ src.out -> act.in ]
)");
  EXPECT_EQ(m.run.status, 3) << m.run.output;
  EXPECT_NE(reason(m).find("timed out"), std::string::npos) << reason(m);
  EXPECT_TRUE(m.safe_state);
}

// Once the actuators exist, a signal puts them in their safe state; a second one forces the
// exit when a component holds the stop back.
TEST(CliMisbehaving, ASignalWhileRunningPutsTheActuatorInItsSafeState) {
  for (int sig : {SIGINT, SIGTERM}) {
    const fs::path out = temp_dir("sig-running");
    Child p(fba_run_command({write_task("t.yaml", kMisbehaving), "--plugin-path", misbehaving_plugins(), "--output-dir",
               out.string()}));
    ASSERT_TRUE(p.wait_for_file(out / "running.act")) << p.output();
    p.signal(sig);
    const auto r = p.wait();
    EXPECT_EQ(r.status, sig == SIGINT ? 130 : 143) << r.output;
    EXPECT_TRUE(fs::exists(out / "safe_state.act"));
    const auto summary = nlohmann::json::parse(read_file(out / "summary.json"));
    EXPECT_EQ(summary["phase"], "running");
    EXPECT_EQ(summary["exit_code"], sig == SIGINT ? 130 : 143);
  }
}

// The user's signal decides the status even when a safe state then hangs: it exited 3, so a
// script could not tell that its user stopped the run, and the summary had no 'signal'.
TEST(CliMisbehaving, SigtermWhileASafeStateBlocksExits143NamingTheCall) {
  const fs::path out = temp_dir("sigterm-safe-state");
  Child p(fba_run_command({write_task("t.yaml", kMisbehaving), "--plugin-path", misbehaving_plugins(), "--output-dir",
             out.string(), "--set", "act.mode=block_safe_state", "--stop-grace", "0.2"}));
  ASSERT_TRUE(p.wait_for_file(out / "running.act")) << p.output();
  p.signal(SIGTERM);
  const auto r = p.wait();
  EXPECT_EQ(r.status, 143) << r.output;
  const auto summary = nlohmann::json::parse(read_file(out / "summary.json"), nullptr, false);
  ASSERT_TRUE(summary.is_object()) << r.output;
  EXPECT_EQ(summary["outcome"], "interrupted");
  EXPECT_EQ(summary["signal"], SIGTERM);
  EXPECT_EQ(summary["exit_code"], 143);
  const std::string why = summary.value("reason", "");
  EXPECT_NE(why.find("interrupted by SIGTERM"), std::string::npos) << why;
  EXPECT_NE(why.find("component 'act' (test.misbehaving_actuator) did not return from safe_state()"), std::string::npos) << why;
  EXPECT_EQ(summary["safe_states"]["act"]["status"], "did not return");
}

TEST(CliMisbehaving, ASecondSigintForcesTheExitWhileAComponentHoldsTheStopBack) {
  const fs::path out = temp_dir("second-sigint");
  Child p(fba_run_command({write_task("t.yaml", kMisbehaving), "--plugin-path", misbehaving_plugins(), "--output-dir",
             out.string(), "--set", "bad.mode=block_process", "--stop-grace", "600"}));
  ASSERT_TRUE(p.wait_for_file(out / "running.act")) << p.output();
  p.signal(SIGINT);
  ASSERT_TRUE(p.wait_for_output("SIGINT received")) << p.output();
  // Over a second later: the same signal from the same process sooner is taken as one request.
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  p.signal(SIGINT);
  const auto r = p.wait();
  EXPECT_EQ(r.status, 130) << r.output;
  EXPECT_NE(r.output.find("second SIGINT while stopping: exiting now"), std::string::npos) << r.output;
  // The forced exit still leaves its summary, naming the call it did not wait for.
  const auto summary = nlohmann::json::parse(read_file(out / "summary.json"), nullptr, false);
  ASSERT_TRUE(summary.is_object()) << r.output;
  EXPECT_EQ(summary["outcome"], "interrupted");
  EXPECT_EQ(summary["exit_code"], 130);
  EXPECT_EQ(summary["forced"], true);
  EXPECT_EQ(summary["phase"], "running");
  EXPECT_EQ(summary["stuck"], nlohmann::json::parse(R"j([{"component": "bad", "type": "test.misbehaving", "call": "process()"}])j"));
}

// An actuator whose safe_state() never returns holds the stop back until a second SIGINT, which
// exits at once with 130 and a summary.json naming that call, written by the signal thread.
TEST(CliMisbehaving, ASecondSigintWhileASafeStateBlocksExitsWithTheSummary) {
  const fs::path out = temp_dir("second-sigint-safe-state");
  Child p(fba_run_command({write_task("t.yaml", kMisbehaving), "--plugin-path", misbehaving_plugins(), "--output-dir",
             out.string(), "--set", "act.mode=block_safe_state", "--stop-grace", "600"}));
  ASSERT_TRUE(p.wait_for_file(out / "running.act")) << p.output();
  p.signal(SIGINT);
  ASSERT_TRUE(p.wait_for_file(out / "safe_state.act")) << p.output();
  // Over a second later: the same signal from the same process sooner is taken as one request.
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  p.signal(SIGINT);
  const auto r = p.wait();
  EXPECT_EQ(r.status, 130) << r.output;
  EXPECT_NE(r.output.find("safe states: act (attempted, did not return)"), std::string::npos) << r.output;
  const auto summary = nlohmann::json::parse(read_file(out / "summary.json"), nullptr, false);
  ASSERT_TRUE(summary.is_object()) << r.output;
  EXPECT_EQ(summary["outcome"], "interrupted");
  EXPECT_EQ(summary["exit_code"], 130);
  EXPECT_EQ(summary["signal"], SIGINT);
  EXPECT_EQ(summary["forced"], true);
  EXPECT_EQ(summary["phase"], "running");
  EXPECT_NE(summary.value("reason", "").find("a second SIGINT forced the exit"), std::string::npos) << summary.dump(2);
  EXPECT_EQ(summary["stuck"],
            nlohmann::json::parse(R"j([{"component": "act", "type": "test.misbehaving_actuator", "call": "safe_state()"}])j"));
  EXPECT_EQ(summary["safe_states"]["act"]["status"], "did not return");
  EXPECT_TRUE(summary["components"].contains("src")) << summary.dump(2);
  EXPECT_FALSE(fs::exists(out / "summary.json.forced"));
}

// timeout(1) sends its signal to fba-run and again to the process group: one request, which
// stops the run in order (safe states, summary), not a forced exit.
TEST(CliMisbehaving, TheSameSignalTwiceAtOnceFromOneSenderIsOneRequest) {
  const fs::path out = temp_dir("double-sigterm");
  Child p(fba_run_command({task("chain.yaml"), "--set", "source.rate=10", "--output-dir", out.string()}), {.signals_blocked = true});
  p.signal(SIGTERM);
  p.signal(SIGTERM);
  const auto r = p.wait();
  EXPECT_EQ(r.status, 143) << r.output;
  EXPECT_EQ(r.output.find("second SIGTERM"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(out / "summary.json"));
}

// ---------------------------------------------------------------------------------------------
// The output's readers and the summary's file

TEST(Cli, AStderrReaderThatWentAwayDoesNotStopTheRun) {
  const fs::path out = temp_dir("epipe");
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  close(fds[0]);  // the reader is gone before the first line: every write fails with EPIPE
  Child p(fba_run_command({task("chain.yaml"), "--output-dir", out.string(), "--log-level", "debug"}), {.output_fd = fds[1]});
  close(fds[1]);
  const auto r = p.wait();
  ASSERT_EQ(r.signal, 0) << "ended by signal " << r.signal;
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(read_file(out / "summary.json").find("\"outcome\": \"success\""), std::string::npos);
}

TEST(Cli, ASummaryThatCannotBeWrittenFailsTheRun) {
  const fs::path dir = temp_dir("summary-dir");
  fs::create_directory(dir / "summary.json");
  auto r = fba_run({task("chain.yaml"), "--output-dir", dir.string()});
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_NE(r.output.find("could not write the summary " + (dir / "summary.json").string()), std::string::npos)
      << r.output;

  const fs::path full = temp_dir("summary-full");
  fs::create_symlink("/dev/full", full / "summary.json");
  r = fba_run({task("chain.yaml"), "--output-dir", full.string()});
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_NE(r.output.find((full / "summary.json").string() + ": No space left on device"), std::string::npos)
      << r.output;
}

TEST(Cli, CheckValidatesWithoutRunning) {
  const auto r = fba_run({"--check", task("composite.yaml")});
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.output.find("ok (8 components"), std::string::npos) << r.output;
}

// --check constructs the filters (fba::check_construction): a handle a constructor binds but the
// spec leaves out is the plugin's bug, said before anything runs; the device it would have opened
// (an actuator's constructor leaving a mark) is not touched.
TEST(Cli, CheckFindsAHandleAFilterUsesButItsSpecLeavesOut) {
  // The bad plugin alone in a folder (its neighbours there are refused, one registers examples.counter).
  const fs::path plugins = temp_dir("plugins");
  for (const char* file : {"undeclared_handle.so", "undeclared_handle.manifest.json"})
    fs::copy_file(fba::test::binary_dir() + "/core/tests/bad_plugins/" + file, plugins / file);
  const fs::path mark = temp_dir("mark") / "constructed";
  const auto f = write_task("forgetful.yaml", "components:\n"
                                              "  src: { type: examples.counter, params: { count: 3 } }\n"
                                              "  forgetful: { type: bad.undeclared_handle }\n"
                                              "  device: { type: bad.marking_actuator, params: { mark: " + mark.string() + " } }\n"
                                              "connections: [ src.out -> forgetful.in, forgetful.out -> device.in ]\n");
  const std::string out = refusal({"--check", "-p", plugins.string(), f});
  EXPECT_NE(out.find("forgetful.yaml:3:"), std::string::npos) << out;
  EXPECT_NE(out.find("component 'forgetful' (bad.undeclared_handle): plugin bug in "), std::string::npos) << out;
  EXPECT_NE(out.find("uses output 'forgotten', which its spec does not declare"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(mark));
}

TEST(Cli, DotPrintsTheGraph) {
  const auto r = fba_run({"--dot", task("composite.yaml")});
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.output.rfind("digraph \"composite\" {", 0), 0u) << r.output;
  EXPECT_NE(r.output.find("cluster_pair/front"), std::string::npos);
}

// The live graph (also written on SIGUSR1 and every --dot-every seconds while running) is written
// once more when the run ends: its counts are then the run's own.
TEST(Cli, DotEveryWritesTheLiveGraphWithCountsAndQueueFills) {
  const fs::path out = temp_dir("live-dot-test");
  ASSERT_EQ(fba_run({task("chain.yaml"), "-o", out.string(), "-e", "deterministic", "--dot-every", "1000"}).status, 0);
  std::ifstream in(out / "graph-live.dot");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string dot = ss.str();
  EXPECT_EQ(dot.rfind("digraph \"chain\" {", 0), 0u) << dot;
  EXPECT_NE(dot.find("100000 calls"), std::string::npos) << dot;          // the sink's invocations
  EXPECT_NE(dot.find("lossless 0/64"), std::string::npos) << dot;         // a queue's fill and capacity
  EXPECT_NE(dot.find("/s\"]"), std::string::npos) << dot;                 // a rate on an edge
  EXPECT_FALSE(fs::exists(out / "graph-live.dot.partial"));
}

TEST(Cli, DotEveryNeedsAnOutputDir) {
  const std::string out = refusal({task("chain.yaml"), "--dot-every", "1"});
  EXPECT_NE(out.find("--dot-every needs --output-dir"), std::string::npos) << out;
}

TEST(Cli, OutputDirHoldsTheSummary) {
  const fs::path out = temp_dir("summary-test");
  ASSERT_EQ(fba_run({task("chain.yaml"), "-o", out.string(), "-e", "deterministic"}).status, 0);
  std::ifstream in(out / "summary.json");
  std::stringstream ss;
  ss << in.rdbuf();
  for (const char* key : {"\"outcome\": \"success\"", "\"final_event\"", "\"name\": \"done\"", "\"wall_time_s\"", "\"first\"",
                          "\"samples_out_per_s\""})
    EXPECT_NE(ss.str().find(key), std::string::npos) << key;
}

// A run never leaves an earlier run's summary looking like its own: a run that fails at
// configuration in a folder where another succeeded writes its own (exit 2, configuration_error),
// every summary names its run (--run-id), and lists the files the run wrote beside it, not those
// left from before.
TEST(Cli, EveryEndWritesItsOwnSummaryNamingItsRunAndItsFiles) {
  const fs::path out = temp_dir("stale-summary");
  ASSERT_EQ(fba_run({task("chain.yaml"), "-o", out.string(), "--run-id", "first", "--dot-every", "100"}).status, 0);
  auto summary = nlohmann::json::parse(read_file(out / "summary.json"));
  EXPECT_EQ(summary["run_id"], "first");
  EXPECT_EQ(summary["outcome"], "success");
  // With report.html when the build has the live view's page to make it from (docs/live-view.md).
  nlohmann::json files = nlohmann::json::array({"graph-live.dot"});
  if (fs::exists(fs::path(fba::test::binary_dir()) / "share" / "fba" / "web" / "report.html")) files.push_back("report.html");
  EXPECT_EQ(summary["artefacts"], files) << summary.dump();

  const auto failed = fba_run({task("chain.yaml"), "-o", out.string(), "--run-id", "second", "--set", "source.count=-4"});
  ASSERT_EQ(failed.status, 2) << failed.output;
  summary = nlohmann::json::parse(read_file(out / "summary.json"));
  EXPECT_EQ(summary["run_id"], "second");
  EXPECT_EQ(summary["outcome"], "configuration_error");
  EXPECT_EQ(summary["exit_code"], 2);
  EXPECT_NE(summary["reason"].get<std::string>().find("source.count"), std::string::npos) << summary.dump();
  EXPECT_FALSE(summary.contains("artefacts")) << summary.dump();  // graph-live.dot is the first run's

  // A mistake on the command line, once the folder is known, is written down too.
  ASSERT_EQ(fba_run({task("chain.yaml"), "-o", out.string(), "--run-id", "third", "--executor", "fast"}).status, 2);
  summary = nlohmann::json::parse(read_file(out / "summary.json"));
  EXPECT_EQ(summary["run_id"], "third");
  EXPECT_NE(summary["reason"].get<std::string>().find("--executor must be threaded or deterministic"), std::string::npos);

  // Without --run-id, each run gets an id of its own.
  ASSERT_EQ(fba_run({task("chain.yaml"), "-o", out.string()}).status, 0);
  const std::string id = nlohmann::json::parse(read_file(out / "summary.json"))["run_id"];
  ASSERT_EQ(fba_run({task("chain.yaml"), "-o", out.string()}).status, 0);
  EXPECT_NE(nlohmann::json::parse(read_file(out / "summary.json"))["run_id"], id);
}

TEST(Cli, PluginPathFlagAndVariableAddFolders) {
  EXPECT_EQ(fba_run({"--plugin-path", "/nonexistent", task("chain.yaml")}).status, 2);
  setenv("FBA_PLUGIN_PATH", "/nonexistent-too", 1);
  EXPECT_EQ(fba_run({"--check", task("chain.yaml")}).status, 0);  // a missing folder in the variable is skipped
  unsetenv("FBA_PLUGIN_PATH");
}
