// fba-run --serve as a user runs it: a real fba-run process on a free port, the URL read from its
// stderr, and a real client: the page with and without the token, the stream from the task to the
// end, and report.html in the output folder.
#include <signal.h>
#include <stdlib.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/live_client.hpp"
#include "support/build_paths.hpp"
#include "support/child_process.hpp"
#include "support/fba_run.hpp"
#include "support/temp_dir.hpp"

namespace {

using namespace fba::test;
using nlohmann::json;

// Runs until stopped: a counter at a steady rate into a sink, whose safe state is an event.
constexpr const char* kEndless = R"(task: endless
components:
  source: { type: examples.counter, params: { count: 1000000000, rate: 200 } }
  sink: { type: examples.sink }
connections:
  - source.out -> sink.in
)";

// Ends by itself: a thousand samples and the sink's done.
constexpr const char* kFinite = R"(task: finite
components:
  source: { type: examples.counter, params: { count: 1000 } }
  sink: { type: examples.sink, params: { expected: 1000 } }
connections:
  - source.out -> sink.in
on:
  sink.done: stop_success
)";

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The page fba-run serves and the report template, set for this process's children.
class CliServe : public ::testing::Test {
 protected:
  CliServe() {
    web_.write("index.html", "<!doctype html><title>live</title>");
    web_.write("report.html", "<!doctype html><title>report</title><!--FBA_REPORT_DATA--><p>the page</p>");
    ::setenv("FBA_WEB_DIR", web_.path().c_str(), 1);
  }
  ~CliServe() override { ::unsetenv("FBA_WEB_DIR"); }

  // The live view's URL, from the line fba-run says on stderr.
  static LiveUrl serve(Child& child) {
    const std::string prefix = "fba-run: live view at ";
    const std::string line = child.read_line_with(prefix, kHangLimit);
    if (line.rfind(prefix, 0) != 0) throw std::runtime_error("fba-run did not say its live view's address:\n" + child.read_until(prefix, {}));
    return parse_live_url(line.substr(prefix.size()));
  }

  TempDir web_{"web"}, dir_{"run"};
};

TEST_F(CliServe, ThePageNeedsTheRunsToken) {
  Child child(fba_run_command({dir_.file("endless.yaml", kEndless), "--serve", "0"}));
  const LiveUrl url = serve(child);
  EXPECT_EQ(http_get(url, "/?token=" + url.token).result(), http::status::ok);
  EXPECT_EQ(http_get(url, "/?token=" + url.token).body(), "<!doctype html><title>live</title>");
  EXPECT_EQ(http_get(url, "/").result(), http::status::forbidden);
  EXPECT_EQ(http_get(url, "/?token=0123456789abcdef0123456789abcdef").result(), http::status::forbidden);
  EXPECT_EQ(child.wait(SIGINT, kHangLimit), 130);
}

TEST_F(CliServe, ThePageIsSentTheTaskStatsEventsAndTheEndInOrder) {
  Child child(fba_run_command({dir_.file("endless.yaml", kEndless), "--serve", "0", "--run-id", "served-run"}));
  const LiveUrl url = serve(child);
  LiveSocket socket(url);
  beast::error_code ec;
  socket.handshake(url.origin(), url.token, ec);
  ASSERT_FALSE(ec) << ec.message();
  std::vector<json> messages{json::parse(socket.read(ec))};
  ASSERT_EQ(messages[0].at("type"), "task");
  EXPECT_EQ(messages[0]["run_id"], "served-run");
  EXPECT_EQ(messages[0]["components"].size(), 2u);
  EXPECT_EQ(messages[0]["components"][0]["outputs"][0], (json{{"name", "out"}, {"type", "fba.Int"}}));
  EXPECT_EQ(messages[0]["connections"][0]["from"], "source.out");
  // Stopped once the run is seen running: its stop brings the sink's safe-state event, then the end.
  for (;;) {
    messages.push_back(json::parse(socket.read(ec)));
    ASSERT_FALSE(ec) << ec.message();
    const json& m = messages.back();
    if (m["type"] == "stats" && !m["components"].empty() && m["components"][0]["invocations"] > 0) break;
  }
  // SIGINT on another thread, which waits for the exit while this one reads the stream to its close.
  int status = -1;
  std::thread stop([&] { status = child.wait(SIGINT, kHangLimit); });
  for (;;) {
    const std::string text = socket.read(ec);
    if (ec) break;
    messages.push_back(json::parse(text));
  }
  stop.join();
  EXPECT_EQ(ec, websocket::error::closed) << ec.message();
  EXPECT_EQ(socket.close_reason().code, websocket::close_code::normal);
  EXPECT_EQ(status, 130);

  // task first, stats while running, every event once and in order, the end last.
  std::size_t events = 0, stats = 0;
  for (std::size_t i = 1; i < messages.size(); ++i) {
    const json& m = messages[i];
    ASSERT_NE(m["type"], "task") << i;
    if (m["type"] == "stats") ++stats;
    if (m["type"] == "event") EXPECT_EQ(m["index"], events++) << m;
    if (m["type"] == "end") EXPECT_EQ(i, messages.size() - 1);
  }
  EXPECT_GE(stats, 2u);
  ASSERT_GE(events, 1u);
  const json& end = messages.back();
  ASSERT_EQ(end["type"], "end");
  EXPECT_EQ(end["outcome"], "interrupted");
  EXPECT_EQ(end["exit_code"], 130);
  EXPECT_EQ(end["summary"]["run_id"], "served-run");
  bool safe_state = false;
  for (const json& m : messages) safe_state |= m["type"] == "event" && m["source"] == "sink" && m["name"] == "safe_state";
  EXPECT_TRUE(safe_state);
}

