// --serve's [ADDR:]PORT: loopback unless an address is given; every mistake said.
#include "listen_address.hpp"

#include <stdexcept>

#include <gtest/gtest.h>

namespace {

using fba::serve::parse_listen_address;

TEST(ListenAddress, APortAloneIsOnLoopback) {
  const auto a = parse_listen_address("8080");
  EXPECT_EQ(a.host, "127.0.0.1");
  EXPECT_EQ(a.port, 8080);
  EXPECT_TRUE(a.loopback);
  EXPECT_EQ(parse_listen_address("0").port, 0);
}

TEST(ListenAddress, AnotherAddressOnlyWhenGiven) {
  const auto any = parse_listen_address("0.0.0.0:9000");
  EXPECT_EQ(any.host, "0.0.0.0");
  EXPECT_FALSE(any.loopback);
  const auto v6 = parse_listen_address("[::1]:9000");
  EXPECT_EQ(v6.host, "::1");
  EXPECT_TRUE(v6.loopback);
  EXPECT_EQ(fba::serve::url_host(v6.host), "[::1]");
  EXPECT_EQ(parse_listen_address("localhost:1").host, "127.0.0.1");
}

TEST(ListenAddress, MistakesAreRefusedSayingWhatWasExpected) {
  for (const char* bad : {"", "http", "65536", "-1", "80x", "host.example:80", "::1:80", "[::1]80", "[::1", "1.2.3:80", ":"}) {
    try {
      parse_listen_address(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("--serve"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(std::string("'") + bad), std::string::npos) << e.what();
    }
  }
}

}  // namespace
