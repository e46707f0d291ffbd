// `fba-evaluate grasp <args>` as a user runs it, to its end: its exit status and what it printed.
#pragma once

#include <string>

#include "support/build_paths.hpp"
#include "support/run_command.hpp"

namespace fba::test {

inline CommandResult evaluate_grasp(const std::string& args) {
  return run_command("'" + program("fba-evaluate") + "' grasp " + args);
}

}  // namespace fba::test