TEST_F(CliServe, AWebSocketFromAnotherOriginIsRefused) {
  Child child(fba_run_command({dir_.file("endless.yaml", kEndless), "--serve", "0"}));
  const LiveUrl url = serve(child);
  EXPECT_EQ(upgrade_status(url, url.origin(), url.token), http::status::switching_protocols);
  EXPECT_EQ(upgrade_status(url, "http://attacker.example", url.token), http::status::forbidden);
  EXPECT_EQ(upgrade_status(url, "http://127.0.0.1:" + std::to_string(std::stoi(url.port) + 1), url.token),
            http::status::forbidden);
  EXPECT_EQ(child.wait(SIGINT, kHangLimit), 130);
}

TEST_F(CliServe, AnOversizedMessageEndsItsConnection) {
  Child child(fba_run_command({dir_.file("endless.yaml", kEndless), "--serve", "0"}));
  const LiveUrl url = serve(child);
  LiveSocket socket(url);
  beast::error_code ec;
  socket.handshake(url.origin(), url.token, ec);
  ASSERT_FALSE(ec) << ec.message();
  socket.write(std::string(4097, ' '), ec);
  ASSERT_FALSE(ec) << ec.message();
  while (!ec) socket.read(ec);  // what the server had sent before it read the message
  if (ec == websocket::error::closed) EXPECT_EQ(socket.close_reason().code, websocket::close_code::too_big);
  EXPECT_EQ(child.wait(SIGINT, kHangLimit), 130);
}

TEST_F(CliServe, AFinishedRunsReportHoldsItsMessagesAsJsonAndIsListedInTheSummary) {
  const std::string out = (dir_.path() / "out").string();
  const Result r = run_shell(program("fba-run") + " " + dir_.file("finite.yaml", kFinite) + " -o " + out + " --run-id reported");
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string html = read_text(dir_.path() / "out" / "report.html");
  EXPECT_EQ(html.find("<!--FBA_REPORT_DATA-->"), std::string::npos);
  const std::string open = R"(<script type="application/json" id="fba-report">)";
  const auto from = html.find(open);
  ASSERT_NE(from, std::string::npos) << html.substr(0, 300);
  EXPECT_EQ(html.rfind("<!doctype html><title>report</title>", 0), 0u);
  const auto to = html.find("</script>", from);
  ASSERT_NE(to, std::string::npos);
  EXPECT_EQ(html.substr(to), "</script><p>the page</p>");
  const json data = json::parse(html.substr(from + open.size(), to - from - open.size()));
  const json& messages = data.at("messages");
  ASSERT_GE(messages.size(), 4u);
  EXPECT_EQ(messages.front()["type"], "task");
  EXPECT_EQ(messages[1]["type"], "stats");
  EXPECT_EQ(messages[1]["components"][1]["samples_in"], 1000);
  EXPECT_EQ(messages.back()["type"], "end");
  EXPECT_EQ(messages.back()["outcome"], "success");
  const json summary = json::parse(read_text(dir_.path() / "out" / "summary.json"));
  EXPECT_EQ(messages.back()["summary"], summary);
  EXPECT_NE(std::find(summary["artefacts"].begin(), summary["artefacts"].end(), "report.html"), summary["artefacts"].end())
      << summary["artefacts"];
}

