// One spdlog logger per component, all writing through one sink (stderr by default).
#pragma once

#include <memory>
#include <string>

#include <spdlog/common.h>
#include <spdlog/logger.h>

namespace fba {

std::shared_ptr<spdlog::logger> make_logger(const std::string& name);
// Level for every logger made from now on: trace, debug, info, warn,
// error, critical, off. Throws std::invalid_argument for another word.
void set_log_level(const std::string& level);
// Level for the loggers made from now on whose name is `name` or begins with `name` + "/" (the
// components inside a composite instance), over the one for every logger; the longest name that
// fits wins. Throws std::invalid_argument for a level that is not one of the words above.
void set_log_level(const std::string& name, const std::string& level);
// Where the loggers made from now on write (standard error, coloured on a terminal, by default):
// a sink that wraps log_sink() keeps stderr's writing and adds its own (fba-run's progress line).
spdlog::sink_ptr log_sink();
void set_log_sink(spdlog::sink_ptr sink);

}  // namespace fba
