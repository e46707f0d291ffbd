// What the views' tests share: a view's JSON read back, its protocol shapes checked
// (docs/live-view.md), and an image view's picture decoded.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <fba/packet.hpp>
#include <fba/view.hpp>
#include <nlohmann/json.hpp>

namespace fba::test {

using nlohmann::json;

// The registered view of p's type applied to p, parsed; fails the test when there is no view.
inline json view_of(const Packet& p) {
  const ViewFunction f = find_view(p.type());
  if (!f) {
    ADD_FAILURE() << "no view registered for " << (p.type() ? p.type()->name : "nothing");
    return nullptr;
  }
  const std::string text = f(p);
  if (text.empty()) return nullptr;
  return json::parse(text);  // throws, failing the test, on text that is not JSON
}

template <class T>
json view_of(T value) {
  return view_of(Packet::make(std::make_shared<const T>(std::move(value))));
}

// An array of n numbers (n < 0: any count).
inline bool numbers(const json& j, int n) {
  if (!j.is_array() || (n >= 0 && j.size() != static_cast<std::size_t>(n))) return false;
  for (const json& v : j)
    if (!v.is_number()) return false;
  return true;
}

inline std::vector<unsigned char> from_base64(const std::string& text) {
  static const std::string digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<unsigned char> out;
  unsigned v = 0;
  int bits = 0;
  for (char c : text) {
    if (c == '=') break;
    const auto d = digits.find(c);
    if (d == std::string::npos) {
      ADD_FAILURE() << "not base64: '" << c << "'";
      return {};
    }
    v = (v << 6) | static_cast<unsigned>(d);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<unsigned char>((v >> bits) & 0xFF));
    }
  }
  return out;
}

}  // namespace fba::test
