// demo.scale: multiplies each integer by a factor. A whole plugin in one source file, built
// outside the fba tree with find_package(fba) and fba_add_plugin(demo scale.cpp).
#include <fba/component.hpp>

namespace {

class Scale final : public fba::Component {
 public:
  // The interface, declared once as typed constants: spec() is built from them (the loader
  // checks task files against it, fba-inspect shows it) and the code below uses the same ones.
  static constexpr fba::In<std::int64_t> kIn{"in", "the integers to scale"};
  static constexpr fba::Out<std::int64_t> kOut{"out", "each integer times factor, with the input's time stamp"};
  static constexpr auto kFactor = fba::Param<std::int64_t>("factor", 2, "what each integer is multiplied by").range(-1000, 1000);
  static constexpr fba::EventOut kOverflow{"overflow", "a product does not fit in 64 bits; the sample is dropped; payload: the input"};

  static fba::Spec spec() { return fba::Spec::filter("demo.scale", "Multiplies each integer by `factor`.").add(kIn, kOut, kFactor, kOverflow); }

  // Runs when the task is built, before anything runs: read parameters here.
  explicit Scale(fba::Context& ctx) : ctx_(ctx), factor_(ctx(kFactor)) {}

  // One sample in, one sample out (the default trigger of a filter: any input has a sample).
  // The output carries the input's time stamp.
  void process() override {
    const std::int64_t x = ctx_(kIn).get();
    std::int64_t y = 0;
    if (__builtin_mul_overflow(x, factor_, &y)) {
      ctx_.emit(kOverflow, std::to_string(x));
      return;
    }
    ctx_(kOut).emit(y);
  }

  // Every producer has finished and the input is drained.
  void end_of_stream() override { ctx_.log().info("scaled {} samples by {}", ctx_(kOut).count(), factor_); }

 private:
  fba::Context& ctx_;
  const std::int64_t factor_;
};

}  // namespace

FBA_COMPONENT(Scale);
