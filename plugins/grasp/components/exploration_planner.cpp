// grasp.exploration_planner: the exploration movement's planning. Each regions sample from grasp
// synthesis is a request for a new view; the planner scores its candidate views by the request's
// surface points each one grazes in a new direction (the lines of sight that pin a contact down),
// or when none does by the uncertain model nodes inside the regions each one sees, less the cost
// of moving there, and emits the best as the camera's target pose, or no_view with the reason when
// none is worth the move. (The models are written by grasp.synthesis, which analyses every one.)
// With the arm's joints it sends the joints to move to instead, once it has checked the move
// there clear of the arm itself, the table and the model: the arm carries its camera round an
// object it may not touch.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <fba/component.hpp>
#include <fba/geometry/viewpoints.hpp>
#include <fba/thread_pool.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/pose.hpp>
#include <fba/types/pose_json.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/vision/image_set.hpp>

#include "fba/grasp/exploration.hpp"
#if FBA_GRASP_REACH
#include "arm_model.hpp"
#include "fba/motion/joint_path.hpp"
#include "fba/motion/model_obstacles.hpp"
#include "fba/motion/reach_parameters.hpp"
#include "fba/motion/robot_collision.hpp"
#include "robot_parameters.hpp"
#endif

namespace {

constexpr double kDeg = std::numbers::pi / 180;

class ExplorationPlanner final : public fba::Component {
 public:
  static constexpr fba::In<fba::Octree> kOctree{"octree", "the model (the latest is used)"};
  static constexpr fba::In<fba::RegionsOfInterest> kRegions{
      "regions", "where grasping needs detail; a sample from a model with every view asked for so far asks for a new view"};
  static constexpr fba::OptionalIn<fba::Pose> kCurrent{
      "current", "where the camera is (world_from_camera); without it, the last target stands for it"};
  static constexpr fba::OptionalIn<std::int64_t> kStart{
      "start", "a sample (grasp.start's) starts the exploration: the first initial_views candidates are requested, no model needed"};
  static constexpr fba::Out<fba::Pose> kTarget{"target", "the camera's next pose, world_from_camera"};
  static constexpr auto kViews = fba::Param<std::string>(
      "views", "ring", "the candidate views: a ring or a hemisphere around centre, or the recorded views of poses_from")
      .choices({"ring", "hemisphere", "recorded"});
  static constexpr auto kCount = fba::Param<int>("count", 16, "ring and hemisphere: how many candidate views").range(1, 10000);
  static constexpr auto kDistance = fba::Param<double>("distance", 0.5, "ring and hemisphere: metres from the centre").range(1e-6, 1e6);
  static constexpr auto kMinElevation = fba::Param<double>(
      "min_elevation_deg", 30, "lowest elevation above the centre's horizontal plane; a ring lies midway between the two")
      .range(-90, 90);
  static constexpr auto kMaxElevation =
      fba::Param<double>("max_elevation_deg", 30, "highest elevation of a hemisphere band (90: up to the zenith)").range(-90, 90);
  static inline const auto kCentre = fba::Param<std::vector<double>>(
      "centre", {}, "ring and hemisphere: what the cameras look at [x, y, z], metres; empty: the model's root box centre")
      .size({0, 3});
  static constexpr fba::Param<std::string> kPosesFrom{
      "poses_from", "", "recorded: the image set (Middlebury *_par.txt or fba YAML) whose camera poses are the candidates; relative to the task file's folder"};
  static constexpr fba::Param<bool> kGoodOnly{"good_only", true, "recorded, Middlebury: only the views with good silhouettes"};
  static constexpr auto kInitialViews = fba::Param<int>(
      "initial_views", 3, "on start: how many views are requested before any model, for the initial analysis").range(1, 10000);
  static constexpr auto kInitialLayout = fba::Param<std::string>(
      "initial_layout", "neighbours",
      "which views the start requests: neighbours, candidate 0 and its nearest candidates (the paper's few views close together); "
      "spread, candidate 0 and then each time the candidate farthest from those taken, so that the first model is carved "
      "from around the object")
      .choices({"neighbours", "spread"});
#if FBA_GRASP_REACH
  static constexpr fba::Param<bool> kReachableOnly{
      "reachable_only", false,
      "ring and hemisphere: keep only the candidate views the arm reaches with the robot clear of itself and the table (inverse "
      "kinematics on the robot's arm to its camera, with the arms' collision check; the robot: urdf and its measured transforms), "
      "so that no view asked for is refused"};
  static constexpr fba::OptionalIn<fba::JointState> kJointState{
      "joint_state",
      "the arm's joints (the newest is used). With them every view goes out on joint_target instead of target, as the joints the "
      "arm's inverse kinematics gives nearest to where the arm stands, and only when the straight joint-space motion there keeps "
      "the arm, its camera and its open hand clear of the arm itself, the table and the model (occupied and not-yet-carved "
      "leaves, less what the robot stands in); a view whose motion is not clear is passed over for the next best. The initial "
      "views wait for the arm's first joint state and chain from it, each in place of the nearest candidate whose move is clear"};
  static constexpr fba::Out<fba::JointState> kJointTarget{
      "joint_target", "with joint_state: the joints of the next view (wire it to the arm's joint_target)"};
  static constexpr auto kMoveStep = fba::Param<double>(
      "move_step", 0.02, "with joint_state: rad (Euclidean in joint space) between the poses checked along a move to a view")
      .range(1e-4, 1);
#endif
  static constexpr auto kMovementWeight = fba::Param<double>(
      "movement_weight", 0.1, "score = gain (the grazing gain of the request's points, else the share of its uncertain nodes seen) - movement_weight * (angle moved / 180 deg)").at_least(0);
  static constexpr auto kHalfFov =
      fba::Param<double>("half_fov_deg", 30, "a node is in view within this angle of the optical axis").range(0.1, 179);
  static constexpr auto kMinGain =
      fba::Param<double>("min_gain", 0.01, "no_view when no view reaches this gain (points grazed, else share of the uncertain nodes seen)").range(0, 1);
  static constexpr auto kMaxRays =
      fba::Param<int>("max_rays", 4096, "at most this many uncertain nodes get a ray per candidate (an even stride)").range(1, 100000000);
  static constexpr auto kNextView = fba::Param<std::string>(
      "next_view", "best",
      "best: the candidate of the highest score; random: one of the candidates not yet taken, drawn from seed (the baseline the "
      "choice is measured against: docs/evaluating-grasps.md)")
      .choices({"best", "random"});
  static constexpr auto kSeed = fba::Param<int>("seed", 1, "next_view random: the draws' seed, the same views on every run").range(0, 2147483647);
  static constexpr fba::Param<bool> kExcludeVisited{"exclude_visited", true, "a candidate already requested is not chosen again"};
  static constexpr fba::EventOut kViewChosen{
      "view_chosen", "a target was emitted; payload (JSON): view, pose, score, gain, seen, targets, by_points (chosen by grazing the "
      "request's surface points), points (still to pin), pins, first, reason"};
  static constexpr fba::EventOut kNoView{"no_view", "no candidate is worth the move; payload (JSON): reason, views requested"};

