// examples.faulty: forwards samples and throws after a given number, for fault-handling tests.
#include <fba/component.hpp>

namespace {

class Faulty final : public fba::Component {
 public:
  static constexpr fba::AnyIn kIn{"in", "samples of any type"};
  static constexpr fba::OutLike kOut{"out", kIn, "the samples before the failure"};
  static constexpr auto kFailAfter = fba::Param<std::int64_t>("fail_after", 5, "samples forwarded before it throws").at_least(0);
  static constexpr fba::Param<std::string> kMessage{"message", "injected fault", "the exception's text"};

  static fba::Spec spec() {
    return fba::Spec::filter("examples.faulty", "Forwards samples; throws on the sample after `fail_after` of them.")
        .add(kIn, kOut, kFailAfter, kMessage);
  }

  explicit Faulty(fba::Context& ctx) : in_(ctx(kIn)), out_(ctx(kOut)), fail_after_(ctx(kFailAfter)), message_(ctx(kMessage)) {}

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
