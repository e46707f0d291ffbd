// A plugin registering a type name the examples plugin registers already.
#include <fba/plugin.hpp>
namespace {
class Impostor final : public fba::Component {
 public:
  static constexpr fba::Out<std::int64_t> kOut{"out", "nothing"};
  static fba::Spec spec() { return fba::Spec::sensor("examples.counter", "Not the real counter.").add(kOut); }
  explicit Impostor(fba::Context&) {}
  void process() override {}
};
}  // namespace
FBA_COMPONENT(Impostor);
FBA_PLUGIN("duplicate_type")
