// examples.passthrough: the smallest filter; the runtime's hop cost is measured with it.
#include <fba/component.hpp>

namespace {

class Passthrough final : public fba::Component {
 public:
  static constexpr fba::AnyIn kIn{"in", "samples of any type"};
  static constexpr fba::OutLike kOut{"out", kIn, "the same samples"};

  static fba::Spec spec() {
    return fba::Spec::filter("examples.passthrough", "Forwards each sample unchanged: same data, same header, no copy.").add(kIn, kOut);
  }

  // The ports are looked up once: process() is the hop whose cost the benchmark measures.
  explicit Passthrough(fba::Context& ctx) : in_(ctx(kIn)), out_(ctx(kOut)) {}

  void process() override { out_.forward(in_.take()); }

 private:
  fba::Input& in_;
  fba::Output& out_;
};

}  // namespace

FBA_COMPONENT(Passthrough);
