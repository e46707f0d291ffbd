// examples.passthrough: the smallest filter; the runtime's hop cost is measured with it.
#include <fba/component.hpp>

namespace {

class Passthrough final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("examples.passthrough", "Forwards each sample unchanged: same data, same header, no copy.")
        .any_input("in", "samples of any type")
        .output_like("out", "in", "the same samples");
  }

  explicit Passthrough(fba::Context& ctx) : in_(ctx.input("in")), out_(ctx.output("out")) {}

  void process() override { out_.forward(in_.take()); }

 private:
  fba::Input& in_;
  fba::Output& out_;
};

}  // namespace

FBA_COMPONENT(Passthrough);
