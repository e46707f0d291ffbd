#include "fba/log.hpp"

#include <unistd.h>

#include <cerrno>
#include <map>
#include <mutex>
#include <stdexcept>

#include <spdlog/sinks/base_sink.h>
#include <spdlog/spdlog.h>

namespace fba {
namespace {

// Standard error, coloured on a terminal. When its reader has gone (EPIPE: `fba-run ... |& head`),
// logging stops for good and the run carries on; SIGPIPE is ignored by fba-run.
class StderrSink final : public spdlog::sinks::base_sink<std::mutex> {
 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    if (closed_) return;
    spdlog::memory_buf_t text;
    formatter_->format(msg, text);
    const std::size_t start = msg.color_range_start, end = msg.color_range_end;
    if (!color_ || end <= start || end > text.size()) {
      write(text.data(), text.size());
      return;
    }
    write(text.data(), start);
    write(color(msg.level));
    write(text.data() + start, end - start);
    write("\033[m");
    write(text.data() + end, text.size() - end);
  }
  void flush_() override {}

 private:
  static const char* color(spdlog::level::level_enum level) {
    switch (level) {
      case spdlog::level::trace: return "\033[37m";
      case spdlog::level::debug: return "\033[36m";
      case spdlog::level::info: return "\033[32m";
      case spdlog::level::warn: return "\033[33m\033[1m";
      case spdlog::level::err: return "\033[31m\033[1m";
      case spdlog::level::critical: return "\033[1m\033[41m";
      default: return "";
    }
  }
  void write(const char* s) { write(s, std::char_traits<char>::length(s)); }
  void write(const char* p, std::size_t n) {
    while (n > 0 && !closed_) {
      const ssize_t w = ::write(STDERR_FILENO, p, n);
      if (w < 0) {
        if (errno == EINTR) continue;
        if (errno == EPIPE) closed_ = true;
        return;  // other errors lose this line only
      }
      p += w;
      n -= static_cast<std::size_t>(w);
    }
  }

  const bool color_ = isatty(STDERR_FILENO) == 1;
  bool closed_ = false;
};

struct Logging {
  std::mutex mutex;
  spdlog::sink_ptr sink = std::make_shared<StderrSink>();
  spdlog::level::level_enum level = spdlog::level::info;
  std::map<std::string, spdlog::level::level_enum> levels;  // by logger name or composite instance

  // The level for a logger of that name: the longest name in `levels` that is it or a composite
  // instance it is in, else the one for every logger.
  spdlog::level::level_enum level_of(const std::string& name) const {
    std::size_t best = 0;
    spdlog::level::level_enum found = level;
    for (const auto& [prefix, lvl] : levels) {
      const bool fits = name == prefix || (name.size() > prefix.size() && name.compare(0, prefix.size(), prefix) == 0 &&
                                           name[prefix.size()] == '/');
      if (fits && prefix.size() >= best) {
        best = prefix.size();
        found = lvl;
      }
    }
    return found;
  }
};

spdlog::level::level_enum parse_level(const std::string& level) {
  const auto lvl = spdlog::level::from_str(level);
  if (lvl == spdlog::level::off && level != "off")
    throw std::invalid_argument("log level '" + level + "' is not one of trace, debug, info, warn, error, critical, off");
  return lvl;
}

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
  logger->set_level(l.level_of(name));
  return logger;
}

void set_log_level(const std::string& level) {
  const auto lvl = parse_level(level);
  auto& l = logging();
  std::lock_guard lock(l.mutex);
  l.level = lvl;
  spdlog::set_level(lvl);
}

void set_log_level(const std::string& name, const std::string& level) {
  const auto lvl = parse_level(level);
  auto& l = logging();
  std::lock_guard lock(l.mutex);
  l.levels[name] = lvl;
}

spdlog::sink_ptr log_sink() {
  auto& l = logging();
  std::lock_guard lock(l.mutex);
  return l.sink;
}

void set_log_sink(spdlog::sink_ptr sink) {
  auto& l = logging();
  std::lock_guard lock(l.mutex);
  l.sink = std::move(sink);
}

}  // namespace fba
