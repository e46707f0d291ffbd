// A filter that binds an output its spec leaves out, in its constructor: found by fba-run --check
// (fba::check_construction) before anything runs. And an actuator whose constructor leaves a mark,
// as opening a device would: --check must not construct it.
#include <fstream>

#include <fba/plugin.hpp>

namespace {

class Undeclared final : public fba::Component {
 public:
  static constexpr fba::In<std::int64_t> kIn{"in", "integers"};
  static constexpr fba::Out<std::int64_t> kOut{"out", "the same integers"};
  static constexpr fba::Out<std::int64_t> kForgotten{"forgotten", "declared here, left out of spec()"};
  static fba::Spec spec() {
    return fba::Spec::filter("bad.undeclared_handle", "Forwards integers; binds an output its spec leaves out.").add(kIn, kOut);
  }
  explicit Undeclared(fba::Context& ctx) : in_(ctx(kIn)), out_(ctx(kOut)), forgotten_(ctx(kForgotten)) {}
  void process() override { out_.emit(in_.get()); }

 private:
  fba::InputOf<std::int64_t> in_;
  fba::OutputOf<std::int64_t> out_, forgotten_;
};
FBA_COMPONENT(Undeclared);

class MarkingActuator final : public fba::Component {
 public:
  static constexpr fba::In<std::int64_t> kIn{"in", "integers"};
  static constexpr fba::Param<std::string> kMark{"mark", fba::required, "the file its constructor creates (a string: a path parameter must exist)"};
  static fba::Spec spec() {
    return fba::Spec::actuator("bad.marking_actuator", "Creates a file when constructed, as opening a device would.").add(kIn, kMark);
  }
  explicit MarkingActuator(fba::Context& ctx) { std::ofstream(ctx(kMark)) << "constructed\n"; }
  void process() override {}
};
FBA_COMPONENT(MarkingActuator);

}  // namespace
FBA_PLUGIN("undeclared_handle")
