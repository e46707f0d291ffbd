// Each run of a batch as an fba-run child process (posix_spawn), its output to log.txt.
#include "batch_jobs.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "options.hpp"

extern char** environ;

namespace fba::evaluate::batch {

namespace {

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
  return s;
}

}  // namespace

void prepare(Job& job, const BatchList& l, const std::string& fba_run) {
  const RunSpec& r = *job.run;
  std::vector<std::string> sets = l.set;
  for (const auto& t : l.pose_set) {
    std::string s = replace_all(t, "{mesh}", r.mesh);
    s = replace_all(s, "{x}", number(r.x));
    s = replace_all(s, "{y}", number(r.y));
    s = replace_all(s, "{yaw}", number(r.yaw));

    sets.push_back(std::move(s));
  }
  sets.insert(sets.end(), job.variant->set.begin(), job.variant->set.end());
  sets.insert(sets.end(), r.set.begin(), r.set.end());
  job.argv = {fba_run, l.task.string(), "-o", job.dir.string(), "--run-id", job.run_id};
  job.argv.insert(job.argv.end(), l.fba_run_args.begin(), l.fba_run_args.end());
  for (const auto& s : sets) job.argv.insert(job.argv.end(), {"--set", s});
}

std::string command_line(const Job& job) {
  std::string line;
  for (const auto& a : job.argv) line += (line.empty() ? "" : " ") + a;
  return line;
}

namespace {

// Starts the job's fba-run, its output to log.txt; setup_error says why when it cannot.
void start(Job& job) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string log = (job.dir / "log.txt").string();
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  for (auto& a : job.argv) argv.push_back(a.data());
  argv.push_back(nullptr);
  job.started = Clock::now();
  const int e = posix_spawnp(&job.pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (e != 0) {
    job.pid = -1;
    job.setup_error = "cannot start '" + job.argv[0] + "': " + std::strerror(e) + " (give --fba-run PATH)";
  }
}

void on_stop_signal(int sig) {
  if (!stop_signal) stop_signal = sig;
}

// How long a run stopped in order (a timeout, the batch's own stop) has to write its summary
// before it is killed.
constexpr double kStopGraceS = 20;

}  // namespace

volatile std::sig_atomic_t stop_signal = 0;

void catch_stop_signals() {
  for (int sig : {SIGTERM, SIGINT, SIGHUP}) {
    struct sigaction old {};
    sigaction(sig, nullptr, &old);
    if (old.sa_handler == SIG_IGN) continue;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(sig, &sa, nullptr);
  }
}

std::string signal_name(int sig) {
  return sig == SIGTERM ? "SIGTERM" : sig == SIGINT ? "SIGINT" : sig == SIGHUP ? "SIGHUP" : "signal " + std::to_string(sig);
}

void run_all(std::vector<Job>& jobs, int parallel, double timeout_s) {
  std::size_t next = 0, running = 0, done = 0;
  std::map<pid_t, Job*> by_pid;
  auto progress = [&](const Job& j, const std::string& what) {
    std::fprintf(stderr, "[%zu/%zu] %s %s: %s\n", done, jobs.size(), j.variant->name.c_str(), j.dir.filename().c_str(), what.c_str());
  };
  // Reaps one child that ended, if any; false when none had.
  auto reap = [&](int flags) {
    int status = 0;
    rusage usage{};
    const pid_t pid = wait4(-1, &status, flags, &usage);
    if (pid < 0 && errno != EINTR && errno != ECHILD) throw std::runtime_error(std::string("waiting for fba-run: ") + std::strerror(errno));
    if (pid <= 0 || !by_pid.count(pid)) return false;
    Job& j = *by_pid[pid];
    by_pid.erase(pid);
    --running;
    ++done;
    j.status = status;
    j.elapsed_s = std::chrono::duration<double>(Clock::now() - j.started).count();
    j.cpu_s = usage.ru_utime.tv_sec + usage.ru_stime.tv_sec + 1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
    progress(j, WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status)) : "signal " + std::to_string(WTERMSIG(status)));
    return true;
  };
  while (done < jobs.size() && !stop_signal) {
    while (running < static_cast<std::size_t>(parallel) && next < jobs.size() && !stop_signal) {
      Job& j = jobs[next++];
      if (j.setup_error.empty()) start(j);
      if (!j.setup_error.empty()) {
        ++done;
        progress(j, j.setup_error);
        continue;
      }
      by_pid[j.pid] = &j;
      ++running;
    }
    if (running == 0) continue;
    if (reap(WNOHANG)) continue;
    // A run past its time is asked to stop in order (it then writes its summary), then killed.
    for (auto& [p, j] : by_pid) {
      const double age = std::chrono::duration<double>(Clock::now() - j->started).count();
      if (age > timeout_s && !j->term_sent) {
        kill(p, SIGTERM);
        j->term_sent = true;
      } else if (age > timeout_s + kStopGraceS && !j->kill_sent) {
        kill(p, SIGKILL);
        j->kill_sent = true;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (!stop_signal) return;
  const int sig = stop_signal;
  const std::string name = signal_name(sig);
  std::fprintf(stderr, "fba-evaluate grasp --batch: %s: stopping %zu running run(s)\n", name.c_str(), running);
  for (auto& [p, j] : by_pid) {
    kill(p, sig);
    j->stopped_by = sig;
  }
  const auto stopping = Clock::now();
  while (running > 0 && std::chrono::duration<double>(Clock::now() - stopping).count() < kStopGraceS)
    if (!reap(WNOHANG)) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  for (auto& [p, j] : by_pid) {
    kill(p, SIGKILL);
    j->kill_sent = true;
  }
  while (running > 0)
    if (!reap(0) && errno == ECHILD) break;
  for (std::size_t i = next; i < jobs.size(); ++i) {
    jobs[i].stopped_by = sig;
    jobs[i].setup_error = "the batch was stopped by " + name + " before this run started";
  }
}

std::string default_fba_run() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec && fs::exists(self.parent_path() / "fba-run")) return (self.parent_path() / "fba-run").string();
  return "fba-run";
}

bool on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream folders(path ? path : "");
  for (std::string folder; std::getline(folders, folder, ':');) {
    const fs::path p = fs::path(folder.empty() ? "." : folder) / name;
    std::error_code ec;
    if (access(p.c_str(), X_OK) == 0 && !fs::is_directory(p, ec)) return true;
  }
  return false;
}

std::string folder_name(std::size_t index, const std::string& object) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%02zu-", index + 1);
  return buf + object;
}

}  // namespace fba::evaluate::batch
