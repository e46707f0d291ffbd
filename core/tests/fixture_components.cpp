// Components that exist only for the runtime's tests: each exercises one rule.
#include "fixture_components.hpp"


#include <fba/component.hpp>
#include "support/build_paths.hpp"

namespace {

// Two inputs; with trigger 'all' it pairs samples of equal stamp and emits their sum.
class Pair final : public fba::Component {
 public:
  static constexpr fba::In<std::int64_t> kA{"a", "left"};
  static constexpr fba::In<std::int64_t> kB{"b", "right"};
  static constexpr fba::Out<std::int64_t> kSum{"sum", "a + b, or whichever came"};
  static fba::Spec spec() {
    return fba::Spec::filter("test.pair", "Sums one sample from each input.").add(kA, kB, kSum).trigger({fba::TriggerPolicy::All, 0});
  }
  explicit Pair(fba::Context& ctx) : ctx_(ctx) {}
  void process() override {
    std::int64_t s = 0;
    if (ctx_(kA).has()) s += ctx_(kA).get();
    if (ctx_(kB).has()) s += ctx_(kB).get();
    ctx_(kSum).emit(s);
  }

 private:
  fba::Context& ctx_;
};

// A sensor that never produces unless asked: for stall detection.
class Silent final : public fba::Component {
 public:
  static constexpr fba::OptionalIn<std::int64_t> kRequest{"request", "a request"};
  static constexpr fba::Out<std::int64_t> kOut{"out", "one sample per request"};
  static fba::Spec spec() {
    return fba::Spec::sensor("test.silent", "Emits one sample per request; never finishes by itself.")
        .add(kRequest, kOut)
        .trigger({fba::TriggerPolicy::Any, 0});
  }
  explicit Silent(fba::Context& ctx) : ctx_(ctx) {}
  void process() override {
    if (ctx_(kRequest).has()) ctx_(kOut).emit(ctx_(kRequest).get());  // a periodic tick alone emits nothing
  }

 private:
  fba::Context& ctx_;
};

// Forwards whichever input has a sample: the join point of a feedback loop.
class Merge final : public fba::Component {
 public:
  static constexpr fba::In<std::int64_t> kA{"a", "first"};
  static constexpr fba::OptionalIn<std::int64_t> kB{"b", "second (the feedback edge in loop tests)"};
  static constexpr fba::Out<std::int64_t> kOut{"out", "every sample from a and b"};
  static fba::Spec spec() { return fba::Spec::filter("test.merge", "Forwards samples from either input.").add(kA, kB, kOut); }
  explicit Merge(fba::Context& ctx) : ctx_(ctx) {}
  void process() override {
    if (ctx_(kA).has()) ctx_(kOut).emit(ctx_(kA).get());
    if (ctx_(kB).has()) ctx_(kOut).emit(ctx_(kB).get());
  }

 private:
  fba::Context& ctx_;
};

// Emits value-1 while positive: with Merge, a loop that ends by itself.
class Countdown final : public fba::Component {
 public:
  static constexpr fba::In<std::int64_t> kIn{"in", "a value"};
  static constexpr fba::Out<std::int64_t> kOut{"out", "the value minus one"};
  static fba::Spec spec() { return fba::Spec::filter("test.countdown", "Emits value - 1 while the value is positive.").add(kIn, kOut); }
  explicit Countdown(fba::Context& ctx) : ctx_(ctx) {}
  void process() override {
    const auto v = ctx_(kIn).get();
    if (v > 0) ctx_(kOut).emit(v - 1);
  }

 private:
  fba::Context& ctx_;
};

// Receives events delivered by task rules and emits their names.
class EventLog final : public fba::Component {
 public:
  static constexpr fba::In<fba::Event> kEvents{"events", "events delivered by rules"};
  static constexpr fba::Out<std::string> kNames{"names", "source.name of each event"};
  static fba::Spec spec() { return fba::Spec::filter("test.event_log", "Turns delivered events into strings.").add(kEvents, kNames); }
  explicit EventLog(fba::Context& ctx) : ctx_(ctx) {}
  void process() override {
    const auto& e = ctx_(kEvents).get();
    ctx_(kNames).emit(e.source + "." + e.name);
  }

 private:
  fba::Context& ctx_;
};

// Stages: idle -> working -> done, driven by the value it receives; reports the last value as the
// result "last" (4: a result that is not JSON, a plugin bug).
class Staged final : public fba::Component {
 public:
  static constexpr fba::In<std::int64_t> kIn{"in", "1: start work, 2: finish, 3: an illegal jump back to idle, 4: a bad result"};
  static constexpr fba::Out<std::int64_t> kOut{"out", "the sample"};
  static fba::Spec spec() {
    return fba::Spec::filter("test.staged", "Moves through its stages as samples arrive.")
        .add(kIn, kOut)
        .stages({"idle", "working", "done"}, {{"idle", "working"}, {"working", "done"}});
  }
  explicit Staged(fba::Context& ctx) : ctx_(ctx), stages_(ctx) {}
  void process() override {
    const auto v = ctx_(kIn).get();
    if (v == 4) ctx_.report("last", "{four");
    ctx_.report("last", std::to_string(v));
    stages_.go(v == 1 ? "working" : v == 2 ? "done" : "idle");
    ctx_(kOut).emit(v);
  }

