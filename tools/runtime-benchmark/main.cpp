// fba-runtime-benchmark: what a hop costs. Chains of K passthroughs between a counter and a
// sink, run three ways: the deterministic executor (one thread), the threaded executor's pool
// (components share the workers), and one thread per component (`thread: dedicated`, the shape of
// GStreamer's `queue ! element` chains). For each, wall time and process CPU time per sample;
// latency with samples arriving one at a time at 1 kHz; the time to build a 1000-component task;
// a lossless soak that must lose nothing and whose resident memory must not grow beyond a bound
// (exit status 1 otherwise).
//
// Regressions show as ratios to plain implementations measured in the same run, which a loaded or
// slower machine slows alike: a hop of the deterministic executor against a mutex-guarded
// std::deque hop, and building a 1000-component task against yaml-cpp's parse of its file.
// --reference FILE compares them with the committed figures (tools/runtime-benchmark/reference.json)
// and names each that grew by more than a third.
//
//   fba-runtime-benchmark [--quick] [--json] [--reference FILE]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sys/resource.h>
#include <string>
#include <vector>

#include <deque>
#include <memory>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <fba/component.hpp>
#include <fba/log.hpp>
#include <fba/registry.hpp>
#include <fba/task.hpp>
#include <fba/view.hpp>
#include "support/build_paths.hpp"

namespace {

using Clock = std::chrono::steady_clock;

// Arrival time minus the counter's stamp, for every sample. A benchmark-only component.
std::mutex g_latency_mutex;
std::vector<std::int64_t> g_latencies_ns;

class LatencySink final : public fba::Component {
 public:
  static constexpr fba::AnyIn kIn{"in", "samples"};
  static fba::Spec spec() { return fba::Spec::actuator("bench.latency_sink", "Records how long each sample took to arrive.").add(kIn); }
  explicit LatencySink(fba::Context& ctx) : ctx_(ctx), in_(ctx(kIn)) {}
  void process() override {
    const auto latency = ctx_.now_ns() - in_.packet().header().stamp_ns;
    std::lock_guard lock(g_latency_mutex);
    g_latencies_ns.push_back(latency);
  }

 private:
  fba::Context& ctx_;
  fba::Input& in_;
};
FBA_COMPONENT(LatencySink);

fba::Registry& registry() {
  static fba::Registry r = [] {
    fba::Registry reg;
    reg.add_builtin(fba::detail::plugin_entries(), "fba-runtime-benchmark");
    reg.load_plugin(fba::test::plugin_dir() + "/fba-examples.so");
    return reg;
  }();
  return r;
}

// How the components of a chain are run.
enum class Mode { Deterministic, Pooled, Dedicated };

const char* name(Mode m) {
  switch (m) {
    case Mode::Deterministic: return "deterministic";
    case Mode::Pooled: return "pooled";
    case Mode::Dedicated: return "dedicated";
  }
  return "?";
}

std::string chain_yaml(int hops, long count, double rate, const std::string& sink, int capacity, Mode mode) {
  const std::string thread = mode == Mode::Dedicated ? ", thread: dedicated" : "";
  std::string y = std::string("executor: ") + (mode == Mode::Deterministic ? "deterministic" : "threaded") + "\n";
  y += "components:\n  src: { type: examples.counter, params: { count: " + std::to_string(count) +
       ", rate: " + std::to_string(rate) + " }" + thread + " }\n";
  for (int i = 0; i < hops; ++i) y += "  p" + std::to_string(i) + ": { type: examples.passthrough" + thread + " }\n";
  y += "  sink: { type: " + sink + thread + " }\nconnections:\n";
  std::string prev = "src";
  for (int i = 0; i <= hops; ++i) {
    const std::string next = i < hops ? "p" + std::to_string(i) : "sink";
    y += "  - { from: " + prev + ".out, to: " + next + ".in, capacity: " + std::to_string(capacity) + " }\n";
    prev = next;
  }
  return y;
}

// User plus system CPU time of the whole process (every thread), seconds.
double cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  auto s = [](const timeval& t) { return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6; };
  return s(u.ru_utime) + s(u.ru_stime);
}

