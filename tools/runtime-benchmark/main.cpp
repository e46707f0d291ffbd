// fba-runtime-benchmark: what a hop costs. Chains of K passthroughs between a counter and a
// sink, under both executors; latency per hop with samples arriving one at a time at 1 kHz;
// the time to build a 1000-component task; a lossless soak that must lose nothing and not grow.
//
//   fba-runtime-benchmark [--quick] [--json]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <mutex>
#include <string>
#include <vector>

#include <fba/component.hpp>
#include <fba/log.hpp>
#include <fba/registry.hpp>
#include <fba/task.hpp>

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
    reg.load_plugin(std::string(FBA_BENCH_PLUGIN_DIR) + "/fba-examples.so");
    return reg;
  }();
  return r;
}

std::string chain_yaml(int hops, long count, double rate, const std::string& sink, int capacity) {
  std::string y = "components:\n  src: { type: examples.counter, params: { count: " + std::to_string(count) +
                  ", rate: " + std::to_string(rate) + " } }\n";
  for (int i = 0; i < hops; ++i) y += "  p" + std::to_string(i) + ": { type: examples.passthrough }\n";
  y += "  sink: { type: " + sink + " }\nconnections:\n";
  std::string prev = "src";
  for (int i = 0; i <= hops; ++i) {
    const std::string next = i < hops ? "p" + std::to_string(i) : "sink";
    y += "  - { from: " + prev + ".out, to: " + next + ".in, capacity: " + std::to_string(capacity) + " }\n";
    prev = next;
  }
  return y;
}

fba::RunResult run(const std::string& yaml, fba::ExecutorKind executor, int threads = 0) {
  fba::RunOptions o;
  o.executor = executor;
  o.threads = threads;
  o.timeout_s = 600;
  fba::Task task(fba::load_task_text(yaml, "bench.yaml", ".", registry()), o);
  auto r = task.run();
  if (r.outcome != fba::Outcome::Success) {
    std::fprintf(stderr, "benchmark run failed: %s\n", r.reason.c_str());
    std::exit(1);
  }
  return r;
}

// Nanoseconds per sample through the whole chain, best of `reps`.
double per_sample_ns(int hops, long count, fba::ExecutorKind executor, int reps) {
  const std::string yaml = chain_yaml(hops, count, 0, "examples.sink", 64);
  double best = 1e300;
  for (int i = 0; i < reps; ++i) best = std::min(best, run(yaml, executor).wall_s * 1e9 / static_cast<double>(count));
  return best;
}

long rss_kib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, json = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) quick = true;
    else if (!std::strcmp(argv[i], "--json")) json = true;
    else {
      std::fprintf(stderr, "usage: fba-runtime-benchmark [--quick] [--json]\n");
      return 2;
    }
  }
  fba::set_log_level("warn");
  const long n = quick ? 20'000 : 1'000'000;
  const int reps = quick ? 1 : 3;
  const std::vector<int> ks{1, 10, 50};
  std::vector<std::string> lines;
  auto out = [&](const std::string& key, double value, const char* unit) {
    char buf[256];
    std::snprintf(buf, sizeof buf, json ? "  \"%s\": %.2f" : "%-52s %12.1f %s", key.c_str(), value, unit);
    lines.push_back(buf);
    if (!json) std::printf("%s\n", buf);
    std::fflush(stdout);
  };

  for (auto executor : {fba::ExecutorKind::Deterministic, fba::ExecutorKind::Threaded}) {
    const std::string name = fba::to_string(executor);
    std::vector<double> t;
    for (int k : ks) {
      t.push_back(per_sample_ns(k, n, executor, reps));
      out(name + " K=" + std::to_string(k) + " per sample", t.back(), "ns");
    }
    out(name + " per extra hop (K=1..50)", (t[2] - t[0]) / 49.0, "ns");
    out(name + " per extra hop (K=10..50)", (t[2] - t[1]) / 40.0, "ns");
  }

  // Latency: one sample at a time, every millisecond, through K threaded hops.
  for (int k : ks) {
    const long samples = quick ? 200 : 2000;
    {
      std::lock_guard lock(g_latency_mutex);
      g_latencies_ns.clear();
    }
    run(chain_yaml(k, samples, 1000.0, "bench.latency_sink", 16), fba::ExecutorKind::Threaded);
    std::vector<std::int64_t> l;
    {
      std::lock_guard lock(g_latency_mutex);
      l = g_latencies_ns;
    }
    std::sort(l.begin(), l.end());
    const double median = static_cast<double>(l[l.size() / 2]) / 1000.0;
    const double p99 = static_cast<double>(l[l.size() * 99 / 100]) / 1000.0;
    out("threaded latency K=" + std::to_string(k) + " median per hop (1 kHz)", median / (k + 1), "us");
    out("threaded latency K=" + std::to_string(k) + " p99 end to end (1 kHz)", p99, "us");
  }

  // Building a task of 1000 components: parse, check, construct.
  {
    const std::string yaml = chain_yaml(998, 10, 0, "examples.sink", 16);
    double best = 1e300;
    for (int i = 0; i < reps; ++i) {
      const auto start = Clock::now();
      fba::Task task(fba::load_task_text(yaml, "bench.yaml", ".", registry()));
      best = std::min(best, std::chrono::duration<double>(Clock::now() - start).count());
    }
    out("build a task of 1000 components", best * 1e3, "ms");
  }

  // Soak: a lossless threaded chain; the sink fails the run on any gap; memory must not grow.
  {
    const long soak = quick ? 200'000 : 1'000'000;
    run(chain_yaml(10, soak / 10, 0, "examples.sink", 64), fba::ExecutorKind::Threaded);  // warm up allocators
    const long before = rss_kib();
    const auto r = run(chain_yaml(10, soak, 0, "examples.sink", 64), fba::ExecutorKind::Threaded);
    const long after = rss_kib();
    std::uint64_t dropped = 0;
    for (const auto& c : r.connections) dropped += c.dropped;
    out("soak: samples through 10 threaded lossless hops", static_cast<double>(r.components.back().samples_in), "");
    out("soak: samples dropped", static_cast<double>(dropped), "");
    out("soak: resident memory growth", static_cast<double>(after - before), "KiB");
    if (r.components.back().samples_in != static_cast<std::uint64_t>(soak) || dropped != 0) {
      std::fprintf(stderr, "soak lost samples\n");
      return 1;
    }
  }
  if (json) {
    std::printf("{\n");
    for (std::size_t i = 0; i < lines.size(); ++i) std::printf("%s%s\n", lines[i].c_str(), i + 1 < lines.size() ? "," : "");
    std::printf("}\n");
  }
  return 0;
}