  static fba::Spec spec() {
    fba::Spec spec = fba::Spec::filter("grasp.exploration_planner",
                                       "Chooses the next view: the candidate whose lines of sight graze most of the grasp's unresolved "
                                       "contacts in a new direction, else the one that sees most uncertain model nodes in its regions; "
                                       "visibility-aware, less the cost of moving.")
        .add(kOctree, kRegions, kCurrent, kStart, kTarget, kViews, kCount, kDistance, kMinElevation, kMaxElevation, kCentre,
             kPosesFrom, kGoodOnly, kInitialViews, kInitialLayout, kMovementWeight, kHalfFov, kMinGain, kMaxRays, kNextView, kSeed, kExcludeVisited, kViewChosen,
             kNoView)
        .add(kMinElevation <= kMaxElevation)
        .check([](const fba::ParamValues& p) {
          if (p(kViews) == "recorded" && p(kPosesFrom).empty())
            return std::string("views: recorded needs poses_from, the image set whose poses are the candidates; found none");
          if (p(kViews) != "recorded" && !p(kPosesFrom).empty())
            return std::string("poses_from '" + p(kPosesFrom) + "' is used only with views: recorded; found views: " + p(kViews));
          return std::string();
        });
#if FBA_GRASP_REACH
    spec.add(kReachableOnly, kJointState, kJointTarget, kMoveStep);
    fba::arm::RobotParameters::add(spec);  // the robot reachable_only and the moves are checked on
#endif
    return spec;
  }