// CPU time of the calling thread, seconds.
double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

struct Measured {
  fba::RunResult result;
  double cpu_s = 0;  // CPU time the run took, all threads
};

// `threads`: the threaded executor's workers (0: the task's setting). `watched`: outputs a live
// view watches (Task::watch), never read, so that each sample supersedes the last.
Measured run(const std::string& yaml, int threads = 0, const std::vector<std::string>& watched = {}) {
  fba::RunOptions o;
  o.timeout_s = 600;
  o.threads = threads;
  fba::Task task(fba::load_task_text(yaml, "bench.yaml", ".", registry()), o);
  std::vector<std::shared_ptr<fba::LatestSample>> watches;
  for (const auto& port : watched) watches.push_back(task.watch(port));
  const double cpu0 = cpu_s();
  auto r = task.run();
  const double cpu = cpu_s() - cpu0;
  if (r.outcome != fba::Outcome::Success) {
    std::fprintf(stderr, "benchmark run failed: %s\n", r.reason.c_str());
    std::exit(1);
  }
  return {std::move(r), cpu};
}

struct PerSample {
  double wall_ns = 1e300, cpu_ns = 0;
};

// Wall and CPU nanoseconds per sample through the whole chain, from the run with the best wall time
// of `reps`; `watched`: with every passthrough's output watched.
PerSample per_sample(int hops, long count, Mode mode, int reps, bool watched = false) {
  const std::string yaml = chain_yaml(hops, count, 0, "examples.sink", 64, mode);
  std::vector<std::string> ports;
  for (int i = 0; watched && i < hops; ++i) ports.push_back("p" + std::to_string(i) + ".out");
  PerSample best;
  for (int i = 0; i < reps; ++i) {
    const Measured m = run(yaml, 0, ports);
    const double wall = m.result.run_s() * 1e9 / static_cast<double>(count);
    if (wall < best.wall_ns) best = {wall, m.cpu_s * 1e9 / static_cast<double>(count)};
  }
  return best;
}

// The plainest good hop in one thread: a sample through K mutex-guarded queues, each popped and
// pushed to the next, a shared pointer moved along. CPU nanoseconds per sample, one run.
double plain_queue_chain_cpu_ns(int hops, long count) {
  struct Queue {
    std::mutex mutex;
    std::deque<std::shared_ptr<const std::int64_t>> items;
  };
  std::vector<Queue> queues(static_cast<std::size_t>(hops) + 1);
  std::int64_t sum = 0;
  const double cpu0 = cpu_s();
  for (long i = 0; i < count; ++i) {
    {
      std::lock_guard lock(queues[0].mutex);
      queues[0].items.push_back(std::make_shared<const std::int64_t>(i));
    }
    for (std::size_t k = 0; k < queues.size(); ++k) {
      std::shared_ptr<const std::int64_t> sample;
      {
        std::lock_guard lock(queues[k].mutex);
        sample = std::move(queues[k].items.front());
        queues[k].items.pop_front();
      }
      if (k + 1 == queues.size()) {
        sum += *sample;
        continue;
      }
      std::lock_guard lock(queues[k + 1].mutex);
      queues[k + 1].items.push_back(std::move(sample));
    }
  }
  const double cpu = (cpu_s() - cpu0) * 1e9 / static_cast<double>(count);
  if (sum != count * (count - 1) / 2) std::exit(1);  // every sample went through
  return cpu;
}

long rss_kib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

struct Options {
  bool quick = false, json = false;
  std::string reference;  // a file of expected ratios; empty: none
};

