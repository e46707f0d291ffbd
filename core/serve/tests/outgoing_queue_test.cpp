// A slow page's queue: old stats and views make way, the task, the events and the end never do,
// and a page too slow even for those is given up on.
#include "outgoing_queue.hpp"

#include <memory>
#include <string>

#include <gtest/gtest.h>

namespace {

using fba::serve::LiveMessage;
using fba::serve::OutgoingQueue;

LiveMessage message(LiveMessage::Kind kind, std::uint64_t seq) {
  return {kind, {}, std::make_shared<const std::string>(std::to_string(seq)), seq};
}

std::string contents(OutgoingQueue q) {
  std::string s;
  for (; !q.empty(); q.pop()) s += (s.empty() ? "" : " ") + *q.front().text;
  return s;
}

TEST(OutgoingQueue, AFullQueueDropsItsOldestStatsOrViewNeverAnEvent) {
  OutgoingQueue q(4, 100);
  EXPECT_TRUE(q.push(message(LiveMessage::Task, 1), false));
  EXPECT_TRUE(q.push(message(LiveMessage::Event, 2), false));
  EXPECT_TRUE(q.push(message(LiveMessage::Stats, 3), false));
  EXPECT_TRUE(q.push(message(LiveMessage::View, 4), false));
  EXPECT_TRUE(q.push(message(LiveMessage::Stats, 5), false));  // full: stats 3 goes
  EXPECT_EQ(contents(q), "1 2 4 5");
  EXPECT_TRUE(q.push(message(LiveMessage::Event, 6), false));  // view 4 goes
  EXPECT_TRUE(q.push(message(LiveMessage::End, 7), false));    // stats 5 goes
  EXPECT_EQ(contents(q), "1 2 6 7");
  EXPECT_EQ(q.dropped(), 3u);
}

TEST(OutgoingQueue, TheMessageBeingWrittenStays) {
  OutgoingQueue q(2, 100);
  q.push(message(LiveMessage::Stats, 1), false);
  q.push(message(LiveMessage::Stats, 2), true);
  q.push(message(LiveMessage::Stats, 3), true);  // 1 is on the wire: 2 goes
  EXPECT_EQ(contents(q), "1 3");
}

TEST(OutgoingQueue, APageTooSlowForTheEventsIsGivenUpOn) {
  OutgoingQueue q(2, 3);
  EXPECT_TRUE(q.push(message(LiveMessage::Event, 1), false));
  EXPECT_TRUE(q.push(message(LiveMessage::Event, 2), false));
  EXPECT_TRUE(q.push(message(LiveMessage::Event, 3), false));  // nothing to drop: over the limit, under the hard one
  EXPECT_FALSE(q.push(message(LiveMessage::Event, 4), false));
  EXPECT_EQ(contents(q), "1 2 3");
}

TEST(OutgoingQueue, WhatALatePageIsSentFirstIsNotBounded) {
  OutgoingQueue q(2, 3);
  q.assign({message(LiveMessage::Task, 1), message(LiveMessage::Event, 2), message(LiveMessage::Event, 3),
            message(LiveMessage::Event, 4), message(LiveMessage::Stats, 5)});
  EXPECT_EQ(q.size(), 5u);
}

}  // namespace
