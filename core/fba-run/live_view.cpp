// fba-run's live view and report (see live_view.hpp).
#include "live_view.hpp"

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>

#include <nlohmann/json.hpp>

#include "page_files.hpp"
#include "report_page.hpp"
#include "run_state.hpp"
#include "summary_file.hpp"

namespace fba_run {

namespace {

// The protocol's rate of updates: ten a second.
constexpr std::chrono::milliseconds kPeriod{100};
// How long the end waits for a page to take what is queued before cutting it off.
constexpr std::chrono::milliseconds kEndGrace{2000};

}  // namespace

LiveView::LiveView(const Options& o, const fba::TaskConfig& config) : config_(config) {
  web_dir_ = fba::serve::find_web_dir();
  if (!o.output_dir.empty()) {
    std::error_code ec;
    if (fs::is_regular_file(web_dir_ / "report.html", ec)) report_ = fs::absolute(o.output_dir) / "report.html";
    else
      std::cerr << "fba-run: no report.html written: the live page's front end is not built (" << (web_dir_ / "report.html").string()
                << " is missing); install npm and run tools/dev.sh again, or set FBA_WEB_DIR to a built page\n";
  }
  if (!o.serve && report_.empty()) return;  // nobody to show the run to: nothing sampled
  feed_.emplace(record_, config, state().run_id);
  if (!o.serve) return;
  fba::serve::ServerOptions options;
  options.address = *o.serve;
  options.page = fba::serve::PageFiles::load(web_dir_);
  server_ = std::make_unique<fba::serve::LiveServer>(std::move(options), record_);
  keep_ = o.serve_keep;
  feed_->publish_to(server_.get());
  const std::string line = "fba-run: live view at " + server_->url() + "\n";
  std::fwrite(line.data(), 1, line.size(), stderr);  // one write: a reader never sees half the address
}

// A run that ended before its task ran (a constructor refused, a device failed, a signal): the
// pages are told, with the summary when there is one, instead of waiting for an end that never comes.
LiveView::~LiveView() {
  if (!feed_ || ended_) return;
  try {
    nlohmann::json summary;
    if (const fs::path file = state().summary; !file.empty()) {
      std::ifstream in(file, std::ios::binary);
      summary = nlohmann::json::parse(in, nullptr, false);
    }
    nlohmann::json end{{"type", "end"}};
    if (summary.is_object() && summary.value("outcome", "running") != "running") {
      end["outcome"] = summary["outcome"];
      end["exit_code"] = summary.value("exit_code", -1);
      end["reason"] = summary.value("reason", "");
    } else {
      const int sig = state().signal.load();
      end["outcome"] = sig ? "interrupted" : "not_run";
      end["exit_code"] = sig ? 128 + sig : -1;
      end["reason"] = std::string("the run ended while ") + state().phase.load() + ", before its task ran; fba-run said why on stderr";
    }
    end["summary"] = summary.is_object() ? summary : nlohmann::json(nullptr);
    feed_->end_with(end.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    keep_serving();
    close_pages();
  } catch (const std::exception& e) {  // a destructor says what failed and goes on
    std::cerr << "fba-run: live view: " << e.what() << "\n";
  }
}

void LiveView::watch(fba::Task& task, Monitor& monitor) {
  if (!feed_) return;
  feed_->watch(task, config_);
  monitor.watch([this](const fba::RunResult& now, const fba::RunResult* previous) { feed_->sample(now, previous); },
                Monitor::Schedule{kPeriod, true});
}

void LiveView::before_summary() {
  if (!report_.empty()) std::ofstream(report_).flush();  // written now, so listed as this run's
}

std::string LiveView::summary_text(const fba::RunResult& result) const {
  const fs::path summary = state().summary;
  if (!summary.empty()) {
    std::ifstream in(summary, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (in) return text.str();
  }
  fba::RunResult r = result;
  r.run_id = state().run_id;
  return fba::summary_json(r, config_);
}

void LiveView::end(const fba::RunResult& result) {
  if (!feed_) return;
  ended_ = true;
  feed_->end(result, summary_text(result));
  if (!report_.empty())
    if (const std::string error = fba::serve::write_report(web_dir_, report_, record_.replay().messages); !error.empty()) {
      std::cerr << "fba-run: report.html: " << error << "\n";
      std::error_code ec;
      fs::remove(report_, ec);  // not the placeholder, which the summary lists as the report
    }
  if (!keep_) close_pages();
}

void LiveView::keep_serving() {
  auto& st = state();
  if (!server_ || !keep_ || st.stop.stop_requested()) return;
  st.phase.store("serving the run's final state");
  const std::string line = "fba-run: the run is over; still serving its live view at " + server_->url() +
                           " (--serve-keep) until SIGINT or SIGTERM\n";
  std::fwrite(line.data(), 1, line.size(), stderr);
  // The signal watcher takes the signal and requests the stop; the callback this wait registers on
  // the stop token wakes it.
  std::mutex mutex;
  std::condition_variable_any stopped;
  std::unique_lock lock(mutex);
  stopped.wait(lock, st.stop.get_token(), [] { return false; });
  close_pages();
}

void LiveView::close_pages() {
  if (server_) server_->finish(kEndGrace);
}

}  // namespace fba_run