  explicit ExplorationPlanner(fba::Context& ctx)
      : ctx_(ctx), initial_views_(ctx(kInitialViews)), exclude_visited_(ctx(kExcludeVisited)), random_(ctx(kNextView) == "random"),
        draws_(static_cast<std::uint32_t>(ctx(kSeed))) {
    params_.movement_weight = ctx(kMovementWeight);
    params_.half_fov_deg = ctx(kHalfFov);
    params_.min_gain = ctx(kMinGain);
    params_.max_rays = static_cast<std::size_t>(ctx(kMaxRays));
    params_.parallel_for = ctx.thread_pool().as_parallel_for();  // the views are scored at once
#if FBA_GRASP_REACH
    if (ctx(kJointState).connected()) arm_.emplace(ctx);  // before the candidates: reachable_only checks on it too
#endif
    const std::string views = ctx(kViews);
    if (views == "recorded") {
      std::filesystem::path file = ctx(kPosesFrom);
      if (file.is_relative()) file = ctx.task_dir() / file;
      const auto set = fba::vision::ImageSet::load(file.string(), ctx(kGoodOnly));
      for (std::size_t i = 0; i < set.size(); ++i) candidates_.push_back(set[i].camera.camera_from_world.inverse());
      if (candidates_.empty()) throw std::runtime_error("poses_from " + file.string() + ": the image set has no views");
    } else if (const auto c = ctx(kCentre); c.size() == 3) {
      make_candidates(Eigen::Vector3d(c[0], c[1], c[2]));
    } else if (ctx(kStart).connected()) {
      throw std::runtime_error("start is connected but the " + views +
                               " has no centre before a model exists: set centre [x, y, z] or use views: recorded");
    }
  }

  void process() override {
    if (auto o = ctx_(kOctree); o.has()) model_ = o.share();
    if (auto c = ctx_(kCurrent); c.has()) current_ = c.get().world_from_frame;
    if (auto r = ctx_(kRegions); r.has()) pending_ = r.share();
    if (ctx_(kStart).has()) start_asked_ = true;
    if (start_asked_ && !started_) {
#if FBA_GRASP_REACH
      // The moves to the initial views start where the arm stands: its first joint state.
      if (arm_ && !arm_->at_rest(ctx_(kJointState).latest())) return;
#endif
      start();
    }
    if (!pending_ || !model_ || model_->node_count == 0) return;
    // A request counts once it comes from a model with every view asked for: one from an older
    // model does not know the last view yet and is dropped (synthesis sends another per model).
    // Without its model's view count, the latest model's stands for it.
    const int views = pending_->model_views >= 0 ? pending_->model_views : model_->views;
    if (views < requested_) {
      if (pending_->model_views >= 0) pending_.reset();
      return;
    }
    if (model_->views < requested_) return;  // plan on a model that has the view too
#if FBA_GRASP_REACH
    if (arm_ && !arm_->at_last_view(ctx_(kJointState).latest(), last_target_)) return;  // a joint state comes
#endif
    plan(*model_, *pending_);
    pending_.reset();
  }

 private:
  void make_candidates(const Eigen::Vector3d& centre) {
    const double lo = ctx_(kMinElevation) * kDeg, hi = ctx_(kMaxElevation) * kDeg;
    const auto camera_from_world = ctx_(kViews) == "ring"
                                       ? fba::geometry::ring_views(ctx_(kCount), 0.5 * (lo + hi), ctx_(kDistance), centre)
                                       : fba::geometry::hemisphere_views(ctx_(kCount), lo, hi, ctx_(kDistance), centre);
    for (const auto& p : camera_from_world) candidates_.push_back(p.inverse());
#if FBA_GRASP_REACH
    if (ctx_(kReachableOnly)) keep_reachable();
#endif
  }

#if FBA_GRASP_REACH
  // Drops the candidates the arm cannot take: no IK solution for its camera there, within the
  // joint limits, with the arm, the camera and the hand clear of the arm itself and the table (the
  // check sim.arm and hw.canopen_arm make before they move).
  void keep_reachable() {
    std::optional<Arm> own;
    Arm& arm = arm_ ? *arm_ : own.emplace(ctx_);
    arm.robot.set_model(nullptr);  // the candidates are kept for the arm's reach, whatever is seen
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(arm.to_flange.size()));
    std::vector<Eigen::Isometry3d> kept;
    for (const auto& view : candidates_)
      if (arm.to_camera.inverse(view, zero, arm.ik).ok) kept.push_back(view);
    ctx_.log().info("{} of the {} candidate views are within the arm's reach ({})", kept.size(), candidates_.size(), arm.name);
    if (kept.empty())
      throw std::runtime_error("reachable_only: none of the " + std::to_string(candidates_.size()) + " candidate views is within the reach of " +
                               "the arm of " + arm.name + "; move the views (centre, distance, elevations) or the arm");
    candidates_ = std::move(kept);
  }