TEST_F(CliServe, WithoutABuiltTemplateNoReportIsWrittenAndFbaRunSaysHowToGetOne) {
  ::setenv("FBA_WEB_DIR", (dir_.path() / "nothing").c_str(), 1);
  const std::string out = (dir_.path() / "out").string();
  const Result r = run_shell(program("fba-run") + " " + dir_.file("finite.yaml", kFinite) + " -o " + out);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir_.path() / "out" / "report.html"));
  EXPECT_NE(r.output.find("no report.html written"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("npm"), std::string::npos) << r.output;
}

// Ends by itself with a failure: the sink's done is a failure event (exit 1).
constexpr const char* kFiniteFailing = R"(task: finite_failing
components:
  source: { type: examples.counter, params: { count: 100 } }
  sink: { type: examples.sink, params: { expected: 100 } }
connections:
  - source.out -> sink.in
on:
  sink.done: stop_failure
)";

// A page that connects after the run: the run's messages from the task to the end, read until the
// server closes the stream or the end is in. Returns them in order.
std::vector<json> replayed(const LiveUrl& url) {
  LiveSocket socket(url);
  beast::error_code ec;
  socket.handshake(url.origin(), url.token, ec);
  if (ec) throw std::runtime_error("the WebSocket handshake failed: " + ec.message());
  std::vector<json> messages;
  while (messages.empty() || messages.back().value("type", "") != "end") {
    const std::string text = socket.read(ec);
    if (ec) throw std::runtime_error("the stream ended before its end message: " + ec.message());
    messages.push_back(json::parse(text));
  }
  return messages;
}

// A page that connects while the run goes on: reads until a stats message says the source has run.
void replayed_until_stats(const LiveUrl& url) {
  LiveSocket socket(url);
  beast::error_code ec;
  socket.handshake(url.origin(), url.token, ec);
  if (ec) throw std::runtime_error("the WebSocket handshake failed: " + ec.message());
  for (;;) {
    const std::string text = socket.read(ec);
    if (ec) throw std::runtime_error("the stream ended before the run was seen running: " + ec.message());
    const json m = json::parse(text);
    if (m["type"] == "stats" && !m["components"].empty() && m["components"][0]["invocations"] > 0) return;
  }
}

// --serve-keep: the run ends by itself, and fba-run goes on serving it (the page, and its messages to
// a page that connects after the end) until SIGTERM, then exits with the run's status, its summary
// the run's. For a success and a failure, so that the status is seen to be the run's, not 0.
TEST_F(CliServe, WithServeKeepTheEndedRunIsServedUntilSigtermAndTheStatusIsTheRuns) {
  struct Case {
    const char* name;
    const char* task;
    int status;
    const char* outcome;
  };
  for (const Case& c : {Case{"finite", kFinite, 0, "success"}, Case{"finite_failing", kFiniteFailing, 1, "failure"}}) {
    SCOPED_TRACE(c.name);
    const std::filesystem::path out = dir_.path() / (std::string(c.name) + "-out");
    Child child(fba_run_command({dir_.file(std::string(c.name) + ".yaml", c.task), "--serve", "0", "--serve-keep", "-o", out.string()}));
    const LiveUrl url = serve(child);
    const std::string kept = child.read_line_with("still serving its live view", kHangLimit);
    ASSERT_NE(kept.find("until SIGINT or SIGTERM"), std::string::npos) << child.output();
    // The run's last line came first: the run is over.
    ASSERT_NE(child.output().find("fba-run: " + std::string(c.status == 0 ? "success" : "failed")), std::string::npos) << child.output();
    ASSERT_TRUE(child.running()) << child.output();

    EXPECT_EQ(http_get(url, "/?token=" + url.token).result(), http::status::ok);
    EXPECT_EQ(http_get(url, "/").result(), http::status::forbidden);  // still the run's token only
    for (int page = 0; page < 2; ++page) {  // each page that connects is sent the whole run
      const std::vector<json> messages = replayed(url);
      EXPECT_EQ(messages.front()["type"], "task");
      EXPECT_EQ(messages.back()["outcome"], c.outcome);
      EXPECT_EQ(messages.back()["exit_code"], c.status);
    }
    EXPECT_TRUE(child.running()) << child.output();

    EXPECT_EQ(child.wait(SIGTERM, kHangLimit), c.status) << child.output();
    const json summary = json::parse(read_text(out / "summary.json"));
    EXPECT_EQ(summary["outcome"], c.outcome) << "the stop of the serving is not the run's outcome";
    EXPECT_EQ(summary["exit_code"], c.status);
    EXPECT_TRUE(std::filesystem::is_regular_file(out / "report.html"));
  }
}