// The command line into `o`; the exit status when it is wrong.
std::optional<int> parse_options(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) o.quick = true;
    else if (!std::strcmp(argv[i], "--json")) o.json = true;
    else if (!std::strcmp(argv[i], "--reference") && i + 1 < argc) o.reference = argv[++i];
    else {
      std::fprintf(stderr, "usage: fba-runtime-benchmark [--quick] [--json] [--reference FILE]\n");
      return 2;
    }
  }
  return std::nullopt;
}

// The figures as they are measured: printed at once as text, or kept for one JSON object at the end.
struct Report {
  bool json = false;
  std::vector<std::string> lines;
  std::map<std::string, double> ratios;  // what the reference file holds, measured now

  void out(const std::string& key, double value, const char* unit) {
    char buf[256];
    std::snprintf(buf, sizeof buf, json ? "  \"%s\": %.2f" : "%-52s %12.1f %s", key.c_str(), value, unit);
    lines.push_back(buf);
    if (!json) std::printf("%s\n", buf);
    std::fflush(stdout);
  }
};

const std::vector<int> kHops{1, 10, 50};

// The ratio the reference holds: the deterministic executor's CPU per extra hop against the plain
// queue's, each the least of `rounds` runs taken in turn. A virtual machine's speed swings by half
// between runs a second apart; runs taken in turn see the same swings, and the least of each is
// the run the swing touched least.
void measure_hop_ratio(Report& report, long count, int rounds) {
  const std::string one = chain_yaml(1, count, 0, "examples.sink", 64, Mode::Deterministic);
  const std::string fifty = chain_yaml(50, count, 0, "examples.sink", 64, Mode::Deterministic);
  double det1 = 1e300, det50 = 1e300, plain1 = 1e300, plain50 = 1e300;
  for (int r = 0; r < rounds; ++r) {
    det1 = std::min(det1, run(one).cpu_s * 1e9 / static_cast<double>(count));
    det50 = std::min(det50, run(fifty).cpu_s * 1e9 / static_cast<double>(count));
    plain1 = std::min(plain1, plain_queue_chain_cpu_ns(1, count));
    plain50 = std::min(plain50, plain_queue_chain_cpu_ns(50, count));
  }
  const std::string least = ", least of " + std::to_string(rounds) + " in turn";
  report.out("deterministic CPU per extra hop (K=1..50)" + least, (det50 - det1) / 49.0, "ns");
  report.out("plain mutex-guarded deque: CPU per extra hop" + least, (plain50 - plain1) / 49.0, "ns");
  report.ratios["deterministic CPU per extra hop / plain queue hop"] = (det50 - det1) / (plain50 - plain1);
}

// Throughput of chains of each length, run each way; for the deterministic executor also the cost of
// watching every hop. (Its hop against the plain queue: measure_hop_ratio.)
void measure_throughput(Report& report, long n, int reps) {
  // One thread per component makes a context switch of every hop on a small machine: fewer samples.
  for (Mode mode : {Mode::Deterministic, Mode::Pooled, Mode::Dedicated}) {
    const std::string m = name(mode);
    const long count = mode == Mode::Dedicated ? n / 10 : n;
    std::vector<PerSample> t;
    for (int k : kHops) {
      t.push_back(per_sample(k, count, mode, reps));
      report.out(m + " K=" + std::to_string(k) + " per sample", t.back().wall_ns, "ns");
      report.out(m + " K=" + std::to_string(k) + " CPU per sample", t.back().cpu_ns, "ns");
    }
    report.out(m + " per extra hop (K=1..50)", (t[2].wall_ns - t[0].wall_ns) / 49.0, "ns");
    report.out(m + " per extra hop (K=10..50)", (t[2].wall_ns - t[1].wall_ns) / 40.0, "ns");
    report.out(m + " CPU per extra hop (K=1..50)", (t[2].cpu_ns - t[0].cpu_ns) / 49.0, "ns");
    if (mode == Mode::Deterministic) {
      // A live view's cost on the producer: every hop's output also handed to a watch (fba-run --serve).
      const PerSample w1 = per_sample(1, count, mode, reps, true), w50 = per_sample(50, count, mode, reps, true);
      report.out(m + " watched: CPU per extra hop (K=1..50)", (w50.cpu_ns - w1.cpu_ns) / 49.0, "ns");
    }
  }
}

