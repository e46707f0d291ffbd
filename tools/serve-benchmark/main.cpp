// fba-serve-benchmark: what the live view costs a run. The runtime benchmark's chain (a counter,
// ten passthroughs, a sink) run by fba-run, in rounds, once plainly and once with --serve and a
// page connected that reads every message (ten updates a second), in alternating order; the
// throughput of each from its summary.json (samples over the run's time, construction left out),
// and the cost as the median of the rounds' ratios, so that a machine whose load drifts slows both
// runs of a round alike.
//
//   fba-serve-benchmark [--rounds N] [--samples N] [--executor threaded|deterministic]
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "support/live_client.hpp"
#include "support/build_paths.hpp"
#include "support/child_process.hpp"

namespace {

namespace fs = std::filesystem;
using namespace fba::test;

struct Run {
  double samples_per_s = 0;
  double cpu_s = 0;          // the fba-run process's user + system time, all its threads
  std::size_t messages = 0;  // what the page received, served runs only
};

std::string chain_task(long samples) {
  std::string t = "task: served_chain\ncomponents:\n  source: { type: examples.counter, params: { count: " + std::to_string(samples) +
                  " } }\n";
  for (int i = 0; i < 10; ++i) t += "  p" + std::to_string(i) + ": { type: examples.passthrough }\n";
  t += "  sink: { type: examples.sink, params: { expected: " + std::to_string(samples) + " } }\nconnections:\n  - source.out -> p0.in\n";
  for (int i = 1; i < 10; ++i) t += "  - p" + std::to_string(i - 1) + ".out -> p" + std::to_string(i) + ".in\n";
  t += "  - p9.out -> sink.in\non:\n  sink.done: stop_success\n  sink.gap: stop_failure\n";
  return t;
}

double children_cpu_s() {
  rusage u{};
  ::getrusage(RUSAGE_CHILDREN, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// One run of fba-run; with `serve`, a page reads its live stream to the end.
Run run_once(const fs::path& task, const fs::path& out, long samples, const std::string& executor, bool serve) {
  const double cpu_before = children_cpu_s();
  std::vector<std::string> args{program("fba-run"), task.string(), "-o", out.string(), "-e", executor};
  if (serve) args.insert(args.end(), {"--serve", "0"});
  Child child(args);
  Run r;
  if (serve) {
    const std::string prefix = "fba-run: live view at ";
    const std::string line = child.read_line_with(prefix, kHangLimit);
    if (line.empty()) throw std::runtime_error("fba-run said no live view address:\n" + child.read_until(prefix, {}));
    const LiveUrl url = parse_live_url(line.substr(line.find(prefix) + prefix.size()));
    LiveSocket page(url);
    beast::error_code ec;
    page.handshake(url.origin(), url.token, ec);
    if (ec) throw std::runtime_error("the live view refused the page: " + ec.message());
    while (!ec) {
      page.read(ec);
      if (!ec) ++r.messages;
    }
  }
  // Waited for without polling, as the served run's page waits on its socket: a poller (Child's
  // bounded wait looks every 2 ms) alone sped the threaded executor up by a quarter on a 2-core
  // VM, a difference between the two runs that is not serving's.
  const int status = serve ? child.wait(0, kHangLimit) : child.wait().status;
  r.cpu_s = children_cpu_s() - cpu_before;
  if (status != 0) throw std::runtime_error("fba-run ended with " + std::to_string(status) + ":\n" + child.read_until("\x01", {}));
  std::ifstream in(out / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  const double run_s = summary.at("wall_time_s").get<double>() - summary.at("construct_time_s").get<double>();
  r.samples_per_s = static_cast<double>(samples) / run_s;
  return r;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : (v[v.size() / 2 - 1] + v[v.size() / 2]) / 2;
}

}  // namespace

int main(int argc, char** argv) {
  int rounds = 9;
  long samples = 2'000'000;
  std::string executor = "threaded";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--rounds" && i + 1 < argc) rounds = std::atoi(argv[++i]);
    else if (a == "--samples" && i + 1 < argc) samples = std::atol(argv[++i]);
    else if (a == "--executor" && i + 1 < argc) executor = argv[++i];
    else {
      std::fprintf(stderr, "usage: fba-serve-benchmark [--rounds N] [--samples N] [--executor threaded|deterministic]\n");
      return 2;
    }
  }
  if (rounds < 1 || samples < 1000 || (executor != "threaded" && executor != "deterministic")) {
    std::fprintf(stderr, "fba-serve-benchmark: expected --rounds >= 1, --samples >= 1000, --executor threaded or deterministic\n");
    return 2;
  }
  // The page's build may be absent or present: without a report template to write, the plain run
  // samples nothing, and the served one pays for all of the live view.
  ::setenv("FBA_WEB_DIR", "/nonexistent", 1);
  const fs::path dir = fs::temp_directory_path() / ("fba-serve-benchmark-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path task = dir / "chain.yaml";
  std::ofstream(task) << chain_task(samples);
  std::vector<double> plain, served, ratios, cpu_ratios, plain_cpu, served_cpu;
  std::size_t messages = 0;
  try {
    for (int round = 0; round < rounds; ++round) {
      const bool served_first = round % 2;  // each order half the time: neither pays for a warm-up
      Run a = run_once(task, dir / "a", samples, executor, served_first);
      Run b = run_once(task, dir / "b", samples, executor, !served_first);
      if (served_first) std::swap(a, b);
      plain.push_back(a.samples_per_s);
      served.push_back(b.samples_per_s);
      ratios.push_back(b.samples_per_s / a.samples_per_s);
      cpu_ratios.push_back(b.cpu_s / a.cpu_s);
      plain_cpu.push_back(a.cpu_s);
      served_cpu.push_back(b.cpu_s);
      messages += b.messages;
      std::fprintf(stderr, "round %d: plain %.0f samples/s %.2f s CPU, served %.0f samples/s %.2f s CPU, %zu messages to the page\n",
                   round + 1, a.samples_per_s, a.cpu_s, b.samples_per_s, b.cpu_s, b.messages);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fba-serve-benchmark: %s\n", e.what());
    fs::remove_all(dir);
    return 1;
  }
  fs::remove_all(dir);
  std::printf("fba-serve-benchmark: chain of 10 passthroughs, %ld samples, %s executor, %d rounds\n", samples, executor.c_str(), rounds);
  std::printf("plain   %.0f samples/s, %.3f s CPU a run (medians)\n", median(plain), median(plain_cpu));
  std::printf("served  %.0f samples/s, %.3f s CPU a run (medians), one page connected, %.0f messages a run\n", median(served),
              median(served_cpu), static_cast<double>(messages) / rounds);
  std::printf("cost    %.2f %% of the throughput, %.2f %% more CPU time (medians of the rounds' ratios)\n", 100.0 * (1.0 - median(ratios)),
              100.0 * (median(cpu_ratios) - 1.0));
  return 0;
}
