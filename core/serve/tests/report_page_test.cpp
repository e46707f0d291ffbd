// report.html: the template's marker replaced by the run's messages, safe inside a <script>.
#include "report_page.hpp"

#include <stdexcept>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "run_record.hpp"

namespace {

using fba::serve::LiveMessage;

std::string embedded(const std::string& html) {
  const std::string open = R"(<script type="application/json" id="fba-report">)";
  const auto from = html.find(open);
  if (from == std::string::npos) return {};
  const auto to = html.find("</script>", from + open.size());
  return html.substr(from + open.size(), to - from - open.size());
}

TEST(ReportPage, TheMarkerIsReplacedByTheMessagesInOrderAsJson) {
  fba::serve::RunRecord record;
  record.add(LiveMessage::Task, R"({"type":"task"})");
  record.add(LiveMessage::Stats, R"({"type":"stats","t":1})");
  record.add(LiveMessage::Event, R"({"type":"event","index":0})");
  record.add(LiveMessage::End, R"({"type":"end"})");
  const std::string html = fba::serve::report_html("<html><head><!--FBA_REPORT_DATA--></head></html>", record.replay().messages);
  EXPECT_EQ(html.find(fba::serve::kReportMarker), std::string::npos);
  EXPECT_EQ(html.rfind("<html><head><script", 0), 0u) << html;
  const auto data = nlohmann::json::parse(embedded(html));
  ASSERT_EQ(data.at("messages").size(), 4u);
  EXPECT_EQ(data["messages"][0]["type"], "task");
  EXPECT_EQ(data["messages"][3]["type"], "end");
}

TEST(ReportPage, TextThatWouldEndTheScriptIsEscapedAndReadsTheSame) {
  fba::serve::RunRecord record;
  const nlohmann::json event{{"type", "event"}, {"payload", "</script><script>alert(1)</script> <!-- </SCRIPT"}};
  record.add(LiveMessage::Event, event.dump());
  const std::string html = fba::serve::report_html("<!--FBA_REPORT_DATA-->", record.replay().messages);
  const std::string data = embedded(html);
  EXPECT_EQ(data.find("</"), std::string::npos) << data;
  EXPECT_EQ(data.find("<!--"), std::string::npos) << data;
  EXPECT_EQ(nlohmann::json::parse(data)["messages"][0], event);
}

TEST(ReportPage, ATemplateWithoutTheMarkerExactlyOnceIsRefused) {
  EXPECT_THROW(fba::serve::report_html("<html></html>", {}), std::invalid_argument);
  EXPECT_THROW(fba::serve::report_html("<!--FBA_REPORT_DATA--><!--FBA_REPORT_DATA-->", {}), std::invalid_argument);
}

TEST(RunRecord, KeepsTheNewestViewOfEachPortAndEveryPose) {
  fba::serve::RunRecord record;
  record.add(LiveMessage::View, R"({"type":"view","port":"camera.frame","view":{"kind":"image"}})", "camera.frame");
  record.add(LiveMessage::View, R"({"type":"view","port":"arm.pose","view":{"kind":"pose","position":[0,0,1]}})", "arm.pose");
  record.add(LiveMessage::View, R"({"type":"view","port":"camera.frame","view":{"kind":"image","n":2}})", "camera.frame");
  record.add(LiveMessage::View, R"({"type":"view","port":"arm.pose","view":{"kind":"pose","position":[0,0,2]}})", "arm.pose");
  const auto replay = record.replay();
  ASSERT_EQ(replay.messages.size(), 3u);
  EXPECT_NE(replay.messages[0].text->find("[0,0,1]"), std::string::npos);
  EXPECT_NE(replay.messages[1].text->find(R"("n":2)"), std::string::npos);  // in the order they came
  EXPECT_NE(replay.messages[2].text->find("[0,0,2]"), std::string::npos);
  EXPECT_EQ(replay.up_to, 4u);
}

}  // namespace
