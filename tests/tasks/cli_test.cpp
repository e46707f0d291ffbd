// fba-run's contract with the shell: exit statuses, signals, --check, --dot, --output-dir.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

extern char** environ;

namespace {

namespace fs = std::filesystem;

struct Result {
  int status = -1;  // exit status, or 128 + signal
  std::string output;
};

// Runs fba-run with arguments; optionally sends `signal` after `delay`.
Result fba_run(std::vector<std::string> args, int signal = 0, std::chrono::milliseconds delay = {}) {
  const fs::path log = fs::path(testing::TempDir()) / ("fba-run-" + std::to_string(getpid()) + ".log");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  args.insert(args.begin(), FBA_RUN);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  Result r;
  if (posix_spawn(&pid, FBA_RUN, &actions, nullptr, argv.data(), environ) != 0) return r;
  posix_spawn_file_actions_destroy(&actions);
  if (signal) {
    std::this_thread::sleep_for(delay);
    kill(pid, signal);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  r.output = ss.str();
  return r;
}

std::string task(const std::string& name) { return std::string(FBA_TASKS_DIR) + "/examples/" + name; }

std::string write_task(const std::string& name, const std::string& text) {
  const fs::path p = fs::path(testing::TempDir()) / name;
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
  const auto r = fba_run({f});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("bad.yaml:2:"), std::string::npos) << r.output;
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

TEST(Cli, TimeoutExitsThree) {
  const auto r = fba_run({write_task("long.yaml", kLong), "--timeout", "0.5"});
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.output.find("timed out"), std::string::npos) << r.output;
}

TEST(Cli, SigintAndSigtermStopInOrderWith130) {
  for (int sig : {SIGINT, SIGTERM}) {
    const fs::path out = fs::path(testing::TempDir()) / ("sig" + std::to_string(sig));
    fs::remove_all(out);
    const auto start = std::chrono::steady_clock::now();
    const auto r = fba_run({write_task("long.yaml", kLong), "--output-dir", out.string()}, sig, std::chrono::milliseconds(500));
    EXPECT_EQ(r.status, 130) << r.output;
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
    EXPECT_NE(r.output.find("safe state reached"), std::string::npos) << r.output;
    std::ifstream summary(out / "summary.json");
    std::stringstream ss;
    ss << summary.rdbuf();
    EXPECT_NE(ss.str().find("\"outcome\": \"interrupted\""), std::string::npos) << ss.str();
  }
}

TEST(Cli, CheckValidatesWithoutRunning) {
  const auto r = fba_run({"--check", task("composite.yaml")});
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.output.find("ok (8 components"), std::string::npos) << r.output;
}

TEST(Cli, DotPrintsTheGraph) {
  const auto r = fba_run({"--dot", task("composite.yaml")});
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.output.rfind("digraph \"composite\" {", 0), 0u) << r.output;
  EXPECT_NE(r.output.find("cluster_pair/front"), std::string::npos);
}

TEST(Cli, OutputDirHoldsTheSummary) {
  const fs::path out = fs::path(testing::TempDir()) / "summary-test";
  fs::remove_all(out);
  ASSERT_EQ(fba_run({task("chain.yaml"), "-o", out.string(), "-e", "deterministic"}).status, 0);
  std::ifstream in(out / "summary.json");
  std::stringstream ss;
  ss << in.rdbuf();
  for (const char* key : {"\"outcome\": \"success\"", "\"final_event\"", "\"name\": \"done\"", "\"wall_time_s\"", "\"first\"",
                          "\"samples_out_per_s\""})
    EXPECT_NE(ss.str().find(key), std::string::npos) << key;
}

TEST(Cli, PluginPathFlagAndVariableAddFolders) {
  EXPECT_EQ(fba_run({"--plugin-path", "/nonexistent", task("chain.yaml")}).status, 2);
  setenv("FBA_PLUGIN_PATH", "/nonexistent-too", 1);
  EXPECT_EQ(fba_run({"--check", task("chain.yaml")}).status, 0);  // a missing folder in the variable is skipped
  unsetenv("FBA_PLUGIN_PATH");
}
