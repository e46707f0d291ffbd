// The CAN transport's backends with real descriptors: SLCAN's codec and line splitting, SLCAN
// host and adapter over a pseudo-terminal, the socketpair bus, and SocketCAN when the kernel has it.
#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <mutex>
#include <random>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "fba/can/pty.hpp"
#include "fba/can/slcan.hpp"
#include "fba/can/slcan_adapter.hpp"
#include "fba/can/socketcan.hpp"
#include "fba/can/socketpair_bus.hpp"
#include "support/temp_dir.hpp"

using namespace std::chrono_literals;
using fba::can::BusError;
using fba::can::Frame;
using fba::can::make_frame;
namespace slcan = fba::can::slcan;

namespace {

Frame extended_frame() {
  Frame f = make_frame(0x1ABCDEF0, {1, 2, 3});
  f.extended = true;
  return f;
}

Frame remote_frame() {
  Frame f;
  f.id = 0x701;
  f.rtr = true;
  f.dlc = 1;
  return f;
}

// An SLCAN adapter on the master end of a pseudo-terminal, answering in its own thread and keeping
// the frames the host sends.
class AdapterThread {
 public:
  explicit AdapterThread(fba::can::Pty& pty) : adapter_(std::move(pty.master), "adapter") {
    thread_ = std::thread([this] {
      try {
        while (!stop_)
          if (auto f = adapter_.receive(5ms)) {
            std::lock_guard lock(mutex_);
            received_.push_back(*f);
          }
      } catch (const BusError&) {  // the host side is gone: the test looks at that end
      }
    });
  }
  ~AdapterThread() { stop(); }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  std::vector<Frame> received() {
    std::lock_guard lock(mutex_);
    return received_;
  }
  // Only while the thread is stopped or from a test that tolerates the adapter writing concurrently.
  slcan::SlcanAdapter& adapter() { return adapter_; }

 private:
  slcan::SlcanAdapter adapter_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<Frame> received_;
  std::thread thread_;
};

}  // namespace

TEST(CanFrame, ValidateRejectsAnIdBeyondElevenBitsAndALengthBeyondEight) {
  Frame f = make_frame(0x800, {});
  EXPECT_THROW(f.validate(), std::invalid_argument);
  f.extended = true;
  EXPECT_NO_THROW(f.validate());
  f.dlc = 9;
  EXPECT_THROW(f.validate(), std::invalid_argument);
  EXPECT_THROW(make_frame(1, {1, 2, 3, 4, 5, 6, 7, 8, 9}), std::invalid_argument);
}

TEST(Slcan, EncodesEachFrameKindAsLawicelLines) {
  EXPECT_EQ(slcan::encode(make_frame(0x601, {0x40, 0x00, 0x10, 0x00})), "t601440001000\r");
  EXPECT_EQ(slcan::encode(make_frame(0x080, {})), "t0800\r");
  EXPECT_EQ(slcan::encode(extended_frame()), "T1ABCDEF03010203\r");
  EXPECT_EQ(slcan::encode(remote_frame()), "r7011\r");
}

TEST(Slcan, DecodeInvertsEncodeAndIgnoresATimeStamp) {
  for (const Frame& f :
       {make_frame(0x7FF, {0, 1, 2, 3, 4, 5, 6, 0xFF}), make_frame(0, {}), extended_frame(), remote_frame()}) {
    std::string line = slcan::encode(f);
    line.pop_back();  // the CR
    std::string error;
    const auto decoded = slcan::decode(line, &error);
    ASSERT_TRUE(decoded) << error;
    EXPECT_EQ(*decoded, f) << line;
    const auto stamped = slcan::decode(line + "1A2B", &error);
    ASSERT_TRUE(stamped) << error;
    EXPECT_EQ(*stamped, f);
  }
}

TEST(Slcan, DecodeRefusesMalformedLinesSayingWhy) {
  const std::pair<std::string, std::string> cases[] = {
      {"t1", "too short"},          {"tXYZ8", "not hexadecimal"},         {"t1239001122334455667788", "0 to 8"},
      {"t7FF2AB", "expected 4"},    {"t8000", "beyond the 11-bit range"}, {"x123", "starts with t, T, r or R"},
      {"t12320G11", "data byte 0"},
  };
  for (const auto& [line, why] : cases) {
    std::string error;
    EXPECT_FALSE(slcan::decode(line, &error)) << line;
    EXPECT_NE(error.find(why), std::string::npos) << line << ": " << error;
  }
}

