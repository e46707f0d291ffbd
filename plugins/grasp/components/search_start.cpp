// grasp.start: where a grasp search begins. One sample when the task starts, which the
// exploration planner's `start` takes as the order to request its initial views; then it finishes.
// The loop's own component, so that a grasp task does not depend on the tutorial's examples.
#include <cstdint>

#include <fba/component.hpp>

namespace {

class SearchStart final : public fba::Component {
 public:
  static constexpr fba::Out<std::int64_t> kOut{"out", "one sample (0) when the task starts: wire it to the exploration planner's start"};

  static fba::Spec spec() {
    return fba::Spec::sensor("grasp.start", "Starts a grasp search: one sample when the task starts, then finishes.").add(kOut);
  }

  explicit SearchStart(fba::Context& ctx) : ctx_(ctx), out_(ctx(kOut)) {}

  void process() override {
    out_.emit(0);
    ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  fba::OutputOf<std::int64_t> out_;
};

}  // namespace

FBA_COMPONENT(SearchStart);
