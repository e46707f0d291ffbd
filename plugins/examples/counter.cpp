// examples.counter: emits the integers start .. start+count-1, as fast as the consumers take
// them or at a fixed rate.
#include <fba/component.hpp>

namespace {

class Counter final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::sensor("examples.counter", "Emits the integers start .. start+count-1, then finishes.")
        .output<std::int64_t>("out", "the integers, one sample each")
        .param("count", 10, "how many integers to emit").range(0, std::nullopt)
        .param("start", 0, "the first integer")
        .param("rate", 0.0, "samples per second; 0 emits as fast as the consumers take them").range(0, 1e6);
  }

  explicit Counter(fba::Context& ctx)
      : ctx_(ctx), out_(ctx.output("out")), next_(ctx.param<std::int64_t>("start")), end_(next_ + ctx.param<std::int64_t>("count")) {
    if (const double rate = ctx.param<double>("rate"); rate > 0) ctx.set_trigger({fba::TriggerPolicy::Periodic, 1.0 / rate});
  }

  void process() override {
    if (next_ < end_) out_.emit<std::int64_t>(next_++);
    if (next_ >= end_) ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  fba::Output& out_;
  std::int64_t next_, end_;
};

}  // namespace

FBA_COMPONENT(Counter);