TEST(Slcan, LineReaderJoinsPartialLinesAndSeparatesBells) {
  slcan::LineReader reader;
  const std::string stream = "t12";
  reader.feed({stream.data(), stream.size()});
  EXPECT_FALSE(reader.next());
  const std::string rest = "30\r\a\r\nz\r";
  reader.feed({rest.data(), rest.size()});
  auto t = reader.next();
  ASSERT_TRUE(t);
  EXPECT_EQ(t->kind, slcan::LineReader::Token::line);
  EXPECT_EQ(t->text, "t1230");
  EXPECT_EQ(reader.next()->kind, slcan::LineReader::Token::bell);
  t = reader.next();
  EXPECT_EQ(t->text, "");               // an OK answer
  EXPECT_EQ(reader.next()->text, "z");  // the LF before it is skipped
  EXPECT_FALSE(reader.next());
}

TEST(Slcan, LineReaderDropsAnOverlongLineAndRecoversAtTheNextCr) {
  slcan::LineReader reader;
  const std::string stream = std::string(10000, 'A') + "\rt1230\r";
  reader.feed({stream.data(), stream.size()});
  const auto t = reader.next();
  ASSERT_TRUE(t);
  EXPECT_EQ(t->kind, slcan::LineReader::Token::overflow);
  EXPECT_LE(t->text.size(), slcan::kMaxLine);
  EXPECT_EQ(reader.next()->text, "t1230");
}

TEST(Slcan, FramesBetweenRandomNoiseAllArriveInOrderWhateverTheReadSizes) {
  std::mt19937 rng(2026);  // fixed: the same stream on every run
  auto byte = [&] { return static_cast<std::uint8_t>(rng() & 0xFF); };
  std::vector<Frame> sent;
  std::string stream;
  for (int i = 0; i < 500; ++i) {
    const std::size_t noise = rng() % 80;  // up to beyond kMaxLine, with CRs, BELs, anything
    for (std::size_t k = 0; k < noise; ++k) stream += static_cast<char>(byte());
    Frame f;
    f.extended = rng() % 4 == 0;
    f.id = static_cast<std::uint32_t>(rng()) & (f.extended ? Frame::kMaxExtendedId : Frame::kMaxStandardId);
    f.rtr = rng() % 8 == 0;
    f.dlc = static_cast<std::uint8_t>(rng() % 9);
    for (auto& d : f.data) d = f.rtr ? 0 : byte();
    sent.push_back(f);
    stream += "\r" + slcan::encode(f);  // a line noise left open ends at the CR before the frame
  }
  slcan::LineReader reader;
  std::vector<Frame> received;
  for (std::size_t at = 0; at < stream.size();) {
    const std::size_t n = std::min<std::size_t>(1 + rng() % 37, stream.size() - at);
    reader.feed({stream.data() + at, n});
    at += n;
    while (auto t = reader.next())
      if (t->kind == slcan::LineReader::Token::line)
        if (auto f = slcan::decode(t->text, nullptr)) received.push_back(*f);
  }
  // Every frame sent arrives, in order; noise may, rarely, happen to spell a valid frame of its own.
  std::size_t next = 0;
  for (const Frame& f : received)
    if (next < sent.size() && f == sent[next]) ++next;
  EXPECT_EQ(next, sent.size());
  EXPECT_LE(received.size(), sent.size() + 10);
}

TEST(Slcan, BitrateCodesFollowLawicel) {
  EXPECT_EQ(slcan::bitrate_code(500000), '6');
  EXPECT_EQ(slcan::bitrate_code(1000000), '8');
  EXPECT_EQ(slcan::bitrate_code(10000), '0');
  EXPECT_THROW(slcan::bitrate_code(333333), std::invalid_argument);
}