  // The robot the views are checked on: the arm to its camera and to its flange, the hand open on
  // it, IK solutions accepted clear of the arm itself, the table and (once set) the model.
  struct Arm {
    explicit Arm(const fba::Context& ctx)
        : description(fba::arm::RobotParameters::read(ctx)),
          name(description.name),
          to_camera(fba::arm::ArmModel::from_string(description.urdf, name, "world", "camera")),
          to_flange(fba::arm::ArmModel::from_string(description.urdf, name, "world", "flange")),
          robot(to_flange, fba::motion::urdf_flange_from_palm(description.urdf, name, "world")),
          step(ctx(kMoveStep)) {
      ik.accept = [this](const Eigen::VectorXd& q) { return robot.collision(q); };
    }
    Arm(const Arm&) = delete;  // ik.accept holds `this`
    Arm& operator=(const Arm&) = delete;

    // Whether `state` is the arm standing still (fba::motion::at_rest), taking its joints as where
    // the next move starts.
    bool at_rest(const fba::JointState* state) {
      joints.reset();
      if (!state || !fba::motion::at_rest(*state)) return false;
      std::string why;
      joints = fba::motion::arm_joints(to_camera, *state, why);
      return joints.has_value();
    }

    // Whether `state` is the arm standing still at the view last asked for (its camera within
    // 5 mm and 1 degree of it): the move to the next view starts there.
    bool at_last_view(const fba::JointState* state, const std::optional<Eigen::Isometry3d>& view) {
      if (!at_rest(state) || !view) return false;
      const Eigen::Isometry3d at = to_camera.forward(*joints);
      if ((at.translation() - view->translation()).norm() > 0.005 ||
          Eigen::AngleAxisd(at.linear().transpose() * view->linear()).angle() > kDeg) {
        joints.reset();
        return false;
      }
      return true;
    }

    // The joints to move to for `view` from `joints`, with the straight joint-space motion there
    // clear of the arm itself, the table and `model` (null: none yet); "" when so, else why not.
    std::string move(const Eigen::Isometry3d& view, const std::shared_ptr<const fba::motion::ModelObstacles>& model,
                     Eigen::VectorXd& goal) {
      robot.set_model(model);
      if (model) robot.free_model_at(*joints, true);  // the robot stands there, its hand too: nothing of the object does
      const auto solution = to_camera.inverse(view, *joints, ik);
      if (!solution.ok) return "no IK solution there clear of the arm, the table and the model: " + solution.why;
      goal = solution.joints;
      const std::string hit = fba::motion::motion_collision(
          *joints, goal, step, [this](const Eigen::VectorXd& q) { return robot.collision(q); });
      return hit.empty() ? hit : "the straight motion there: " + hit;
    }

    fba::arm::RobotDescription description;
    std::string name;
    fba::arm::ArmModel to_camera, to_flange;
    fba::motion::RobotCollision robot;
    fba::arm::IkOptions ik;
    double step;
    std::optional<Eigen::VectorXd> joints;  // where the arm stands, at the view last asked for
  };
#endif

  void start() {
    started_ = true;
    const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(initial_views_), candidates_.size());
    auto where = [&](std::size_t i) { return candidates_[i].translation(); };
    std::vector<std::size_t> chosen;
    if (n > 0 && ctx_(kInitialLayout) == "neighbours") {
      // Candidate 0 and its nearest neighbours: a few views close together, as in the paper.
      std::vector<std::size_t> order(candidates_.size());
      for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
      std::stable_sort(order.begin(), order.end(),
                       [&](std::size_t a, std::size_t b) { return (where(a) - where(0)).norm() < (where(b) - where(0)).norm(); });
      chosen.assign(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n));
    } else if (n > 0) {
      // Farthest-point order: each next view the one farthest from every view taken (the first of
      // equals), so that three views stand about a third of a turn apart.
      chosen.push_back(0);
      std::vector<double> nearest(candidates_.size(), std::numeric_limits<double>::infinity());
      while (chosen.size() < n) {
        std::size_t far = 0;
        for (std::size_t i = 0; i < candidates_.size(); ++i) {
          nearest[i] = std::min(nearest[i], (where(i) - where(chosen.back())).norm());
          if (nearest[i] > nearest[far]) far = i;
        }
        chosen.push_back(far);
      }
    }