 private:
  fba::Context& ctx_;
  fba::Stages stages_;
};

// Path and choice parameters, for the loader's tests.
class Reader final : public fba::Component {
 public:
  static constexpr fba::Out<std::int64_t> kSize{"size", "bytes"};
  static constexpr fba::Param<std::filesystem::path> kFile{"file", fba::required, "the file to read"};
  static constexpr auto kMode = fba::Param<std::string>("mode", "bytes", "what to count").choices({"bytes", "lines"});
  static fba::Spec spec() { return fba::Spec::sensor("test.reader", "Emits the size of a file.").add(kSize, kFile, kMode); }
  explicit Reader(fba::Context& ctx) : ctx_(ctx) {}
  void process() override {
    ctx_(kSize).emit(static_cast<std::int64_t>(std::filesystem::file_size(ctx_(kFile))));
    ctx_.finish();
  }

 private:
  fba::Context& ctx_;
};

// Emits one event with a payload of the given size, then finishes: payload limits.
class Shout final : public fba::Component {
 public:
  static constexpr fba::Out<std::int64_t> kOut{"out", "nothing"};
  static constexpr fba::Param<std::int64_t> kBytes = fba::Param<std::int64_t>{"bytes", 0, "the payload's size"}.at_least(0);
  static constexpr fba::EventOut kSaid{"said", "the payload: `bytes` times 'y'"};
  static fba::Spec spec() {
    return fba::Spec::sensor("test.shout", "Emits one event 'said' with a payload of `bytes` bytes, then finishes.")
        .add(kOut, kBytes, kSaid);
  }
  explicit Shout(fba::Context& ctx) : ctx_(ctx), bytes_(ctx(kBytes)) {}
  void process() override {
    ctx_.emit(kSaid, std::string(static_cast<std::size_t>(bytes_), 'y'));
    ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  const std::int64_t bytes_;
};

// An actuator whose process() blocks until interrupt(): shutdown must not hang on it.
class Blocker final : public fba::Component {
 public:
  static constexpr fba::AnyIn kIn{"in", "anything"};
  static fba::Spec spec() {
    return fba::Spec::actuator("test.blocker", "Blocks in process() until interrupted, like a device read.").add(kIn).blocking();
  }
  explicit Blocker(fba::Context&) {}
  void process() override { interrupted_.wait(); }
  void interrupt() override { interrupted_.raise(); }

 private:
  fba::test::Flag interrupted_;
};

// Plugin bugs: reads a parameter its spec does not declare (the handle was left out of spec()).
class Forgetful final : public fba::Component {
 public:
  static constexpr fba::Out<std::int64_t> kOut{"out", "nothing"};
  static constexpr fba::Param<std::int64_t> kUndeclared{"undeclared", 1, "not in spec()"};
  static fba::Spec spec() { return fba::Spec::sensor("test.forgetful", "Reads a parameter it did not declare.").add(kOut); }
  explicit Forgetful(fba::Context& ctx) { ctx(kUndeclared); }
  void process() override {}
};

// Two handles of one name with different types: declared as double, read as an int.
class Mistyped final : public fba::Component {
 public:
  static constexpr fba::Out<std::int64_t> kOut{"out", "nothing"};
  static constexpr fba::Param<double> kFactor{"factor", 2.0, "a double"};
  static constexpr fba::Param<std::int64_t> kFactorAsInt{"factor", 2, "the same name, as an int"};
  static fba::Spec spec() { return fba::Spec::sensor("test.mistyped", "Reads a double parameter as an int.").add(kOut, kFactor); }
  explicit Mistyped(fba::Context& ctx) { ctx(kFactorAsInt); }
  void process() override {}
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
FBA_COMPONENT(Forgetful);
FBA_COMPONENT(Mistyped);

namespace fba::test {

const Registry& registry() {
  static const Registry* r = [] {
    auto* reg = new Registry;
    reg->add_builtin(detail::plugin_entries(), "the test program");
    const auto errors = reg->load_path({fba::test::plugin_dir()});
    for (const auto& e : errors) throw e;
    return reg;
  }();
  return *r;
}

TaskConfig load(const std::string& yaml, const LoadOptions& options) {
  return load_task_text(yaml, "test.yaml", fba::test::source_dir() + "/core/tests", registry(), options);
}

std::vector<std::int64_t> ints(const std::vector<Packet>& packets) {
  std::vector<std::int64_t> out;
  for (const auto& p : packets) out.push_back(p.get<std::int64_t>());
  return out;
}

std::string errors_of(const std::string& yaml, const LoadOptions& options) {
  try {
    load(yaml, options);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

std::vector<Diagnostic> diagnostics_of_file(const std::filesystem::path& file, const LoadOptions& options) {
  try {
    load_task(file, registry(), options);
  } catch (const ConfigError& e) {
    return e.diagnostics();
  }
  return {};
}

std::string errors_of_file(const std::filesystem::path& file) {
  std::string s;
  for (const auto& d : diagnostics_of_file(file)) s += d.str() + "\n";
  return s;
}

}  // namespace fba::test