// Latency: one sample at a time, every millisecond, through K hops of both threaded kinds.
void measure_latency(Report& report, bool quick) {
  for (Mode mode : {Mode::Pooled, Mode::Dedicated}) {
    for (int k : kHops) {
      const long samples = quick ? 200 : 2000;
      {
        std::lock_guard lock(g_latency_mutex);
        g_latencies_ns.clear();
      }
      run(chain_yaml(k, samples, 1000.0, "bench.latency_sink", 16, mode));
      std::vector<std::int64_t> l;
      {
        std::lock_guard lock(g_latency_mutex);
        l = g_latencies_ns;
      }
      std::sort(l.begin(), l.end());
      const double median = static_cast<double>(l[l.size() / 2]) / 1000.0;
      const double p99 = static_cast<double>(l[l.size() * 99 / 100]) / 1000.0;
      const std::string m = std::string(name(mode)) + " latency K=" + std::to_string(k);
      report.out(m + " median end to end (1 kHz)", median, "us");
      report.out(m + " median per hop (1 kHz)", median / (k + 1), "us");
      report.out(m + " p99 end to end (1 kHz)", p99, "us");
    }
  }
}

// More workers than cores: idle workers must sleep, not take the cores from the busy ones.
void measure_many_workers(Report& report, long n) {
  for (int workers : {2, 256}) {
    const Measured m = run(chain_yaml(10, n, 0, "examples.sink", 64, Mode::Pooled), workers);
    const std::string key = "pooled K=10, " + std::to_string(workers) + " workers: ";
    report.out(key + "wall per sample", m.result.run_s() * 1e9 / static_cast<double>(n), "ns");
    report.out(key + "CPU per sample", m.cpu_s * 1e9 / static_cast<double>(n), "ns");
  }
}

// Building a task of 1000 components (parse, check, construct) against yaml-cpp's parse of its
// file alone, in the thread's CPU time (both happen on this thread). Builds and parses are taken
// in turn, the least of at least nine each: a build beside the benchmark (CI's sanitizer build)
// slows whichever runs while it compiles, and both see the same spells. False when yaml-cpp's
// parse misread the file.
bool measure_build(Report& report, int reps) {
  const std::string yaml = chain_yaml(998, 10, 0, "examples.sink", 16, Mode::Pooled);
  const int rounds = std::max(reps, 9);
  double best = 1e300, parse = 1e300;
  for (int i = 0; i < rounds; ++i) {
    {
      const double start = thread_cpu_s();
      fba::Task task(fba::load_task_text(yaml, "bench.yaml", ".", registry()));
      best = std::min(best, thread_cpu_s() - start);  // the build, not the task's destruction
    }
    const double start = thread_cpu_s();
    const YAML::Node doc = YAML::Load(yaml);
    parse = std::min(parse, thread_cpu_s() - start);
    if (!doc["components"]) return false;
  }
  report.out("build a task of 1000 components (CPU)", best * 1e3, "ms");
  report.out("yaml-cpp's parse of its file alone (CPU)", parse * 1e3, "ms");
  report.ratios["build 1000 components / yaml-cpp parse"] = best / parse;
  return true;
}