// Without --serve-keep a run that ends exits by itself, serving or not: a script never waits on a
// page. With it, a run stopped by a signal exits too: the signal asked fba-run to end.
TEST_F(CliServe, WithoutServeKeepOrAfterASignalFbaRunExitsWhenTheRunEnds) {
  Child finite(fba_run_command({dir_.file("finite.yaml", kFinite), "--serve", "0"}));
  serve(finite);
  const Result done = finite.wait();
  EXPECT_EQ(done.status, 0) << done.output;
  EXPECT_EQ(done.output.find("still serving"), std::string::npos) << done.output;

  Child endless(fba_run_command({dir_.file("endless.yaml", kEndless), "--serve", "0", "--serve-keep"}));
  const LiveUrl url = serve(endless);
  replayed_until_stats(url);
  EXPECT_EQ(endless.wait(SIGINT, kHangLimit), 130) << endless.output();
  EXPECT_EQ(endless.output().find("still serving"), std::string::npos) << endless.output();
}

// A task whose component refuses its configuration when constructed (the test plugin's mode).
constexpr const char* kRefusing = R"(task: refusing
components:
  src: { type: examples.counter, params: { count: 10 } }
  bad: { type: test.misbehaving, params: { mode: throw_in_constructor_int } }
connections: [ src.out -> bad.in ]
)";

// A run that ended before its task ran is kept on the page too: its end says why, and SIGTERM
// ends fba-run with the construction's status.
TEST_F(CliServe, WithServeKeepARunThatEndedBeforeItsTaskRanIsServedUntilSigterm) {
  Child child(fba_run_command({dir_.file("refusing.yaml", kRefusing), "--plugin-path", misbehaving_plugins(), "--serve", "0",
                               "--serve-keep", "-o", (dir_.path() / "out").string()}));
  const LiveUrl url = serve(child);
  child.read_line_with("still serving its live view", kHangLimit);
  ASSERT_TRUE(child.running()) << child.output();
  const std::vector<json> messages = replayed(url);
  EXPECT_EQ(messages.front()["type"], "task");
  EXPECT_EQ(messages.back()["outcome"], "configuration_error");
  EXPECT_EQ(messages.back()["exit_code"], 2);
  EXPECT_NE(messages.back()["reason"].get<std::string>().find("component 'bad' (test.misbehaving) refused its configuration"),
            std::string::npos)
      << messages.back();
  EXPECT_EQ(child.wait(SIGTERM, kHangLimit), 2) << child.output();
}

TEST_F(CliServe, ServeKeepWithoutServeIsRefused) {
  const Result r = run_shell(program("fba-run") + " " + dir_.file("finite.yaml", kFinite) + " --serve-keep");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--serve-keep needs --serve"), std::string::npos) << r.output;
}

TEST_F(CliServe, BadAddressesAndAPortInUseAreRefusedBeforeTheRun) {
  const std::string task = dir_.file("finite.yaml", kFinite);
  for (const char* bad : {"70000", "nowhere:80", "http://x"}) {
    const Result r = run_shell(program("fba-run") + " " + task + " --serve '" + bad + "'");
    EXPECT_EQ(r.status, 2) << bad << "\n" << r.output;
    EXPECT_NE(r.output.find("--serve"), std::string::npos) << r.output;
  }
  Child child(fba_run_command({dir_.file("endless.yaml", kEndless), "--serve", "0"}));
  const LiveUrl url = serve(child);
  const Result taken = run_shell(program("fba-run") + " " + task + " --serve " + url.port);
  EXPECT_EQ(taken.status, 2) << taken.output;
  EXPECT_NE(taken.output.find("cannot listen on 127.0.0.1:" + url.port), std::string::npos) << taken.output;
  EXPECT_EQ(child.wait(SIGINT, kHangLimit), 130);
}

}  // namespace
