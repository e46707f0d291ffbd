// examples.sink: consumes samples and checks that each producer's sequence arrives complete
// and in order; the lossless-delivery tests and soaks rest on it.
#include <chrono>
#include <map>
#include <thread>

#include <fba/component.hpp>

namespace {

class Sink final : public fba::Component {
 public:
  static constexpr fba::AnyIn kIn{"in", "samples of any type"};
  static constexpr auto kExpected = fba::Param<std::int64_t>("expected", 0, "emit 'done' after this many samples; 0 for never").at_least(0);
  static constexpr auto kDelay = fba::Param<double>("delay", 0.0, "seconds spent on each sample, to play a slow device").range(0, 10);
  static constexpr fba::EventOut kDone{"done", "the expected number of samples arrived; payload: the count"};
  static constexpr fba::EventOut kGap{"gap", "a sample was missing or out of order; payload: what was expected and what came"};
  static constexpr fba::EventOut kSafeState{"safe_state", "the sink was asked to reach its safe state at the end of the run"};

  static fba::Spec spec() {
    return fba::Spec::actuator("examples.sink", "Consumes samples, checks their sequence numbers have no gap or reordering.")
        .add(kIn, kExpected, kDelay, kDone, kGap, kSafeState);
  }

  explicit Sink(fba::Context& ctx)
      : ctx_(ctx), in_(ctx(kIn)), expected_(ctx(kExpected)), delay_(std::chrono::duration<double>(ctx(kDelay))) {}

  void process() override {
    const fba::Header& h = in_.packet().header();
    auto [it, first] = next_seq_.try_emplace(h.producer, h.seq);
    if (h.seq != it->second) {
      const std::string what = "from " + (h.producer ? *h.producer : std::string("?")) + ": expected sample " +
                               std::to_string(it->second) + ", got " + std::to_string(h.seq);
      ctx_.emit(kGap, what);
      throw std::runtime_error("sequence gap " + what);
    }
    it->second = h.seq + 1;
    if (delay_.count() > 0) std::this_thread::sleep_for(delay_);
    if (++received_ == expected_) ctx_.emit(kDone, std::to_string(received_));
  }

  void safe_state() override { ctx_.emit(kSafeState, std::to_string(received_) + " samples received"); }

 private:
  fba::Context& ctx_;
  fba::Input& in_;
  const std::int64_t expected_;
  const std::chrono::duration<double> delay_;
  std::map<const std::string*, std::uint64_t> next_seq_;
  std::int64_t received_ = 0;
};

}  // namespace

FBA_COMPONENT(Sink);