TEST(SlcanPty, HostOpensTheAdapterAndFramesCrossBothWays) {
  auto pty = fba::can::open_pty();
  const std::string path = pty.slave_path;
  AdapterThread adapter(pty);
  slcan::SlcanBus host(path, {.bitrate = 1000000});
  EXPECT_EQ(host.name(), "slcan:" + path);
  const Frame out = make_frame(0x601, {0x40, 0x41, 0x60, 0x00, 0, 0, 0, 0});
  host.send(out);
  host.send(extended_frame());
  for (int i = 0; i < 400 && adapter.received().size() < 2; ++i) std::this_thread::sleep_for(5ms);
  ASSERT_EQ(adapter.received().size(), 2u);
  EXPECT_EQ(adapter.received()[0], out);
  EXPECT_EQ(adapter.received()[1], extended_frame());
  EXPECT_TRUE(adapter.adapter().is_open());
  EXPECT_EQ(adapter.adapter().bitrate(), 1000000);
  const Frame in = make_frame(0x581, {0x4B, 0x41, 0x60, 0x00, 0x37, 0x02, 0, 0});
  adapter.adapter().send(in);
  const auto got = host.receive(2s);
  ASSERT_TRUE(got);
  EXPECT_EQ(*got, in);
  EXPECT_FALSE(host.receive(0ms));  // nothing more: a zero timeout returns at once
}

TEST(SlcanPty, NoiseOnTheLineIsSkippedAndCountedWithTheReason) {
  auto pty = fba::can::open_pty();
  const std::string path = pty.slave_path;
  AdapterThread adapter(pty);
  slcan::SlcanBus host(path);
  const std::string noise = std::string("\x01\xFFjunk\r") + "tXYZ8\r" + std::string(300, 'B') + "\r\a";
  adapter.adapter().write_raw({reinterpret_cast<const std::uint8_t*>(noise.data()), noise.size()});
  const Frame in = make_frame(0x185, {1, 2});
  adapter.adapter().send(in);
  const auto got = host.receive(2s);
  ASSERT_TRUE(got);
  EXPECT_EQ(*got, in);
  EXPECT_EQ(host.discarded(), 4u);
  EXPECT_NE(host.last_discard_reason().find("BEL"), std::string::npos) << host.last_discard_reason();
}

TEST(SlcanPty, AnAdapterThatDoesNotAnswerIsAClearErrorNotAHang) {
  auto pty = fba::can::open_pty();  // nobody reads the master end
  try {
    slcan::SlcanBus host(pty.slave_path, {.reply_timeout = 100ms});
    FAIL() << "opened a line with no adapter";
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("no answer to 'C'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(pty.slave_path), std::string::npos) << e.what();
  }
}

// A task stopping while its adapter is awaited (a driver's constructor opens the line): the wait
// for the adapter's answers ends at the stop, not at their time-out.
TEST(SlcanPty, AStopWhileTheAdapterIsAwaitedEndsTheOpeningAtOnce) {
  auto pty = fba::can::open_pty();  // nobody answers
  std::stop_source stop;
  std::jthread stopper([&] {
    // Once the host has written its first CRs, it waits for the answers.
    char c = 0;
    while (::read(pty.master.get(), &c, 1) != 1) std::this_thread::sleep_for(1ms);
    stop.request_stop();
  });
  try {
    slcan::SlcanBus host(pty.slave_path, {.reply_timeout = 600s, .stop = stop.get_token()});
    FAIL() << "opened a line with no adapter";
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("opening the adapter stopped"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(pty.slave_path), std::string::npos) << e.what();
  }
}

TEST(SlcanPty, TheLineVanishingIsABusErrorNamingTheDevice) {
  auto pty = fba::can::open_pty();
  const std::string path = pty.slave_path;
  std::optional<slcan::SlcanBus> host;
  {
    AdapterThread adapter(pty);
    host.emplace(path);
  }  // the adapter thread has stopped; its end of the line closes with it (the slave end too)
  pty.slave.reset();
  try {
    host->receive(2s);
    FAIL() << "no error from a vanished line";
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("slcan:" + path), std::string::npos) << e.what();
  }
  EXPECT_THROW(host->send(make_frame(0x000, {1, 0})), BusError);
}

TEST(SlcanPty, AFileThatIsNotASerialLineIsRefusedSayingWhatItIs) {
  fba::test::TempDir dir;
  const std::string file = dir.file("not-a-tty", "hello");
  try {
    slcan::SlcanBus host(file);
    FAIL();
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("not a serial line but a regular file"), std::string::npos) << e.what();
  }
  try {
    slcan::SlcanBus host(dir.file("missing"));
    FAIL();
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
}

