// fba-run's live view and report (docs/live-view.md): with --serve, the server and its URL on
// stderr; with --output-dir, report.html. Both fed by one LiveFeed, sampled on the Monitor's thread.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "fba/task.hpp"
#include "live_feed.hpp"
#include "live_server.hpp"
#include "monitor.hpp"
#include "options.hpp"
#include "run_record.hpp"

namespace fba_run {

class LiveView {
 public:
  // Without --serve or --output-dir, nothing. With --serve, listens now and says where on stderr;
  // throws std::runtime_error when it cannot.
  LiveView(const Options& o, const fba::TaskConfig& config);
  ~LiveView();  // a run that ended before its task ran: its end said to the pages

  // Before the run: the task's outputs that have views watched, and the feed sampled by `monitor`
  // (before its start()).
  void watch(fba::Task& task, Monitor& monitor);

  // Before summary.json is written: report.html's place taken, so that the summary lists it.
  void before_summary();
  // The run is over (the monitor's last sample given): the end message, report.html written, and
  // the server's pages sent what is queued and closed (with --serve-keep: left open, see below).
  void end(const fba::RunResult& result);

  // With --serve-keep, once the run is over and its summary written (also a run that ended before
  // its task ran, from the destructor): says so on stderr and serves the run's final state until a
  // stop signal (State::stop), then closes the pages. Returns at once without --serve-keep, or when
  // a signal has already stopped the run: it asked fba-run to end.
  void keep_serving();

 private:
  std::string summary_text(const fba::RunResult& result) const;
  void close_pages();

  const fba::TaskConfig& config_;
  std::filesystem::path web_dir_, report_;  // report_: empty without --output-dir or a template
  fba::serve::RunRecord record_;
  std::optional<fba::serve::LiveFeed> feed_;
  std::unique_ptr<fba::serve::LiveServer> server_;
  bool ended_ = false;
  bool keep_ = false;  // --serve-keep
};

}  // namespace fba_run