#if FBA_GRASP_REACH
    if (arm_) return start_moves(chosen);
#endif
    for (std::size_t i : chosen) request(i);
    ctx_.log().info("start: {} initial views requested ({})", n, ctx_(kInitialLayout));
  }

#if FBA_GRASP_REACH
  // The initial views as joints, each move from where the one before ends, clear of the arm itself
  // and the table (no model yet). A view whose move is not clear gives way to the candidate nearest
  // it whose move is.
  void start_moves(const std::vector<std::size_t>& chosen) {
    const std::shared_ptr<const fba::motion::ModelObstacles> none;
    std::string passed, last_why;
    for (std::size_t view : chosen) {
      std::vector<std::size_t> order;
      for (std::size_t i = 0; i < candidates_.size(); ++i)
        if (visited_.size() <= i || !visited_[i]) order.push_back(i);
      const Eigen::Vector3d at = candidates_[view].translation();
      std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return (candidates_[a].translation() - at).norm() < (candidates_[b].translation() - at).norm();
      });
      Eigen::VectorXd goal;
      std::string first_why;
      for (std::size_t i : order) {
        const std::string why = arm_->move(candidates_[i], none, goal);
        if (why.empty()) {
          if (i != view)
            passed += (passed.empty() ? "" : "; ") + ("view " + std::to_string(i) + " for view " + std::to_string(view) + " (" + first_why + ")");
          request(i, &goal);
          arm_->joints = goal;  // the next move starts where this one ends
          break;
        }
        if (first_why.empty()) first_why = why;
        last_why = why;
      }
    }
    if (requested_ == 0) {
      const std::string reason = "the arm cannot reach any candidate view by a clear straight move from where it stands (the last: " + last_why + ")";
      ctx_.log().info("no view: {}", reason);
      ctx_.emit(kNoView, nlohmann::json{{"reason", reason}, {"views_requested", 0}}.dump());
      return;
    }
    ctx_.log().info("start: {} initial views requested ({}){}", requested_, ctx_(kInitialLayout),
                    passed.empty() ? "" : "; in place of views the arm cannot reach by a clear straight move: " + passed);
  }
