// fba-run's --log-level: LEVEL for every logger, COMPONENT=LEVEL for one component of the task (or
// a composite instance and the components inside it), repeatable.
#pragma once

#include <string>
#include <vector>

#include "fba/task_config.hpp"

namespace fba_run {

// Without `task`: every value's form and level word checked and the levels applied (a component's
// reaches its logger when the component is constructed). With it: each COMPONENT's name checked
// against the task's components. Returns what is wrong with the first value refused; empty if none.
std::string apply_log_levels(const std::vector<std::string>& values, const fba::TaskConfig* task);

}  // namespace fba_run
