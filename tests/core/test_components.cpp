// Components that exist only for the runtime's tests: each exercises one rule.
#include "test_components.hpp"

#include <condition_variable>
#include <mutex>

#include <fba/component.hpp>

namespace {

// Two inputs; with trigger 'all' it pairs samples of equal stamp and emits their sum.
class Pair final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("test.pair", "Sums one sample from each input.")
        .input<std::int64_t>("a", "left")
        .input<std::int64_t>("b", "right")
        .output<std::int64_t>("sum", "a + b, or whichever came")
        .trigger({fba::TriggerPolicy::All, 0});
  }
  explicit Pair(fba::Context& ctx) : a_(ctx.input("a")), b_(ctx.input("b")), out_(ctx.output("sum")) {}
  void process() override {
    std::int64_t s = 0;
    if (a_.has()) s += a_.get<std::int64_t>();
    if (b_.has()) s += b_.get<std::int64_t>();
    out_.emit<std::int64_t>(s);
  }

 private:
  fba::Input& a_;
  fba::Input& b_;
  fba::Output& out_;
};

// A sensor that never produces unless asked: for stall detection.
class Silent final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::sensor("test.silent", "Emits one sample per request; never finishes by itself.")
        .optional_input<std::int64_t>("request", "a request")
        .output<std::int64_t>("out", "one sample per request")
        .trigger({fba::TriggerPolicy::Any, 0});
  }
  explicit Silent(fba::Context& ctx) : in_(ctx.input("request")), out_(ctx.output("out")) {}
  void process() override { out_.emit<std::int64_t>(in_.get<std::int64_t>()); }

 private:
  fba::Input& in_;
  fba::Output& out_;
};

// Forwards whichever input has a sample: the join point of a feedback loop.
class Merge final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("test.merge", "Forwards samples from either input.")
        .input<std::int64_t>("a", "first")
        .optional_input<std::int64_t>("b", "second (the feedback edge in loop tests)")
        .output<std::int64_t>("out", "every sample from a and b");
  }
  explicit Merge(fba::Context& ctx) : a_(ctx.input("a")), b_(ctx.input("b")), out_(ctx.output("out")) {}
  void process() override {
    if (a_.has()) out_.emit<std::int64_t>(a_.get<std::int64_t>());
    if (b_.has()) out_.emit<std::int64_t>(b_.get<std::int64_t>());
  }

 private:
  fba::Input& a_;
  fba::Input& b_;
  fba::Output& out_;
};

// Emits value-1 while positive: with Merge, a loop that ends by itself.
class Countdown final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("test.countdown", "Emits value - 1 while the value is positive.")
        .input<std::int64_t>("in", "a value")
        .output<std::int64_t>("out", "the value minus one");
  }
  explicit Countdown(fba::Context& ctx) : in_(ctx.input("in")), out_(ctx.output("out")) {}
  void process() override {
    const auto v = in_.get<std::int64_t>();
    if (v > 0) out_.emit<std::int64_t>(v - 1);
  }

 private:
  fba::Input& in_;
  fba::Output& out_;
};

// Receives events delivered by task rules and emits their names.
class EventLog final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("test.event_log", "Turns delivered events into strings.")
        .input<fba::Event>("events", "events delivered by rules")
        .output<std::string>("names", "source.name of each event");
  }
  explicit EventLog(fba::Context& ctx) : in_(ctx.input("events")), out_(ctx.output("names")) {}
  void process() override {
    const auto& e = in_.get<fba::Event>();
    out_.emit<std::string>(e.source + "." + e.name);
  }

 private:
  fba::Input& in_;
  fba::Output& out_;
};

// Stages: idle -> working -> done, driven by the value it receives.
class Staged final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("test.staged", "Moves through its stages as samples arrive.")
        .input<std::int64_t>("in", "1: start work, 2: finish, 3: an illegal jump back to idle")
        .output<std::int64_t>("out", "the sample")
        .stages({"idle", "working", "done"}, {{"idle", "working"}, {"working", "done"}});
  }
  explicit Staged(fba::Context& ctx) : in_(ctx.input("in")), out_(ctx.output("out")), stages_(ctx) {}
  void process() override {
    const auto v = in_.get<std::int64_t>();
    stages_.go(v == 1 ? "working" : v == 2 ? "done" : "idle");
    out_.emit<std::int64_t>(v);
  }

 private:
  fba::Input& in_;
  fba::Output& out_;
  fba::Stages stages_;
};

// Path and choice parameters, for the loader's tests.
class Reader final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::sensor("test.reader", "Emits the size of a file.")
        .output<std::int64_t>("size", "bytes")
        .path_param("file", std::nullopt, "the file to read")
        .param("mode", "bytes", "what to count").choices({"bytes", "lines"});
  }
  explicit Reader(fba::Context& ctx) : ctx_(ctx), out_(ctx.output("size")) {}
  void process() override {
    out_.emit<std::int64_t>(static_cast<std::int64_t>(std::filesystem::file_size(ctx_.path("file"))));
    ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  fba::Output& out_;
};

// Emits one event with a payload of the given size, then finishes: payload limits.
class Shout final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::sensor("test.shout", "Emits one event 'said' with a payload of `bytes` bytes, then finishes.")
        .output<std::int64_t>("out", "nothing")
        .param("bytes", 0, "the payload's size").range(0, std::nullopt)
        .event("said", "the payload: `bytes` times 'y'");
  }
  explicit Shout(fba::Context& ctx) : ctx_(ctx), bytes_(ctx.param<std::int64_t>("bytes")) {}
  void process() override {
    ctx_.emit_event("said", std::string(static_cast<std::size_t>(bytes_), 'y'));
    ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  const std::int64_t bytes_;
};

// An actuator whose process() blocks until interrupt(): shutdown must not hang on it.
class Blocker final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::actuator("test.blocker", "Blocks in process() until interrupted, like a device read.")
        .any_input("in", "anything")
        .blocking();
  }
  explicit Blocker(fba::Context&) {}
  void process() override {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [this] { return interrupted_; });
  }
  void interrupt() override {
    std::lock_guard lock(mutex_);
    interrupted_ = true;
    cv_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool interrupted_ = false;
};

}  // namespace

FBA_COMPONENT(Pair);
FBA_COMPONENT(Silent);
FBA_COMPONENT(Merge);
FBA_COMPONENT(Countdown);
FBA_COMPONENT(EventLog);
FBA_COMPONENT(Staged);
FBA_COMPONENT(Reader);
FBA_COMPONENT(Blocker);
FBA_COMPONENT(Shout);

namespace fba::test {

const Registry& registry() {
  static const Registry* r = [] {
    auto* reg = new Registry;
    reg->add_builtin(detail::plugin_entries(), "the test program");
    const auto errors = reg->load_path({FBA_TEST_PLUGIN_DIR});
    for (const auto& e : errors) throw e;
    return reg;
  }();
  return *r;
}

TaskConfig load(const std::string& yaml, const LoadOptions& options) {
  return load_task_text(yaml, "test.yaml", FBA_TEST_SOURCE_DIR, registry(), options);
}

std::vector<std::int64_t> ints(const std::vector<Packet>& packets) {
  std::vector<std::int64_t> out;
  for (const auto& p : packets) out.push_back(p.get<std::int64_t>());
  return out;
}

}  // namespace fba::test
