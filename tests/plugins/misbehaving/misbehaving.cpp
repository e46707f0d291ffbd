// Components that misbehave on purpose, one way per `mode`, so that fba-run's tests can check
// that every way out of a run ends in order: the documented exit status, summary.json naming the
// cause, and the actuators' safe states attempted.
//
// Modes (after `after` good invocations): throw_exception, throw_int, throw_in_constructor_int,
// segfault, block_process (ignores interrupt), block_safe_state (actuator), exit_zero,
// never_finish (sensor: free-running, produces nothing). "none" behaves.
// FBA_TEST_EXIT_IN_STATIC_INIT=1 in the environment makes the plugin call exit(0) while loading.
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <thread>

#include <fba/component.hpp>

namespace {

[[maybe_unused]] const bool exit_while_loading = [] {
  if (const char* v = std::getenv("FBA_TEST_EXIT_IN_STATIC_INIT"); v && std::string(v) == "1") std::exit(0);
  return true;
}();

fba::Spec with_mode(fba::Spec spec) {
  return std::move(spec)
      .param("mode", std::string("none"),
             "how to misbehave: none, throw_exception, throw_int, throw_in_constructor_int, "
             "segfault, block_process, block_safe_state, exit_zero, never_finish")
      .param("after", 0, "good invocations before misbehaving")
      .range(0, std::nullopt);
}

// Blocks the calling thread for good: neither interrupt() nor anything else ends it.
[[noreturn]] void block_forever() {
  for (;;) pause();
}

class Misbehaviour {
 public:
  explicit Misbehaviour(fba::Context& ctx)
      : mode_(ctx.param<std::string>("mode")), after_(ctx.param<std::int64_t>("after")) {
    static const char* const kModes[] = {
        "none",        "throw_exception", "throw_int",        "throw_in_constructor_int",
        "segfault",    "block_process",   "block_safe_state", "exit_zero",
        "never_finish"};
    bool known = false;
    for (const char* m : kModes) known |= mode_ == m;
    if (!known) throw std::invalid_argument("unknown mode '" + mode_ + "'");
    if (mode_ == "throw_in_constructor_int") throw 7;
  }
  const std::string& mode() const { return mode_; }
  // Called at the start of each process(): misbehaves once `after` invocations went well.
  void maybe() {
    if (count_++ < after_) return;
    if (mode_ == "throw_exception") throw std::runtime_error("misbehaving on purpose");
    if (mode_ == "throw_int") throw 42;
    if (mode_ == "segfault") {
      // A real fault that the sanitizers do not take first (a null store is UB that UBSan stops at).
      void* page = mmap(nullptr, 4096, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      *static_cast<volatile int*>(page) = 1;
    }
    if (mode_ == "block_process") block_forever();
    if (mode_ == "exit_zero") std::exit(0);
  }

 private:
  std::string mode_;
  std::int64_t after_;
  std::int64_t count_ = 0;
};

class MisbehavingFilter final : public fba::Component {
 public:
  static fba::Spec spec() {
    return with_mode(fba::Spec::filter("test.misbehaving", "Forwards integers; misbehaves as its mode says.")
                         .input<std::int64_t>("in", "integers")
                         .output<std::int64_t>("out", "the same integers"));
  }
  explicit MisbehavingFilter(fba::Context& ctx) : m_(ctx), in_(ctx.input("in")), out_(ctx.output("out")) {}
  void process() override {
    m_.maybe();
    out_.emit<std::int64_t>(in_.get<std::int64_t>());
  }

 private:
  Misbehaviour m_;
  fba::Input& in_;
  fba::Output& out_;
};

class MisbehavingSensor final : public fba::Component {
 public:
  static fba::Spec spec() {
    return with_mode(fba::Spec::sensor("test.misbehaving_sensor", "Emits count integers; misbehaves as its mode says.")
                         .output<std::int64_t>("out", "0, 1, 2, ...")
                         .param("count", 10, "integers to emit before finishing")
                         .range(0, std::nullopt));
  }
  explicit MisbehavingSensor(fba::Context& ctx)
      : ctx_(ctx), m_(ctx), out_(ctx.output("out")), count_(ctx.param<std::int64_t>("count")) {}
  void process() override {
    if (m_.mode() == "never_finish") return;  // free-running, produces nothing, never finishes
    m_.maybe();
    if (next_ < count_) out_.emit<std::int64_t>(next_++);
    if (next_ >= count_) ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  Misbehaviour m_;
  fba::Output& out_;
  std::int64_t count_, next_ = 0;
};

// Writes the marker file "running.<name>" into the output folder on its first sample, and
// "safe_state.<name>" when its safe state is asked for, so that a test knows the run started
// and sees the safe state was attempted even when the process ended abnormally.
class MisbehavingActuator final : public fba::Component {
 public:
  static fba::Spec spec() {
    return with_mode(
        fba::Spec::actuator("test.misbehaving_actuator", "Consumes integers; marks its safe state in a file.")
            .input<std::int64_t>("in", "integers"));
  }
  explicit MisbehavingActuator(fba::Context& ctx) : ctx_(ctx), m_(ctx) {}
  void process() override {
    if (!running_ && !ctx_.output_dir().empty())
      std::ofstream(ctx_.output_dir() / ("running." + ctx_.name())) << "running\n";
    running_ = true;
    m_.maybe();
  }
  void safe_state() override {
    if (!ctx_.output_dir().empty()) std::ofstream(ctx_.output_dir() / ("safe_state." + ctx_.name())) << "attempted\n";
    if (m_.mode() == "block_safe_state") block_forever();
  }

 private:
  fba::Context& ctx_;
  Misbehaviour m_;
  bool running_ = false;
};

}  // namespace

FBA_COMPONENT(MisbehavingFilter);
FBA_COMPONENT(MisbehavingSensor);
FBA_COMPONENT(MisbehavingActuator);
