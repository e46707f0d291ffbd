// One spdlog logger per component, all writing through one sink (stderr by default).
#pragma once

#include <memory>
#include <string>

#include <spdlog/logger.h>

namespace fba {

std::shared_ptr<spdlog::logger> make_logger(const std::string& name);
// Level for every logger made from now on: trace, debug, info, warn,
// error, critical, off. Throws std::invalid_argument for another word.
void set_log_level(const std::string& level);

}  // namespace fba
