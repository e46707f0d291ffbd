// Components that misbehave on purpose, one way per `mode`, so that fba-run's tests can check
// that every way out of a run ends in order: the documented exit status, summary.json naming the
// cause, and the actuators' safe states attempted.
//
// Modes (after `after` good invocations): throw_exception, throw_int, throw_in_constructor_int,
// segfault, block_process (ignores interrupt), block_safe_state (actuator), exit_zero,
// never_finish (sensor: free-running, produces nothing). "none" behaves.
// FBA_TEST_EXIT_IN_STATIC_INIT=1 in the environment makes the plugin call exit(0) while loading,
// FBA_TEST_SEGFAULT_IN_STATIC_INIT=1 fault while loading (as a broken plugin's initialiser can).
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <thread>

#include <fba/component.hpp>

namespace {

// A real fault that the sanitizers do not take first (a null store is UB that UBSan stops at).
void fault() {
  void* page = mmap(nullptr, 4096, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  *static_cast<volatile int*>(page) = 1;
}

[[maybe_unused]] const bool misbehave_while_loading = [] {
  auto set = [](const char* name) {
    const char* v = std::getenv(name);
    return v && std::string(v) == "1";
  };
  if (set("FBA_TEST_EXIT_IN_STATIC_INIT")) std::exit(0);
  if (set("FBA_TEST_SEGFAULT_IN_STATIC_INIT")) fault();
  return true;
}();

constexpr fba::Param<std::string> kMode =
    fba::Param<std::string>{"mode", "none", "how to misbehave"}.choices(
        {"none", "throw_exception", "throw_int", "throw_in_constructor_int", "segfault", "block_process",
         "block_safe_state", "exit_zero", "never_finish"});
constexpr fba::Param<std::int64_t> kAfter = fba::Param<std::int64_t>{"after", 0, "good invocations before misbehaving"}.at_least(0);

fba::Spec with_mode(fba::Spec spec) { return std::move(spec).add(kMode, kAfter); }

// Blocks the calling thread for good: neither interrupt() nor anything else ends it.
[[noreturn]] void block_forever() {
  for (;;) pause();
}

class Misbehaviour {
 public:
  explicit Misbehaviour(fba::Context& ctx)
      : mode_(ctx(kMode)), after_(ctx(kAfter)) {
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
    if (mode_ == "segfault") fault();
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
    return with_mode(fba::Spec::filter("test.misbehaving", "Forwards integers; misbehaves as its mode says.").add(kIn, kOut));
  }
  static constexpr fba::In<std::int64_t> kIn{"in", "integers"};
  static constexpr fba::Out<std::int64_t> kOut{"out", "the same integers"};
  explicit MisbehavingFilter(fba::Context& ctx) : ctx_(ctx), m_(ctx) {}
  void process() override {
    m_.maybe();
    ctx_(kOut).emit(ctx_(kIn).get());
  }

 private:
  fba::Context& ctx_;
  Misbehaviour m_;
};

class MisbehavingSensor final : public fba::Component {
 public:
  static fba::Spec spec() {
    return with_mode(fba::Spec::sensor("test.misbehaving_sensor", "Emits count integers; misbehaves as its mode says.")
                         .add(kOut, kCount));
  }
  static constexpr fba::Out<std::int64_t> kOut{"out", "0, 1, 2, ..."};
  static constexpr fba::Param<std::int64_t> kCount =
      fba::Param<std::int64_t>{"count", 10, "integers to emit before finishing"}.at_least(0);
  explicit MisbehavingSensor(fba::Context& ctx) : ctx_(ctx), m_(ctx), out_(ctx(kOut)), count_(ctx(kCount)) {}
  void process() override {
    if (m_.mode() == "never_finish") return;  // free-running, produces nothing, never finishes
    m_.maybe();
    if (next_ < count_) out_.emit(next_++);
    if (next_ >= count_) ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  Misbehaviour m_;
  fba::OutputOf<std::int64_t> out_;
  std::int64_t count_, next_ = 0;
};

// Writes the marker file "running.<name>" into the output folder on its first sample, and
// "safe_state.<name>" when its safe state is asked for, so that a test knows the run started
// and sees the safe state was attempted even when the process ended abnormally.
class MisbehavingActuator final : public fba::Component {
 public:
  static fba::Spec spec() {
    return with_mode(
        fba::Spec::actuator("test.misbehaving_actuator", "Consumes integers; marks its safe state in a file.").add(kIn));
  }
  static constexpr fba::In<std::int64_t> kIn{"in", "integers"};
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
