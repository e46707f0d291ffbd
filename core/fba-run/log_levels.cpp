// --log-level (see log_levels.hpp), applied to the loggers the runtime makes for the components
// (fba/log.hpp), so it must be applied before they are constructed.
#include "log_levels.hpp"

#include <set>
#include <stdexcept>

#include "fba/log.hpp"
#include "fba/message_text.hpp"

namespace fba_run {

namespace {

// The names a COMPONENT=LEVEL may give: each component's ("relay/first" inside the composite
// instance "relay") and each composite instance's ("relay").
std::set<std::string> component_names(const fba::TaskConfig& task) {
  std::set<std::string> names;
  for (const auto& c : task.components)
    for (std::size_t slash = c.name.find('/'); slash != std::string::npos; slash = c.name.find('/', slash + 1))
      names.insert(c.name.substr(0, slash));
  for (const auto& c : task.components) names.insert(c.name);
  return names;
}

std::string listed(const std::set<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

}  // namespace

std::string apply_log_levels(const std::vector<std::string>& values, const fba::TaskConfig* task) {
  const std::set<std::string> names = task ? component_names(*task) : std::set<std::string>{};
  for (const auto& value : values) {
    const auto eq = value.find('=');
    const std::string name = eq == std::string::npos ? "" : value.substr(0, eq);
    const std::string level = eq == std::string::npos ? value : value.substr(eq + 1);
    if (eq != std::string::npos && name.empty())
      return "--log-level '" + fba::escape_controls(value) + "': give COMPONENT=LEVEL or LEVEL";
    if (task) {
      if (!name.empty() && !names.count(name))
        return "--log-level " + fba::escape_controls(value) + ": the task has no component '" + fba::escape_controls(name) +
               "'; its components are " + listed(names);
      continue;
    }
    try {  // a component's level before its name can be checked: no logger has it until construction
      if (name.empty()) fba::set_log_level(level);
      else fba::set_log_level(name, level);
    } catch (const std::invalid_argument& e) {
      return "--log-level " + fba::escape_controls(value) + ": " + e.what();
    }
  }
  return {};
}

}  // namespace fba_run