TEST(SocketpairBus, CarriesEveryFrameKindBothWays) {
  auto [a, b] = fba::can::socketpair_bus();
  for (const Frame& f :
       {make_frame(0x601, {1, 2, 3, 4, 5, 6, 7, 8}), make_frame(0x80, {}), extended_frame(), remote_frame()}) {
    a->send(f);
    const auto got = b->receive(2s);
    ASSERT_TRUE(got);
    EXPECT_EQ(*got, f);
    b->send(f);
    EXPECT_EQ(a->receive(2s), f);
  }
  EXPECT_FALSE(b->receive(1ms));
}

TEST(SocketpairBus, MalformedRecordsAreSkippedAndCounted) {
  auto [a, b] = fba::can::socketpair_bus();
  const std::uint8_t short_record[5] = {1, 2, 3, 4, 5};
  a->write_raw(short_record);
  std::uint8_t too_long[16] = {0x81, 0x05, 0, 0, 12};
  a->write_raw(too_long);
  a->send(make_frame(0x181, {9}));
  const auto got = b->receive(2s);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->id, 0x181u);
  EXPECT_EQ(b->discarded(), 2u);
  EXPECT_NE(b->last_discard_reason().find("data length 12"), std::string::npos) << b->last_discard_reason();
}

TEST(SocketpairBus, APeerThatClosesIsABusError) {
  auto [a, b] = fba::can::socketpair_bus("pair");
  a->close();
  try {
    b->receive(2s);
    FAIL();
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("pair:b"), std::string::npos) << e.what();
  }
  EXPECT_THROW(a->send(make_frame(1, {})), BusError);
}

TEST(SocketCan, RoundTripOnVcan0WhereTheKernelHasCan) {
  if (const auto why = fba::can::socketcan_unavailable()) GTEST_SKIP() << *why;
  std::unique_ptr<fba::can::FrameSocketBus> a, b;
  try {
    a = fba::can::open_socketcan("vcan0");
    b = fba::can::open_socketcan("vcan0");
  } catch (const BusError& e) {
    GTEST_SKIP() << "no usable vcan0 (" << e.what()
                 << "); create one with 'ip link add vcan0 type vcan && ip link set vcan0 up'";
  }
  const Frame f = make_frame(0x123, {1, 2, 3});
  a->send(f);
  EXPECT_EQ(b->receive(2s), f);
}

TEST(SocketCan, AMissingInterfaceIsAClearError) {
  try {
    fba::can::open_socketcan("nosuchcan9");
    FAIL();
  } catch (const BusError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("nosuchcan9"), std::string::npos) << what;
    EXPECT_TRUE(what.find("no SocketCAN support") != std::string::npos ||
                what.find("no such CAN interface") != std::string::npos)
        << what;
  }
}

TEST(SocketpairBus, AFloodOfMalformedRecordsStillEndsAtTheTimeout) {
  auto [a, b] = fba::can::socketpair_bus();
  const std::uint8_t junk[3] = {1, 2, 3};
  a->write_raw(junk);  // some junk is waiting before the wait starts, however late the flood's thread runs
  std::atomic<bool> stop{false};
  std::thread flood([&, &a = a] {
    try {
      while (!stop) a->write_raw(junk);
    } catch (const BusError&) {  // the reader closed: the flood is over
    }
  });
  EXPECT_FALSE(b->receive(20ms));
  EXPECT_GT(b->discarded(), 0u);
  stop = true;
  b->close();
  flood.join();
}

TEST(SlcanPty, AFloodOfNoiseStillEndsAtTheTimeout) {
  auto pty = fba::can::open_pty();
  const std::string path = pty.slave_path;
  AdapterThread adapter(pty);
  slcan::SlcanBus host(path);
  adapter.stop();  // from here on, this test's flood is the only writer
  const std::string noise = "tXYZ8\r";
  // Some noise is on the line before the wait starts, however late the flood's thread runs.
  adapter.adapter().write_raw({reinterpret_cast<const std::uint8_t*>(noise.data()), noise.size()});
  std::atomic<bool> stop{false};
  std::thread flood([&] {
    try {
      while (!stop) adapter.adapter().write_raw({reinterpret_cast<const std::uint8_t*>(noise.data()), noise.size()});
    } catch (const BusError&) {
    }
  });
  EXPECT_FALSE(host.receive(20ms));
  EXPECT_GT(host.discarded(), 0u);
  stop = true;
  flood.join();
}
