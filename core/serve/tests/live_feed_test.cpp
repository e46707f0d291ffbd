// The live feed on a real running task, in this process: the Monitor samples it on its thread, the
// feed turns each sample into messages, the server sends them to a page on a real socket. Run
// under ThreadSanitizer by tools/dev.sh test (the sampler, the server and the task's threads).
#include "live_feed.hpp"

#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "fba/view.hpp"
#include "support/live_client.hpp"
#include "monitor.hpp"
#include "support/built_plugins.hpp"
#include "support/temp_dir.hpp"

namespace {

using namespace fba::test;
using nlohmann::json;

constexpr const char* kChain = R"(task: fed
components:
  src: { type: examples.counter, params: { count: 20000 } }
  pass: { type: examples.passthrough }
  sink: { type: examples.sink, params: { expected: 20000 } }
connections:
  - src.out -> pass.in
  - pass.out -> sink.in
on:
  sink.done: stop_success
)";

// A view of the integers for this test: each one as a pose along x.
std::string int_as_pose(const fba::Packet& p) {
  return R"({"kind":"pose","position":[)" + std::to_string(p.get<std::int64_t>()) + R"(,0,0],"rotation":[1,0,0,0]})";
}

// What a page connected to a run's live feed was sent: every message, in order.
struct PageRun {
  fba::RunResult result;
  std::vector<json> messages;
  std::vector<std::string> watched;  // the ports the feed watched
};

// Runs `config` with its live feed published to a server, sampled every `period`, and a page
// connected to the server from before the start to the end; `record` keeps the run (report.html).
// The set-up every live feed test shares.
PageRun run_with_a_page(const fba::TaskConfig& config, const std::string& run_id, std::chrono::milliseconds period, fba::serve::RunRecord& record) {
  PageRun run;
  fba::serve::LiveFeed feed(record, config, run_id);
  fba::serve::LiveServer server({}, record);
  feed.publish_to(&server);
  const LiveUrl url = parse_live_url(server.url());
  LiveSocket page(url);
  beast::error_code ec;
  page.handshake(url.origin(), url.token, ec);
  if (ec) {
    ADD_FAILURE() << "the page did not connect: " << ec.message();
    return run;
  }
  std::thread reader([&] {
    beast::error_code e;
    for (std::string text = page.read(e); !e; text = page.read(e)) run.messages.push_back(json::parse(text));
  });
  fba::Task task(config);
  feed.watch(task, config);
  run.watched = feed.watched();
  fba_run::Monitor monitor([&task] { return task.snapshot(); });
  monitor.watch([&feed](const fba::RunResult& now, const fba::RunResult* previous) { feed.sample(now, previous); });
  monitor.start(period);
  run.result = task.run();
  monitor.finish(run.result);
  feed.end(run.result, fba::summary_json(run.result, config));
  server.finish(kHangLimit);
  reader.join();
  return run;
}

TEST(LiveFeed, ARunningTaskReachesAPageAsTaskStatsViewsEventsAndTheEnd) {
  fba::register_view("fba.Int", int_as_pose);
  TempDir dir;
  const fba::TaskConfig config = fba::load_task_text(kChain, "fed.yaml", dir.path(), built_plugins());
  fba::serve::RunRecord record;
  const PageRun run = run_with_a_page(config, "feed-run", std::chrono::milliseconds(1), record);
  fba::register_view("fba.Int", nullptr);
  EXPECT_EQ(run.watched, (std::vector<std::string>{"src.out", "pass.out"}));  // in the task's order

  const std::vector<json>& messages = run.messages;
  ASSERT_GE(messages.size(), 4u);
  EXPECT_EQ(messages.front()["type"], "task");
  EXPECT_EQ(messages.front()["run_id"], "feed-run");
  EXPECT_EQ(messages.back()["type"], "end");
  EXPECT_EQ(messages.back()["outcome"], "success");
  EXPECT_EQ(messages.back()["summary"]["outcome"], "success");
  std::size_t stats = 0, events = 0;
  std::map<std::string, std::int64_t> last_seq;
  for (const json& m : messages) {
    if (m["type"] == "stats") ++stats;
    if (m["type"] == "event") EXPECT_EQ(m["index"], events++);
    if (m["type"] != "view") continue;
    EXPECT_EQ(m["data_type"], "fba.Int");
    EXPECT_EQ(m["view"]["kind"], "pose");
    // The newest sample each time: later ones on a port, never an older one again.
    const std::string port = m["port"];
    if (last_seq.count(port)) EXPECT_GT(m["seq"].get<std::int64_t>(), last_seq[port]) << m;
    last_seq[port] = m["seq"];
    EXPECT_EQ(m["view"]["position"][0], m["seq"]) << m;  // the counter's integers start at 0, as the seqs do
  }
  EXPECT_GE(stats, 1u);
  EXPECT_GE(events, 1u);  // the sink's done
  // The last sample of each port reached the page: the run's final values.
  EXPECT_EQ(last_seq["src.out"], 19999);
  EXPECT_EQ(last_seq["pass.out"], 19999);
}

// A type whose view shows every sample (the poses visited): a burst far faster than the updates
// reaches the page whole and in order, none replaced by a newer one on the way (the watch, the
// server's queue for a page), and the run's record keeps each for report.html. 200 samples, within
// what a watch keeps between two updates (kEveryViewedLimit), so none may be lost whatever the timing.
TEST(LiveFeed, EverySampleOfATypeViewedSampleBySampleReachesThePageInOrder) {
  constexpr int kCount = 200;
  static_assert(kCount <= static_cast<int>(fba::kEveryViewedLimit));
  fba::register_view("fba.Int", int_as_pose, fba::ViewedSamples::Every);
  TempDir dir;
  const std::string text = R"(task: burst
components:
  src: { type: examples.counter, params: { count: )" + std::to_string(kCount) + R"( } }
  sink: { type: examples.sink, params: { expected: )" + std::to_string(kCount) + R"( } }
connections:
  - src.out -> sink.in
on:
  sink.done: stop_success
)";
  const fba::TaskConfig config = fba::load_task_text(text, "burst.yaml", dir.path(), built_plugins());
  fba::serve::RunRecord record;
  // The live view's period: the burst is over long before.
  const PageRun run = run_with_a_page(config, "burst-run", std::chrono::milliseconds(100), record);
  fba::register_view("fba.Int", nullptr);
  ASSERT_EQ(run.result.outcome, fba::Outcome::Success) << run.result.reason;

  std::vector<std::int64_t> seen;
  for (const json& m : run.messages)
    if (m["type"] == "view" && m["port"] == "src.out") seen.push_back(m["seq"]);
  std::vector<std::int64_t> every(kCount);
  for (int i = 0; i < kCount; ++i) every[i] = i;
  EXPECT_EQ(seen, every) << "the page was not sent each sample once, in order";
  std::vector<std::int64_t> recorded;
  for (const auto& m : record.replay().messages)
    if (m.kind == fba::serve::LiveMessage::View) recorded.push_back(json::parse(*m.text)["seq"]);
  EXPECT_EQ(recorded, every) << "report.html would not hold each sample in order";
}

}  // namespace