// Soak: a lossless threaded chain; the sink fails the run on any gap; memory must not grow. After
// a warm-up run (allocator arenas, queues), a leak of even 4 bytes per sample shows over 1M samples.
// False (after saying why) when a sample was lost or memory grew too much.
bool measure_soak(Report& report, bool quick) {
  const long soak = quick ? 200'000 : 1'000'000;
  const long growth_limit_kib = 4096;
  run(chain_yaml(10, soak / 10, 0, "examples.sink", 64, Mode::Pooled));  // warm up allocators
  const long before = rss_kib();
  const auto r = run(chain_yaml(10, soak, 0, "examples.sink", 64, Mode::Pooled)).result;
  const long after = rss_kib();
  std::uint64_t dropped = 0, unaccounted = 0;
  for (const auto& c : r.connections) {
    dropped += c.dropped + c.left;  // a sample left in a queue at the stop is lost too
    unaccounted += c.pushed - c.delivered - c.dropped - c.left;
  }
  report.out("soak: samples through 10 threaded lossless hops", static_cast<double>(r.components.back().samples_in), "");
  report.out("soak: samples dropped or left in queues", static_cast<double>(dropped), "");
  report.out("soak: resident memory growth", static_cast<double>(after - before), "KiB");
  report.out("soak: resident memory growth allowed", static_cast<double>(growth_limit_kib), "KiB");
  if (r.components.back().samples_in != static_cast<std::uint64_t>(soak) || dropped != 0 || unaccounted != 0) {
    std::fprintf(stderr, "soak lost samples: %llu of %ld arrived, %llu dropped or left, %llu unaccounted\n",
                 static_cast<unsigned long long>(r.components.back().samples_in), soak,
                 static_cast<unsigned long long>(dropped), static_cast<unsigned long long>(unaccounted));
    return false;
  }
  if (before < 0 || after < 0) {
    std::fprintf(stderr, "soak: cannot read VmRSS from /proc/self/status\n");
    return false;
  }
  if (after - before > growth_limit_kib) {
    std::fprintf(stderr, "soak: resident memory grew by %ld KiB over %ld samples; the bound is %ld KiB\n",
                 after - before, soak, growth_limit_kib);
    return false;
  }
  return true;
}

// The ratios, then each against its reference. A ratio a third above its reference is named: the
// hop or the loader got slower than the plain code beside it, whatever the machine's speed or
// load. Printed, not failed: a loaded machine's noise must not fail CI, and a person reads it the
// day it lands.
void compare_ratios(Report& report, const nlohmann::json& expected, const std::string& reference) {
  for (const auto& [key, value] : report.ratios) report.out("ratio: " + key, value, "");
  bool slower = false;
  for (const auto& [key, value] : report.ratios) {
    if (!expected.contains(key) || !expected[key].is_number()) continue;
    const double ref = expected[key].get<double>();
    const bool worse = value > ref * 4.0 / 3.0;
    slower |= worse;
    std::printf("%s %s: %.2f now, %.2f in %s\n", worse ? "REGRESSION" : "as before:", key.c_str(), value, ref, reference.c_str());
  }
  if (!reference.empty() && !slower) std::printf("no regression against %s\n", reference.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (const auto status = parse_options(argc, argv, options)) return *status;
  nlohmann::json expected;
  if (!options.reference.empty()) {
    std::ifstream in(options.reference);
    expected = nlohmann::json::parse(in, nullptr, false);
    if (!in || !expected.is_object()) {
      std::fprintf(stderr, "fba-runtime-benchmark: --reference %s: expected a JSON object of ratios, found %s\n",
                   options.reference.c_str(), in ? "something else" : "no readable file");
      return 2;
    }
  }
  fba::set_log_level("warn");
  const long n = options.quick ? 20'000 : 1'000'000;
  const int reps = options.quick ? 1 : 3;
  Report report;
  report.json = options.json;
  measure_throughput(report, n, reps);
  measure_hop_ratio(report, options.quick ? 20'000 : 200'000, 15);
  measure_latency(report, options.quick);
  measure_many_workers(report, n);
  if (!measure_build(report, reps)) return 1;
  if (!measure_soak(report, options.quick)) return 1;
  compare_ratios(report, expected, options.reference);
  if (options.json) {
    std::printf("{\n");
    for (std::size_t i = 0; i < report.lines.size(); ++i)
      std::printf("%s%s\n", report.lines[i].c_str(), i + 1 < report.lines.size() ? "," : "");
    std::printf("}\n");
  }
  return 0;
}
