// demo.scale: multiplies each integer by a factor. A whole plugin in one source file, built
// outside the fba tree with find_package(fba) and fba_add_plugin(demo scale.cpp).
#include <fba/component.hpp>

namespace {

class Scale final : public fba::Component {
 public:
  // The interface, declared once: the loader checks task files against it, fba-inspect shows it.
  static fba::Spec spec() {
    return fba::Spec::filter("demo.scale", "Multiplies each integer by `factor`.")
        .input<std::int64_t>("in", "the integers to scale")
        .output<std::int64_t>("out", "each integer times factor, with the input's time stamp")
        .param("factor", 2, "what each integer is multiplied by").range(-1000, 1000)
        .event("overflow", "a product does not fit in 64 bits; the sample is dropped; payload: the input");
  }

  // Runs when the task is built, before anything runs: look up ports and read parameters here.
  explicit Scale(fba::Context& ctx)
      : ctx_(ctx), in_(ctx.input("in")), out_(ctx.output("out")), factor_(ctx.param<std::int64_t>("factor")) {}

  // One sample in, one sample out (the default trigger of a filter: any input has a sample).
  void process() override {
    const std::int64_t x = in_.get<std::int64_t>();
    std::int64_t y = 0;
    if (__builtin_mul_overflow(x, factor_, &y)) {
      ctx_.emit_event("overflow", std::to_string(x));
      return;
    }
    out_.emit(y, in_.packet().header().stamp_ns);
  }

  // Every producer has finished and the input is drained.
  void end_of_stream() override { ctx_.log().info("scaled {} samples by {}", out_.count(), factor_); }

 private:
  fba::Context& ctx_;
  fba::Input& in_;
  fba::Output& out_;
  const std::int64_t factor_;
};

}  // namespace

FBA_COMPONENT(Scale);
