// examples.counter: emits the integers start .. start+count-1, as fast as the consumers take
// them or at a fixed rate.
#include <fba/component.hpp>

namespace {

class Counter final : public fba::Component {
 public:
  static constexpr fba::Out<std::int64_t> kOut{"out", "the integers, one sample each"};
  static constexpr auto kCount = fba::Param<std::int64_t>("count", 10, "how many integers to emit").at_least(0);
  static constexpr fba::Param<std::int64_t> kStart{"start", 0, "the first integer"};
  static constexpr auto kRate =
      fba::Param<double>("rate", 0.0, "samples per second; 0 emits as fast as the consumers take them").range(0, 1e6);

  static fba::Spec spec() {
    return fba::Spec::sensor("examples.counter", "Emits the integers start .. start+count-1, then finishes.")
        .add(kOut, kCount, kStart, kRate);
  }

  explicit Counter(fba::Context& ctx) : ctx_(ctx), out_(ctx(kOut)), next_(ctx(kStart)), end_(next_ + ctx(kCount)) {
    if (const double rate = ctx(kRate); rate > 0) ctx.set_trigger({fba::TriggerPolicy::Periodic, 1.0 / rate});
  }

  void process() override {
    if (next_ < end_) out_.emit(next_++);
    if (next_ >= end_) ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  fba::OutputOf<std::int64_t> out_;
  std::int64_t next_, end_;
};

}  // namespace

FBA_COMPONENT(Counter);
