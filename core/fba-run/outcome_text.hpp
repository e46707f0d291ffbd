// fba-run's last line: how the run ended, in words ("held the object after 5 views, grasp score
// 0.53, epsilon 0.057, 2.8 s"), from the final event and what the components reported; the whole payload is
// summary.json's.
#pragma once

#include <string>

#include "fba/task.hpp"

namespace fba_run {

// The outcome in a sentence, without "fba-run: " and without a newline; control bytes escaped.
std::string outcome_text(const fba::RunResult& result);

// A duration as people read it: "1.7 ms", "0.41 s", "2.8 s", "3 min 12 s".
std::string seconds_text(double s);

}  // namespace fba_run
