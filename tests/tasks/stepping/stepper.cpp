// test.stepper: a sensor that takes `max_views` views one per call, the way the grasp loop's
// components report them (its stage, the result "views"), and waits inside each call until the
// test creates the file "<gate>/<view>": a long call the test ends when it has seen what the
// console says about it. The waits end at the task's stop.
#include <chrono>
#include <filesystem>
#include <thread>

#include <fba/component.hpp>

namespace {

class Stepper final : public fba::Component {
 public:
  static constexpr fba::Out<std::int64_t> kOut{"out", "the view just taken, counted from 0 (as examples.sink expects)"};
  static constexpr auto kMaxViews = fba::Param<std::int64_t>("max_views", 3, "views to take").range(1, 1000);
  static constexpr fba::Param<std::filesystem::path> kGate{"gate", fba::required, "the folder where the test lets each view end"};
  static fba::Spec spec() {
    return fba::Spec::sensor("test.stepper", "Takes views one at a time, each when the test lets it.")
        .add(kOut, kMaxViews, kGate)
        .stages({"looking", "waiting"}, {{"looking", "waiting"}, {"waiting", "looking"}});
  }

  explicit Stepper(fba::Context& ctx) : ctx_(ctx), stages_(ctx), max_views_(ctx(kMaxViews)), gate_(ctx(kGate)) {}

  void process() override {
    if (stages_.current() != "looking") stages_.go("looking");
    ++views_;
    ctx_.report("views", std::to_string(views_));
    ctx_.log().info("view {} taken", views_);
    stages_.go("waiting");
    const auto stop = ctx_.stop_token();
    while (!std::filesystem::exists(gate_ / std::to_string(views_)) && !stop.stop_requested())
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ctx_(kOut).emit(views_ - 1);
    if (views_ >= max_views_) ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  fba::Stages stages_;
  const std::int64_t max_views_;
  const std::filesystem::path gate_;
  std::int64_t views_ = 0;
};
FBA_COMPONENT(Stepper);

}  // namespace
