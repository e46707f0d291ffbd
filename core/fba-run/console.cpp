// fba-run's console (see console.hpp). The progress comes from the Monitor's samples: what the
// components report (their stage, the result "views") and their state (a call running across
// samples), never from parsing their log.
#include "console.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <string_view>

#include <nlohmann/json.hpp>

#include "fba/message_text.hpp"
#include "outcome_text.hpp"

namespace fba_run {

namespace {

// A call running this long is said: shorter ones are the run's ordinary work.
constexpr double kBusyAfterS = 1.0;

long long integer_result(const fba::ComponentStats& c, const char* name) {
  const auto it = c.results.find(name);
  if (it == c.results.end()) return -1;
  const auto j = nlohmann::json::parse(it->second, nullptr, false);
  return j.is_number_integer() ? j.get<long long>() : -1;
}

long long integer_param(const fba::TaskConfig& config, const std::string& component, const char* name) {
  const fba::ComponentConfig* c = config.find(component);
  if (!c) return -1;
  const auto it = c->params.find(name);
  if (it == c->params.end() || !std::holds_alternative<std::int64_t>(it->second)) return -1;
  return std::get<std::int64_t>(it->second);
}

std::string at(double s) { return "[" + seconds_text(s) + "] "; }

// The terminal's width, so that a progress line never wraps (a wrapped line is not erased whole).
std::size_t width(int fd) {
  winsize w{};
  if (ioctl(fd, TIOCGWINSZ, &w) == 0 && w.ws_col > 10) return w.ws_col;
  return 80;
}

class ConsoleSink final : public spdlog::sinks::sink {
 public:
  ConsoleSink(std::shared_ptr<Console> console, spdlog::sink_ptr inner) : console_(std::move(console)), inner_(std::move(inner)) {}
  void log(const spdlog::details::log_msg& msg) override {
    console_->above([&] { inner_->log(msg); });
  }
  void flush() override { inner_->flush(); }
  void set_pattern(const std::string& pattern) override { inner_->set_pattern(pattern); }
  void set_formatter(std::unique_ptr<spdlog::formatter> formatter) override { inner_->set_formatter(std::move(formatter)); }

 private:
  std::shared_ptr<Console> console_;
  spdlog::sink_ptr inner_;
};

}  // namespace

std::vector<Step> steps_of(const fba::RunResult& now, const fba::TaskConfig& config) {
  std::vector<Step> steps;
  for (const auto& c : now.components) {
    Step s{c.name, c.stage, integer_result(c, "views"), -1};
    if (s.view >= 0) s.of = integer_param(config, c.name, "max_views");
    if (!s.stage.empty() || s.view >= 0) steps.push_back(std::move(s));
  }
  return steps;
}

std::string step_text(const Step& step) {
  std::string s = fba::escape_controls(step.component) + ":";
  if (!step.stage.empty()) s += " " + fba::escape_controls(step.stage);
  if (step.view >= 0) {
    s += step.stage.empty() ? " view " : ", view ";
    s += std::to_string(step.view);
    if (step.of >= 0) s += " of " + std::to_string(step.of);
  }
  return s;
}

Console::Console(const fba::TaskConfig& config, int fd, bool terminal) : config_(config), fd_(fd), terminal_(terminal) {}

spdlog::sink_ptr Console::log_sink(std::shared_ptr<Console> console, spdlog::sink_ptr inner) {
  return std::make_shared<ConsoleSink>(std::move(console), std::move(inner));
}

void Console::write(const std::string& text) {
  const char* p = text.data();
  std::size_t n = text.size();
  while (n > 0) {
    const ssize_t w = ::write(fd_, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return;  // the reader went away: the progress is lost, the run goes on
    p += w;
    n -= static_cast<std::size_t>(w);
  }
}

void Console::erase() {
  if (!drawn_) return;
  write("\r\033[K");
  drawn_ = false;
}

void Console::draw() {
  if (!terminal_ || shown_.empty() || closed_) return;
  const std::size_t room = width(fd_) - 1;
  write(shown_.size() > room ? shown_.substr(0, room - 3) + "..." : shown_);
  drawn_ = true;
}

// "arm busy for 3.1 s": the components in one call since at least kBusyAfterS. Without a
// terminal, each such call is said once, on a line of its own.
std::string Console::busy_text(const fba::RunResult& now, const fba::RunResult* previous) {
  std::string text;
  std::map<std::string, Busy> still;
  for (const auto& c : now.components) {
    if (c.state != "running") continue;
    Busy b{c.invocations, now.wall_s, false};
    if (const auto it = busy_.find(c.name); previous && it != busy_.end() && it->second.invocation == c.invocations) b = it->second;
    const double for_s = now.wall_s - b.since_s;
    if (for_s >= kBusyAfterS) {
      text += "; " + fba::escape_controls(c.name) + " busy for " + seconds_text(for_s);
      if (!terminal_ && !b.said) write(at(now.wall_s) + fba::escape_controls(c.name) + ": busy in one call for " + seconds_text(for_s) + "\n");
      b.said = true;
    }
    still.emplace(c.name, b);
  }
  busy_ = std::move(still);
  return text;
}

void Console::update(const fba::RunResult& now, const fba::RunResult* previous) {
  std::lock_guard lock(mutex_);
  if (closed_) return;
  std::vector<Step> steps = steps_of(now, config_);
  std::map<std::string_view, const Step*> before;
  for (const auto& s : steps_) before.emplace(s.component, &s);
  std::string changed;  // the steps that are new since the last sample
  for (const auto& s : steps) {
    const auto it = before.find(s.component);
    if (it == before.end() || !(*it->second == s)) changed += (changed.empty() ? "" : "; ") + step_text(s);
  }
  steps_ = std::move(steps);
  if (!changed.empty()) {
    step_since_s_ = now.wall_s;
    if (drawn_) {
      write("\n");  // the finished step's line stays above, with the time it took
      drawn_ = false;
    }
    if (!terminal_) write(at(now.wall_s) + changed + "\n");
    step_line_ = at(now.wall_s) + changed;
  }
  const std::string busy = busy_text(now, previous);
  if (!terminal_) return;
  if (step_line_.empty()) {  // no component has a stage or a view: the samples so far
    std::uint64_t samples = 0;
    for (const auto& c : now.components) samples += c.kind == fba::Kind::Sensor ? c.samples_out : 0;
    shown_ = at(now.wall_s) + "running: " + std::to_string(samples) + " samples" + busy;
  } else {
    shown_ = step_line_ + " (" + seconds_text(now.wall_s - step_since_s_) + ")" + busy;
  }
  erase();
  draw();
}

void Console::close() {
  std::lock_guard lock(mutex_);
  erase();
  closed_ = true;
}

}  // namespace fba_run
