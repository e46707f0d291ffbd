// `fba-evaluate grasp <args>` as a user runs it, to its end: its exit status and what it printed;
// and the line of its output that starts so.
#pragma once

#include <sstream>
#include <string>

#include "support/build_paths.hpp"
#include "support/run_command.hpp"

namespace fba::test {

inline CommandResult evaluate_grasp(const std::string& args) {
  return run_command("'" + program("fba-evaluate") + "' grasp " + args);
}

// The line of `text` that starts with `start`, or "".
inline std::string line_starting(const std::string& text, const std::string& start) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(start, 0) == 0) return line;
  return "";
}

}  // namespace fba::test
