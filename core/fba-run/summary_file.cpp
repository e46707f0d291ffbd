// summary.json (see summary_file.hpp): written whole at each end, named by the run's id, listing
// the files this run wrote into the output folder. Apart from the run because every way out writes
// it: the main thread, the forced exit, an unexpected exit() and the crash handler.
#include "summary_file.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <vector>

#include <nlohmann/json.hpp>

#include "run_state.hpp"

namespace fba_run {

namespace {

// The files under the output folder written since summary.json's placeholder (start_summary), by
// path relative to the folder: what this run made, as against what an earlier run left there.
// Bounded: a folder of a million files is not listed whole.
std::vector<std::string> artefacts_since(const fs::path& summary) {
  std::vector<std::string> found;
  std::error_code ec;
  const auto since = fs::last_write_time(summary, ec);
  if (ec) return found;
  const fs::path dir = summary.parent_path();
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end && found.size() < 10000; it.increment(ec)) {
    std::error_code e;
    if (!it->is_regular_file(e) || it->path() == summary) continue;
    if (const auto t = it->last_write_time(e); !e && t >= since) found.push_back(fs::relative(it->path(), dir, e).string());
  }
  std::sort(found.begin(), found.end());
  return found;
}

}  // namespace

std::string start_summary() {
  auto& st = state();
  const nlohmann::json j{{"run_id", st.run_id}, {"task_file", st.config.file.string()}, {"outcome", "running"}};
  const std::string text = j.dump(2) + "\n";
  std::FILE* f = std::fopen(st.summary.c_str(), "w");
  if (!f) return st.summary.string() + ": " + std::strerror(errno);
  bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  ok = std::fflush(f) == 0 && ok;
  const int error = errno;
  ok = std::fclose(f) == 0 && ok;
  return ok ? std::string() : st.summary.string() + ": " + std::strerror(error ? error : errno);
}

std::string write_summary(const fba::RunResult& result, fs::path to) {
  auto& st = state();
  if (st.summary.empty()) return {};
  if (to.empty()) to = st.summary;
  fba::RunResult r = result;
  r.run_id = st.run_id;
  r.artefacts = artefacts_since(st.summary);
  const std::string text = fba::summary_json(r, st.config);
  std::FILE* f = std::fopen(to.c_str(), "w");
  if (!f) return to.string() + ": " + std::strerror(errno);
  const bool wrote = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  const int write_errno = errno;
  const bool flushed = std::fflush(f) == 0;
  const int flush_errno = errno;
  const bool closed = std::fclose(f) == 0;
  if (wrote && flushed && closed) return {};
  return to.string() + ": " + std::strerror(!wrote ? write_errno : !flushed ? flush_errno : errno);
}

fba::RunResult early_result(fba::Outcome outcome, const std::string& reason) {
  fba::RunResult r;
  r.outcome = outcome;
  r.reason = reason;
  r.phase = state().phase.load();
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - state().started).count();
  if (outcome == fba::Outcome::Interrupted) r.signal = state().signal.load();
  return r;
}

}  // namespace fba_run
