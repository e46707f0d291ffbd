// What the types' views (fba/view.hpp, docs/live-view.md) share: numbers rounded to what a person
// can see, points and poses in the protocol's shapes, and JSON text that never throws.
#pragma once

#include <charconv>
#include <cmath>
#include <string>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

namespace fba::views {

using nlohmann::json;

// Decimals kept: 10 um in metres (a depth-9 leaf of a 1 m box is 2 mm), 1e-6 of a unit quaternion
// or a radian, a tenth of a pixel. Fewer digits make a model's view a third of its size.
constexpr double kMetres = 1e5;
constexpr double kUnit = 1e6;
constexpr double kPixels = 10;

// v rounded to 1/scale (a power of ten, so the result prints short); null when not finite, which
// JSON cannot hold.
inline json number(double v, double scale) {
  if (!std::isfinite(v)) return nullptr;
  return std::round(v * scale) / scale;
}

inline json xyz(const Eigen::Vector3d& v, double scale = kMetres) {
  return json::array({number(v.x(), scale), number(v.y(), scale), number(v.z(), scale)});
}

// {"position":[x,y,z], "rotation":[qw,qx,qy,qz]}: the transform's translation (metres) and rotation.
inline json pose(const Eigen::Isometry3d& t) {
  Eigen::Quaterniond q(t.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;  // one of the two equal quaternions, so that poses compare as text
  return {{"position", xyz(t.translation())},
          {"rotation", json::array({number(q.w(), kUnit), number(q.x(), kUnit), number(q.y(), kUnit), number(q.z(), kUnit)})}};
}

// The view's text. Names come from devices and files: invalid UTF-8 is replaced, not thrown on.
inline std::string dump(const json& view) { return view.dump(-1, ' ', false, json::error_handler_t::replace); }

// Appends v rounded to 1/scale (a power of ten), as JSON (null when not finite), for the arrays
// built by hand: fixed decimals written as integers, several times faster than a shortest
// round-trip conversion, which a model's view does 10^5 times.
inline void append_number(std::string& out, double v, double scale) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  const double scaled = std::round(v * scale);
  char buf[40];
  if (!(std::abs(scaled) < 9e15)) {  // beyond exact integers: as the number itself
    out.append(buf, std::to_chars(buf, buf + sizeof buf, scaled / scale).ptr);
    return;
  }
  const auto q = static_cast<long long>(scaled);
  const auto unit = static_cast<long long>(scale);
  const unsigned long long a = q < 0 ? 0ull - static_cast<unsigned long long>(q) : static_cast<unsigned long long>(q);
  if (q < 0) out += '-';
  out.append(buf, std::to_chars(buf, buf + sizeof buf, a / static_cast<unsigned long long>(unit)).ptr);
  unsigned long long frac = a % static_cast<unsigned long long>(unit);
  if (frac == 0) return;
  int digits = 0;
  for (long long u = unit; u > 1; u /= 10) ++digits;
  while (frac % 10 == 0) frac /= 10, --digits;  // no trailing zeros
  char* end = buf + digits;
  for (char* c = end; c != buf; frac /= 10) *--c = static_cast<char>('0' + frac % 10);
  out += '.';
  out.append(buf, end);
}

}  // namespace fba::views