#endif

  // Asks for the view: its joints on joint_target when given (`joints`), else its camera pose on
  // target.
  void request(std::size_t view, const Eigen::VectorXd* joints = nullptr) {
    if (visited_.size() < candidates_.size()) visited_.resize(candidates_.size(), false);
    visited_[view] = true;
    taken_.push_back(candidates_[view].translation());
    ++requested_;
    last_target_ = candidates_[view];
#if FBA_GRASP_REACH
    if (joints) {
      fba::JointState target;
      target.names = arm_->to_camera.joint_names();
      target.positions.assign(joints->data(), joints->data() + joints->size());
      target.stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
      ctx_(kJointTarget).emit(std::move(target));
      return;
    }
#endif
    (void)joints;
    fba::Pose target;
    target.world_from_frame = candidates_[view];
    target.stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
    ctx_(kTarget).emit(std::move(target));
  }

  void plan(const fba::Octree& model, const fba::RegionsOfInterest& regions) {
    if (candidates_.empty()) make_candidates(model.bounds.center());
    visited_.resize(candidates_.size(), false);
    if (random_) return plan_at_random(model);
    const std::optional<Eigen::Isometry3d> current = current_ ? current_ : last_target_;
    std::vector<bool> excluded = exclude_visited_ ? visited_ : std::vector<bool>(candidates_.size(), false);
    fba::grasp::ViewChoice choice;
    Eigen::VectorXd goal;
    const Eigen::VectorXd* joints = nullptr;
    std::string blocked;  // the views passed over because the move there is not clear, and why
    int passed = 0;
#if FBA_GRASP_REACH
    std::shared_ptr<const fba::motion::ModelObstacles> obstacles;
#endif
    for (;;) {
      choice = fba::grasp::choose_view(model, regions, candidates_, current, excluded, params_, taken_);
      if (!choice.best) break;
#if FBA_GRASP_REACH
      if (arm_) {
        if (!obstacles) obstacles = std::make_shared<const fba::motion::ModelObstacles>(model);
        const std::string why = arm_->move(candidates_[*choice.best], obstacles, goal);
        if (!why.empty()) {
          if (passed++ == 0) blocked = "view " + std::to_string(*choice.best) + ": " + why;
          excluded[*choice.best] = true;
          continue;
        }
        joints = &goal;
      }
#endif
      break;
    }
    if (passed > 0)
      choice.reason += "; passed over " + std::to_string(passed) + " better view" + (passed > 1 ? "s" : "") +
                       " the arm cannot reach by a clear straight move (" + blocked + ")";
    if (!choice.best) {
      ctx_.log().info("no view: {}", choice.reason);
      ctx_.emit(kNoView, nlohmann::json{{"reason", choice.reason}, {"views_requested", requested_}}.dump());
      return;
    }
    const auto& s = choice.scores[*choice.best];
    ctx_.log().info("{}", choice.reason);
    ctx_.emit(kViewChosen, nlohmann::json{{"view", s.index},
                                          {"pose", fba::pose_json(candidates_[s.index])},
                                          {"score", s.score},
                                          {"gain", s.gain},
                                          {"seen", s.seen},
                                          {"targets", choice.targets},
                                          {"by_points", choice.by_points},
                                          {"points", choice.points},
                                          {"pins", s.pins},
                                          {"first", s.first},
                                          {"reason", choice.reason}}
                               .dump());
    request(s.index, joints);
  }

  // The baseline: any view not yet taken, whatever the model and the request say (with the arm's
  // joints, one the arm moves to clear of the model, as for the best).
  void plan_at_random([[maybe_unused]] const fba::Octree& model) {
    std::vector<std::size_t> left;
    for (std::size_t i = 0; i < candidates_.size(); ++i)
      if (!visited_[i]) left.push_back(i);
    const std::size_t not_taken = left.size();
    Eigen::VectorXd goal;
    const Eigen::VectorXd* joints = nullptr;
    int passed = 0;
#if FBA_GRASP_REACH
    std::shared_ptr<const fba::motion::ModelObstacles> obstacles;
#endif
    while (!left.empty()) {
      const std::size_t k = std::uniform_int_distribution<std::size_t>(0, left.size() - 1)(draws_);
      const std::size_t view = left[k];
#if FBA_GRASP_REACH
      if (arm_) {
        if (!obstacles) obstacles = std::make_shared<const fba::motion::ModelObstacles>(model);
        if (!arm_->move(candidates_[view], obstacles, goal).empty()) {
          ++passed;
          left.erase(left.begin() + static_cast<std::ptrdiff_t>(k));
          continue;
        }
        joints = &goal;
      }
#endif
      std::string reason = "view " + std::to_string(view) + " drawn at random of the " + std::to_string(not_taken) + " not taken";
      if (passed > 0) reason += " (" + std::to_string(passed) + " drawn before it the arm cannot reach by a clear straight move)";
      ctx_.log().info("{}", reason);
      ctx_.emit(kViewChosen, nlohmann::json{{"view", view}, {"pose", fba::pose_json(candidates_[view])}, {"reason", reason}}.dump());
      request(view, joints);
      return;
    }
    const std::string reason = passed == 0 ? "every one of the " + std::to_string(candidates_.size()) + " candidate views is taken"
                                           : "the arm cannot reach any of the " + std::to_string(not_taken) +
                                                 " candidate views not taken by a clear straight move";
    ctx_.log().info("no view: {}", reason);
    ctx_.emit(kNoView, nlohmann::json{{"reason", reason}, {"views_requested", requested_}}.dump());
  }

  fba::Context& ctx_;
  fba::grasp::ExplorationParams params_;
  const int initial_views_;
  const bool exclude_visited_;
  const bool random_;     // next_view: random
  std::mt19937 draws_;    // its draws, from seed
  std::vector<Eigen::Isometry3d> candidates_;  // world_from_camera
  std::vector<bool> visited_;                  // per candidate: already requested
  std::vector<Eigen::Vector3d> taken_;         // the requested views' camera centres, in order
  std::shared_ptr<const fba::Octree> model_;
  std::shared_ptr<const fba::RegionsOfInterest> pending_;
  std::optional<Eigen::Isometry3d> current_, last_target_;
  int requested_ = 0;
  bool start_asked_ = false, started_ = false;
#if FBA_GRASP_REACH
  std::optional<Arm> arm_;  // with joint_state: the moves to the views are checked on it
#endif
};

}  // namespace

FBA_COMPONENT(ExplorationPlanner);
