// examples.faulty: forwards samples and throws after a given number, for fault-handling tests.
#include <fba/component.hpp>

namespace {

class Faulty final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("examples.faulty", "Forwards samples; throws on the sample after `fail_after` of them.")
        .any_input("in", "samples of any type")
        .output_like("out", "in", "the samples before the failure")
        .param("fail_after", 5, "samples forwarded before it throws").range(0, std::nullopt)
        .param("message", "injected fault", "the exception's text");
  }

  explicit Faulty(fba::Context& ctx)
      : in_(ctx.input("in")), out_(ctx.output("out")), fail_after_(ctx.param<std::int64_t>("fail_after")),
        message_(ctx.param<std::string>("message")) {}

  void process() override {
    if (forwarded_ == fail_after_) throw std::runtime_error(message_);
    out_.forward(in_.take());
    ++forwarded_;
  }

 private:
  fba::Input& in_;
  fba::Output& out_;
  const std::int64_t fail_after_;
  const std::string message_;
  std::int64_t forwarded_ = 0;
};

}  // namespace

FBA_COMPONENT(Faulty);
