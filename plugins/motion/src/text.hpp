// How the motion library writes figures into its messages.
#pragma once

#include <cstdio>
#include <string>

#include <Eigen/Core>

namespace fba::motion::text {

inline std::string format(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

inline std::string metres(double v) { return format("%.3f m", v); }

inline std::string point(const Eigen::Vector3d& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
  return buf;
}

}  // namespace fba::motion::text
