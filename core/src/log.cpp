#include "fba/log.hpp"

#include <mutex>
#include <stdexcept>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

namespace fba {
namespace {

struct Logging {
  std::mutex mutex;
  spdlog::sink_ptr sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  spdlog::level::level_enum level = spdlog::level::info;
};

Logging& logging() {
  static Logging* l = new Logging;  // alive for loggers destroyed during exit
  return *l;
}

}  // namespace

std::shared_ptr<spdlog::logger> make_logger(const std::string& name) {
  auto& l = logging();
  std::lock_guard lock(l.mutex);
  auto logger = std::make_shared<spdlog::logger>(name, l.sink);
  logger->set_pattern("[%H:%M:%S.%e] [%n] %^%l%$: %v");
  logger->set_level(l.level);
  return logger;
}

void set_log_level(const std::string& level) {
  auto lvl = spdlog::level::from_str(level);
  if (lvl == spdlog::level::off && level != "off")
    throw std::invalid_argument("log level '" + level + "' is not one of trace, debug, info, warn, error, critical, off");
  auto& l = logging();
  std::lock_guard lock(l.mutex);
  l.level = lvl;
  spdlog::set_level(lvl);
}

}  // namespace fba
