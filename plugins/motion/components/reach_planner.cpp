// motion.reach_planner: the motor stage. For each grasp, with the newest model and joint state,
// it plans what the arm and the hand do (fba/motion/reach_planner.hpp): the timed joint trajectory
// for the arm's driver, the hand's commands in order, or the event `unreachable` with the reason.
// Its stages follow the plan's steps on the task's clock from when the plan was sent, as the
// component runs (each joint state or model that arrives). With an output folder, a plan's
// pictures are written there once the plan is sent: robot_pregrasp.png and robot_lift.png
// (fba/motion/robot_picture.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <fba/component.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/hand_command.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/joint_trajectory.hpp>
#include <fba/types/joint_trajectory_json.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/pose_json.hpp>

#include "fba/motion/reach_parameters.hpp"
#include "fba/motion/reach_planner.hpp"
#if FBA_ROBOT_PICTURES
#include "fba/motion/robot_picture.hpp"
#endif

namespace {

using fba::motion::ReachParameters;
using fba::motion::ReachPlan;
using fba::motion::ReachPlanner;

nlohmann::json values(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

class ReachPlannerFilter final : public fba::Component {
 public:
  static constexpr fba::In<fba::Grasp> kGrasp{"grasp", "the grasp to take (world frame, the table at z = 0)"};
  static constexpr fba::In<fba::Octree> kOctree{
      "octree", "the carved model: its occupied and not-yet-carved leaves are obstacles until the fingers close (the newest is used)"};
  static constexpr fba::In<fba::JointState> kJointState{
      "joint_state", "the arm's joints: the plan starts from the newest at rest (a grasp that comes while the arm moves waits for it)"};
  static constexpr fba::Out<fba::JointTrajectory> kTrajectory{
      "trajectory", "the arm's timed joint trajectory, every joint on every waypoint: the path, the approach, the lift and the retreat"};
  static constexpr fba::Out<fba::HandCommand> kHand{
      "hand", "the hand's commands in order (open for the pregrasp, close, open to release), timed on the trajectory"};
  static constexpr fba::EventOut kUnreachable{
      "unreachable", "the grasp cannot be taken; payload (JSON): refusal (hand, table, ik, collision, approach, lift, start, path) and reason"};

  static constexpr auto kHoldTime = fba::Param<double>("hold_time", 2.0, "seconds the arm holds still at the top of the lift").range(0, 60);
  static constexpr auto kHandTime =
      fba::Param<double>("hand_time", 1.0, "seconds the arm stands still while the hand opens or closes").range(0, 60);
  static constexpr auto kFingerForce =
      fba::Param<double>("finger_force", 15.0, "newtons at each pad when closing (the Robotiq 3-Finger grips with 15 to 60)").range(0.1, 1000);
  static constexpr fba::Param<bool> kRetreat{"retreat", true, "after the hold: put the object back, open the hand, back out to the standoff"};
  static constexpr auto kSpeed =
      fba::Param<double>("speed_scale", 0.5, "share of each joint's URDF velocity limit the trajectory uses").range(0.01, 1.0);
  static constexpr auto kAcceleration =
      fba::Param<double>("acceleration", 3.0, "joint acceleration limit, rad/s^2, every joint").range(0.01, 100.0);
  static constexpr auto kSamplePeriod =
      fba::Param<double>("sample_period", 0.02, "seconds between the trajectory's waypoints").range(0.001, 1.0);
  static constexpr fba::Param<std::string> kObject{
      "object", "", "the object's name in the titles of the pictures written into the output folder; empty: \"the object\""};

  static fba::Spec spec() {
    fba::Spec spec = fba::Spec::filter("motion.reach_planner",
                                       "Plans the arm's reach for a grasp (KDL inverse kinematics, OMPL path, FCL collisions against "
                                       "the table, the arm and the carved model): a timed joint trajectory and the hand's commands.");
    spec.add(kGrasp, kOctree, kJointState, kTrajectory, kHand, kUnreachable);
    ReachParameters::add(spec)  // shared with grasp.synthesis, which checks reachability with them
        .add(kHoldTime, kHandTime, kFingerForce, kRetreat, kSpeed, kAcceleration, kSamplePeriod, kObject)
        .stages({"idle", "plan", "approach", "close", "lift", "hold", "retreat"},
                {{"idle", "plan"}, {"plan", "idle"}, {"plan", "approach"}, {"approach", "plan"}, {"approach", "close"},
                 {"close", "plan"}, {"close", "lift"}, {"lift", "plan"}, {"lift", "hold"}, {"hold", "plan"}, {"hold", "retreat"},
                 {"hold", "idle"}, {"retreat", "plan"}, {"retreat", "idle"}});
    return spec;
  }

  explicit ReachPlannerFilter(fba::Context& ctx)
      : ctx_(ctx), stages_(ctx), planner_(ReachParameters::planner(ctx, params(ctx))) {
    ctx.log().info("reach planning for the arm from '{}' to '{}' ({} joints)", planner_.arm().base_link(), planner_.arm().tip_link(),
                   planner_.arm().size());
  }

  void process() override {
    if (auto in = ctx_(kGrasp); in.has()) pending_ = in.get();
    const fba::Octree* model = ctx_(kOctree).latest();
    const fba::JointState* joints = ctx_(kJointState).latest();
    // An arm refuses a trajectory while it moves (it starts where the arm stands still), and a
    // plan from a moving arm's joints starts where it no longer is: a grasp selected while the
    // arm is on its way to a view waits for it to stop.
    if (pending_ && model && joints && fba::motion::at_rest(*joints)) {
      const fba::Grasp grasp = *pending_;
      pending_.reset();
      plan(grasp, *model, *joints);
    }
    follow(ctx_.now_ns());
  }

 private:
  // The planner's own parameters; ReachParameters::planner() adds the shared ones.
  static fba::motion::ReachParams params(fba::Context& ctx) {
    fba::motion::ReachParams p;
    p.hold_s = ctx(kHoldTime);
    p.hand_s = ctx(kHandTime);
    p.finger_force = ctx(kFingerForce);
    p.retreat = ctx(kRetreat);
    p.speed_scale = ctx(kSpeed);
    p.acceleration = ctx(kAcceleration);
    p.sample_period = ctx(kSamplePeriod);
    return p;
  }

  void plan(const fba::Grasp& grasp, const fba::Octree& model, const fba::JointState& js) {
    go("plan");
    steps_.clear();  // a new grasp replaces the plan being followed
    ++plans_;
    std::string why;
    const auto current = fba::motion::arm_joints(planner_.arm(), js, why);
    ReachPlan plan;
    if (current) {
      plan = planner_.plan(grasp, model, *current);
    } else {
      plan.refusal = fba::motion::Refusal::Start;
      plan.why = why;
    }
    const char* refusal = fba::motion::to_string(plan.refusal);
    nlohmann::json figures = {{"plans", plans_},
                              {"ok", plan.ok},
                              {"ik_attempts", plan.figures.ik_attempts},
                              {"planning_s", plan.figures.planning_s},
                              {"path_length_rad", plan.figures.path_length},
                              {"path_waypoints", plan.figures.path_waypoints},
                              {"direct", plan.figures.direct},
                              {"collision_checks", plan.figures.collision_checks},
                              {"backout_m", plan.figures.backout}};
    if (!plan.ok) {
      ++refused_[refusal];
      figures["refusal"] = refusal;
      figures["reason"] = plan.why;
      figures["refused"] = refused_;
      ctx_.report("reach", figures.dump());
      ctx_.log().warn("grasp unreachable ({}): {}", refusal, plan.why);
      ctx_.emit(kUnreachable, nlohmann::json{{"refusal", refusal}, {"reason", plan.why}}.dump());
      go("idle");
      return;
    }
    nlohmann::json steps = nlohmann::json::object();
    for (const auto& s : plan.steps) steps[s.name] = s.end_s - s.start_s;
    figures["steps_s"] = steps;
    figures["duration_s"] = plan.trajectory.points.back().time;
    figures["pregrasp_palm"] = fba::pose_json(plan.pregrasp_palm);
    figures["pregrasp_joints"] = values(plan.pregrasp_joints);
    figures["opening_m"] = plan.opening;
    figures["spread_m"] = plan.spread;
    figures["trajectory"] = fba::trajectory_json(plan.trajectory);
    if (!refused_.empty()) figures["refused"] = refused_;
    ctx_.report("reach", figures.dump());
    ctx_.log().info("reach planned: {:.2f} s of motion, path {:.2f} rad ({} waypoints{}) found in {:.3f} s",
                    plan.trajectory.points.back().time, plan.figures.path_length, plan.figures.path_waypoints,
                    plan.figures.direct ? ", straight" : "", plan.figures.planning_s);
    ctx_(kTrajectory).emit(plan.trajectory);
    for (const auto& c : plan.hand) ctx_(kHand).emit(c);
    steps_ = plan.steps;
    sent_ns_ = ctx_.now_ns();
    write_pictures(grasp, model, plan);
  }

  // The robot at the plan's pregrasp and lift, into the output folder (none: nothing drawn), once
  // the plan is sent, so that drawing adds nothing to the time a plan takes. The latest plan's
  // pictures replace an earlier one's. A picture lost is reported; the plan stands.
  void write_pictures(const fba::Grasp& grasp, const fba::Octree& model, const ReachPlan& plan) {
    if (ctx_.output_dir().empty()) return;
#if FBA_ROBOT_PICTURES
    try {
      const auto start = std::chrono::steady_clock::now();
      fba::motion::write_robot_pictures(ctx_.output_dir(), planner_, plan, grasp, model, ctx_(kObject));
      ctx_.log().info("wrote robot_pregrasp.png and robot_lift.png in {:.3f} s",
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    } catch (const std::exception& e) {
      ctx_.log().error("could not draw the robot's pictures in {}: {}", ctx_.output_dir().string(), e.what());
    }
#else
    (void)grasp, (void)model, (void)plan;
    ctx_.log().info("no robot pictures: this build has no vision libraries (FBA_BUILD_VISION off) to draw them");
#endif
  }

  // The stage of the plan being followed: the step its time since it was sent falls in.
  void follow(std::int64_t now_ns) {
    if (steps_.empty()) return;
    const double t = static_cast<double>(now_ns - sent_ns_) * 1e-9;
    std::size_t reached = 0;
    while (reached + 1 < steps_.size() && t >= steps_[reached + 1].start_s) ++reached;
    const auto at = [&] {
      for (std::size_t i = 0; i < steps_.size(); ++i)
        if (steps_[i].name == stages_.current()) return i;
      return std::size_t{0};
    }();
    for (std::size_t i = at + 1; i <= reached; ++i) go(steps_[i].name);
    if (t >= steps_.back().end_s) {
      go("idle");
      steps_.clear();
    }
  }

  void go(const std::string& stage) {
    if (stages_.current() != stage) stages_.go(stage);
  }

  fba::Context& ctx_;
  fba::Stages stages_;
  const ReachPlanner planner_;
  std::optional<fba::Grasp> pending_;
  std::vector<fba::motion::ReachStep> steps_;  // of the plan being followed
  std::int64_t sent_ns_ = 0;
  int plans_ = 0;
  std::map<std::string, int> refused_;  // refusals by kind
};

}  // namespace

FBA_COMPONENT(ReachPlannerFilter);
