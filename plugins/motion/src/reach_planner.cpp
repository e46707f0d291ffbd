#include "fba/motion/reach_planner.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <utility>

#include "fba/motion/hand_placement.hpp"
#include "fba/motion/joint_path.hpp"
#include "fba/motion/robot_collision.hpp"
#include "text.hpp"

namespace fba::motion {

namespace {

using text::format;

// "palm touches the table" -> "the palm into the table", for "the pregrasp puts ...".
std::string into(const std::string& contact) {
  const auto k = contact.find(" touches ");
  if (k == std::string::npos) return contact;
  return "the " + contact.substr(0, k) + " into " + contact.substr(k + 9);
}

ReachPlan refuse(ReachPlan plan, Refusal r, std::string why) {
  plan.ok = false;
  plan.refusal = r;
  plan.why = std::move(why);
  return plan;
}

void check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("reach planner: " + what);
}

// The timed trajectory, built motion by motion: each motion a synchronised trapezoid from rest to
// rest (arm::JointTrajectory), sampled every period and at its end.
class TrajectoryBuilder {
 public:
  TrajectoryBuilder(const Eigen::VectorXd& start, Eigen::VectorXd max_velocity, Eigen::VectorXd max_acceleration, double period,
                    fba::JointTrajectory& out)
      : vmax_(std::move(max_velocity)), amax_(std::move(max_acceleration)), period_(period), out_(out), last_(start) {
    add(0, start, Eigen::VectorXd::Zero(start.size()));
  }
  double now() const { return now_; }

  void move_to(const Eigen::VectorXd& goal) {
    const arm::JointTrajectory motion(last_, goal, vmax_, amax_);
    if (motion.duration() <= 0) return;
    const int n = std::max(1, static_cast<int>(std::ceil(motion.duration() / period_ - 1e-9)));
    Eigen::VectorXd q, v;
    for (int k = 1; k <= n; ++k) {
      const double t = motion.duration() * k / n;
      motion.sample(t, q, v);
      add(now_ + t, q, v);
    }
    now_ += motion.duration();
    last_ = goal;
  }
  void through(const std::vector<Eigen::VectorXd>& waypoints) {
    for (const auto& q : waypoints) move_to(q);
  }
  void wait(double seconds) {
    if (seconds <= 0) return;
    now_ += seconds;
    add(now_, last_, Eigen::VectorXd::Zero(last_.size()));
  }

 private:
  void add(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
    out_.points.push_back({t, {q.data(), q.data() + q.size()}, {v.data(), v.data() + v.size()}});
  }
  Eigen::VectorXd vmax_, amax_;
  double period_;
  fba::JointTrajectory& out_;
  Eigen::VectorXd last_;
  double now_ = 0;
};

}  // namespace

const char* to_string(Refusal r) {
  switch (r) {
    case Refusal::None: return "none";
    case Refusal::Hand: return "hand";
    case Refusal::Table: return "table";
    case Refusal::Ik: return "ik";
    case Refusal::Collision: return "collision";
    case Refusal::Approach: return "approach";
    case Refusal::Lift: return "lift";
    case Refusal::Start: return "start";
    case Refusal::Path: return "path";
  }
  return "?";
}

struct ReachPlanner::Impl {
  arm::ArmModel arm;
  ReachParams params;
  Eigen::VectorXd max_velocity, max_acceleration;

  Impl(arm::ArmModel a, const ReachParams& p) : arm(std::move(a)), params(p) {
    check(p.standoff >= 0 && std::isfinite(p.standoff), "standoff must be >= 0, found " + format("%g", p.standoff));
    check(p.lift_height >= 0 && std::isfinite(p.lift_height), "lift_height must be >= 0, found " + format("%g", p.lift_height));
    check(p.hold_s >= 0 && p.hand_s >= 0, "hold_s and hand_s must be >= 0");
    check(p.clearance >= 0 && p.contact_allowance >= 0, "clearance and contact_allowance must be >= 0");
    check(p.planning_time > 0, "planning_time must be > 0, found " + format("%g", p.planning_time));
    check(p.path_checks > 0, "path_checks must be > 0, found 0");
    check(p.ik_attempts >= 1, "ik_attempts must be >= 1");
    check(p.cartesian_step > 0 && p.max_joint_step > 0 && p.collision_step > 0,
          "cartesian_step, max_joint_step and collision_step must be > 0");
    check(p.speed_scale > 0 && p.speed_scale <= 1, "speed_scale must be in (0, 1], found " + format("%g", p.speed_scale));
    check(p.acceleration > 0 && p.sample_period > 0, "acceleration and sample_period must be > 0");
    check(p.max_backout >= 0 && std::isfinite(p.max_backout), "max_backout must be >= 0, found " + format("%g", p.max_backout));
    check(p.jiggle_share >= 0 && p.jiggle_share <= 1, "jiggle_share must be in [0, 1], found " + format("%g", p.jiggle_share));
    const auto n = static_cast<Eigen::Index>(arm.size());
    max_velocity.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) max_velocity(i) = arm.limits()[static_cast<std::size_t>(i)].velocity * p.speed_scale;
    max_acceleration = Eigen::VectorXd::Constant(n, p.acceleration);
    RobotCollision probe(arm, p.flange_from_palm);  // refuses shapes it cannot check, now rather than per grasp
  }

  std::function<std::string(const Eigen::VectorXd&)> checker(RobotCollision& robot) const {
    return [&robot](const Eigen::VectorXd& q) { return robot.collision(q); };
  }

  // IK solutions every cartesian_step along the straight line between two palm poses of the same
  // orientation, from q0 (which reaches `from`), each motion between two of them free. Returns
  // why not, or "" with `path` filled (q0 first). With `done`, the line ends at the first
  // solution it accepts.
  std::string line(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to, const Eigen::VectorXd& q0, RobotCollision& robot,
                   std::vector<Eigen::VectorXd>& path, ReachFigures& figures,
                   const std::function<bool(const Eigen::VectorXd&)>& done = {}) const {
    const Eigen::Vector3d d = to.translation() - from.translation();
    const int n = std::max(1, static_cast<int>(std::ceil(d.norm() / params.cartesian_step - 1e-9)));
    path = {q0};
    arm::IkOptions ik;
    ik.attempts = 1;  // from the last solution only: a line, not a jump to another branch
    const auto collision = checker(robot);
    for (int k = 1; k <= n; ++k) {
      Eigen::Isometry3d palm = from;
      palm.translation() += d * (double(k) / n);
      const double in = d.norm() * k / n;
      const auto s = arm.inverse(palm * params.flange_from_palm.inverse(), path.back(), ik);
      figures.ik_attempts += s.attempts;
      if (!s.ok) return "no IK solution " + format("%.3f m", in) + " along it: " + s.why;
      const Eigen::Index j = [&] {
        Eigen::Index i = 0;
        (s.joints - path.back()).cwiseAbs().maxCoeff(&i);
        return i;
      }();
      const double jump = s.joints(j) - path.back()(j);
      if (std::abs(jump) > params.max_joint_step) {
        const std::string joint = "joint '" + arm.joint_names()[static_cast<std::size_t>(j)] + "'";
        // A whole turn: the same angle, which the line would reach only past the joint's limit.
        const double turns = std::round(jump / (2 * M_PI));
        if (turns != 0 && std::abs(jump - turns * 2 * M_PI) <= params.max_joint_step)
          return joint + " would pass its limit, to " + format("%.2f rad", s.joints(j) - turns * 2 * M_PI) + ", " +
                 format("%.3f m", in) + " along it";
        return joint + " would jump " + format("%.2f rad", std::abs(jump)) + " " + format("%.3f m", in) +
               " along it (a singularity or a flip)";
      }
      if (std::string c = motion_collision(path.back(), s.joints, params.collision_step, collision, &figures.collision_checks);
          !c.empty())
        return c + ", " + format("%.3f m", in) + " along it";
      path.push_back(s.joints);
      if (done && done(s.joints)) return {};
    }
    return {};
  }

  // The start's hand is in the model: back out, in straight steps checked against the table and
  // the arm itself (the model's leaves the hand is in lie on the way out), until a pose clear of
  // everything, within max_backout: along the flange's -z axis (the wrist camera's line of sight,
  // backwards), else, where the arm cannot go that way (a view on the far side of the object
  // stretches it towards the end of its reach), straight up, else by joints alone (jiggle: at the
  // end of its reach the arm can still fold back). Returns why not, or "" with `path` filled (the
  // current joints first, the clear pose last). `robot` checks the model again after.
  std::string back_out(const Eigen::VectorXd& current, RobotCollision& robot, std::vector<Eigen::VectorXd>& path,
                       ReachFigures& figures) const {
    const Eigen::Isometry3d flange = arm.forward(current);
    const Eigen::Isometry3d palm = flange * params.flange_from_palm;
    const Eigen::Vector3d back = -flange.linear().col(2);
    std::string why;
    for (const auto& [way, direction] : {std::pair{"along the flange's axis", back}, std::pair{"straight up", Eigen::Vector3d::UnitZ().eval()}}) {
      if (!why.empty() && back.dot(direction) > std::cos(M_PI / 180)) break;  // the same way again
      const Eigen::Isometry3d out = Eigen::Translation3d(params.max_backout * direction) * palm;
      std::string still;  // what the last pose reached still touches
      auto clear = [&](const Eigen::VectorXd& q) {
        robot.check_model(true);
        still = robot.collision(q);
        robot.check_model(false);
        return still.empty();
      };
      robot.check_model(false);
      std::string failed = line(palm, out, current, robot, path, figures, clear);
      robot.check_model(true);
      if (failed.empty() && still.empty()) return {};
      if (failed.empty()) failed = text::metres(params.max_backout) + " back (max_backout), it still puts " + into(still);
      why += std::string(why.empty() ? "" : "; ") + way + ": " + failed;
    }
    if (std::string failed = jiggle(current, robot, path, figures); !failed.empty()) {
      path.clear();
      return why + "; by joints alone: " + failed;
    }
    return {};
  }

  // As MoveIt's FixStartStateCollision: joint positions drawn around the current ones, each joint
  // within a share of its range that grows with the draws up to jiggle_share, the first one clear of
  // everything whose straight joint motion from the current joints is clear of the table and the
  // arm itself (the model off, as on the lines above). Returns why not, or "" with `path` the two.
  std::string jiggle(const Eigen::VectorXd& current, RobotCollision& robot, std::vector<Eigen::VectorXd>& path,
                     ReachFigures& figures) const {
    if (params.jiggle_draws == 0) return "not tried (jiggle_draws 0)";
    std::mt19937_64 random(params.seed);  // the same way out on every run
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const auto collision = checker(robot);
    std::string last;
    for (std::size_t k = 1; k <= params.jiggle_draws; ++k) {
      const double share = params.jiggle_share * double(k) / double(params.jiggle_draws);
      Eigen::VectorXd q = current;
      for (Eigen::Index i = 0; i < q.size(); ++i) {
        const arm::JointLimits& l = arm.limits()[static_cast<std::size_t>(i)];
        const double range = std::isfinite(l.upper - l.lower) ? l.upper - l.lower : 2 * M_PI;
        q(i) = std::clamp(current(i) + share * range * unit(random), l.lower, l.upper);
      }
      ++figures.collision_checks;
      if (std::string c = robot.collision(q); !c.empty()) {
        last = c;
        continue;
      }
      robot.check_model(false);
      last = motion_collision(current, q, params.collision_step, collision, &figures.collision_checks);
      robot.check_model(true);
      if (!last.empty()) continue;
      path = {current, q};
      return {};
    }
    return "none of " + std::to_string(params.jiggle_draws) + " joint positions within " +
           format("%.0f%%", 100 * params.jiggle_share) + " of each joint's range is clear (the last: " + last + ")";
  }
};

ReachPlanner::ReachPlanner(const std::filesystem::path& urdf, const ReachParams& params, const std::string& base_link,
                           const std::string& flange_link)
    : ReachPlanner(arm::ArmModel(urdf, base_link, flange_link), params) {}
ReachPlanner::ReachPlanner(arm::ArmModel arm, const ReachParams& params) : impl_(std::make_unique<Impl>(std::move(arm), params)) {}
ReachPlanner::~ReachPlanner() = default;
ReachPlanner::ReachPlanner(ReachPlanner&&) noexcept = default;
ReachPlanner& ReachPlanner::operator=(ReachPlanner&&) noexcept = default;

const arm::ArmModel& ReachPlanner::arm() const { return impl_->arm; }
const ReachParams& ReachPlanner::params() const { return impl_->params; }

std::shared_ptr<const ModelObstacles> ReachPlanner::obstacles(const Octree& model) {
  return std::make_shared<const ModelObstacles>(model);
}

ReachPlan ReachPlanner::reachable(const Grasp& grasp, const Octree& model, const Eigen::VectorXd& current) const {
  return reachable(grasp, obstacles(model), current);
}

ReachPlan ReachPlanner::plan(const Grasp& grasp, const Octree& model, const Eigen::VectorXd& current) const {
  return plan(grasp, obstacles(model), current);
}

ReachPlan ReachPlanner::reachable(const Grasp& grasp, std::shared_ptr<const ModelObstacles> model,
                                  const Eigen::VectorXd& current) const {
  const Impl& s = *impl_;
  const ReachParams& p = s.params;
  ReachPlan plan;
  if (const std::string bad = s.arm.limit_violation(current); !bad.empty())
    return refuse(std::move(plan), Refusal::Start, "the current joints are not usable: " + bad);

  const HandPlacement hand = place_hand(grasp, p.clearance);
  if (!hand.why.empty()) return refuse(std::move(plan), Refusal::Hand, "the hand cannot take the grasp: " + hand.why);
  plan.opening = hand.opening;
  plan.width = hand.width;
  plan.spread = hand.spread;
  plan.grasp_palm = hand.world_from_palm;
  const Eigen::Vector3d approach = hand.world_from_palm.linear().col(2);
  plan.pregrasp_palm = Eigen::Translation3d(-approach * p.standoff) * plan.grasp_palm;
  plan.lift_palm = Eigen::Translation3d(Eigen::Vector3d::UnitZ() * p.lift_height) * plan.grasp_palm;

  RobotCollision robot(s.arm, p.flange_from_palm);
  robot.set_hand(hand.opening, hand.spread);
  const std::array<Eigen::Vector3d, 3> contacts{grasp.contacts[0].position, grasp.contacts[1].position, grasp.contacts[2].position};
  robot.set_model(model, contacts, p.contact_allowance);
  robot.free_model_at(current);

  // The hand opens for the pregrasp where the arm stands; where it would touch the model (at a
  // view pose, space not yet carved), the arm first backs out of it along the flange's axis.
  plan.start_joints = current;
  if (std::string c = p.check_start ? robot.collision(current) : std::string(); !c.empty()) {
    robot.check_model(false);
    const std::string fixed = robot.collision(current);  // the table or the arm itself: no way out
    robot.check_model(true);
    if (!fixed.empty() || p.max_backout <= 0)
      return refuse(std::move(plan), Refusal::Start,
                    "the current joints collide, with the hand open for the pregrasp: " + (fixed.empty() ? c : fixed));
    if (std::string why = s.back_out(current, robot, plan.backout_path, plan.figures); !why.empty())
      return refuse(std::move(plan), Refusal::Start,
                    "the current joints put " + into(c) + " (the hand open for the pregrasp), and backing out of it fails: " + why);
    plan.start_joints = plan.backout_path.back();
    plan.figures.backout = (s.arm.forward(plan.start_joints).translation() - s.arm.forward(current).translation()).norm();
  }

  // The hand alone, open, at the pregrasp and at the grasp: the table, then the model.
  for (const auto& [name, palm] : {std::pair{"pregrasp", plan.pregrasp_palm}, std::pair{"grasp", plan.grasp_palm}}) {
    const std::string hit = robot.hand_collision(palm);
    if (hit.empty()) continue;
    const bool table = hit.find("the table") != std::string::npos;
    const bool pregrasp = std::string(name) == "pregrasp";
    plan.model_blocked = robot.model_hit();
    return refuse(std::move(plan), table ? Refusal::Table : pregrasp ? Refusal::Collision : Refusal::Approach,
                  std::string("the ") + name + " puts " + into(hit));
  }

  // The pregrasp's IK solution nearest the current joints from which the straight approach and
  // the straight lift work too: the nearest alone may lie at a joint's limit the lines cross.
  const auto collision = s.checker(robot);
  std::vector<Eigen::VectorXd> approach_path, lift_path;
  struct Lines {
    Eigen::VectorXd pregrasp;
    std::vector<Eigen::VectorXd> approach, lift;
  };
  std::vector<Lines> accepted;
  Refusal first = Refusal::None;  // why the first solution refused was
  bool first_model = false;       // and whether the model refused it
  auto lines = [&](const Eigen::VectorXd& q) {
    auto no = [&](Refusal r, std::string why) {
      if (first == Refusal::None) first = r, first_model = robot.model_hit();
      return why;
    };
    if (p.first_solution && !accepted.empty()) return std::string("one solution is enough");
    robot.set_hand(hand.opening, hand.spread);
    robot.check_model(true);
    if (std::string c = collision(q); !c.empty()) return no(Refusal::Collision, c);
    if (std::string why = s.line(plan.pregrasp_palm, plan.grasp_palm, q, robot, approach_path, plan.figures); !why.empty())
      return no(Refusal::Approach, "the straight approach fails: " + why);
    // The fingers closed on the object, which now moves with the hand.
    robot.set_hand(hand.width, hand.spread);
    robot.check_model(false);
    if (std::string why = s.line(plan.grasp_palm, plan.lift_palm, approach_path.back(), robot, lift_path, plan.figures); !why.empty())
      return no(Refusal::Lift, "the straight lift fails: " + why);
    accepted.push_back({q, approach_path, lift_path});
    return std::string();
  };
  arm::IkOptions ik;
  ik.attempts = p.ik_attempts;
  ik.seed = p.seed;
  ik.accept = lines;
  const auto pregrasp = s.arm.inverse(plan.pregrasp_palm * p.flange_from_palm.inverse(), plan.start_joints, ik);
  plan.figures.ik_attempts += pregrasp.attempts;
  if (!pregrasp.ok) {
    const std::string refused = "every solution found is refused: ";  // arm::ArmModel::inverse's words for `accept`
    const std::string at = text::point(plan.pregrasp_palm.translation()) + ", approach " + text::point(approach);
    if (pregrasp.why.rfind(refused, 0) == 0) {
      plan.model_blocked = first_model;
      return refuse(std::move(plan), first,
                    "every IK solution for the pregrasp at " + at + " fails, the first: " + pregrasp.why.substr(refused.size()));
    }
    return refuse(std::move(plan), Refusal::Ik, "no IK solution within the joint limits for the pregrasp at " + at + ": " + pregrasp.why);
  }
  for (Lines& l : accepted)
    if (l.pregrasp == pregrasp.joints) {
      plan.approach_path = std::move(l.approach);
      plan.lift_path = std::move(l.lift);
    }
  plan.pregrasp_joints = pregrasp.joints;
  plan.grasp_joints = plan.approach_path.back();
  plan.lift_joints = plan.lift_path.back();
  plan.ok = true;
  return plan;
}

ReachPlan ReachPlanner::plan(const Grasp& grasp, std::shared_ptr<const ModelObstacles> model, const Eigen::VectorXd& current) const {
  const Impl& s = *impl_;
  const ReachParams& p = s.params;
  ReachPlan plan = reachable(grasp, model, current);
  if (!plan.ok) return plan;

  // From the current joints (or where the back-out ends) to the standoff, the hand open for the
  // pregrasp.
  RobotCollision robot(s.arm, p.flange_from_palm);
  robot.set_hand(plan.opening, plan.spread);
  const std::array<Eigen::Vector3d, 3> contacts{grasp.contacts[0].position, grasp.contacts[1].position, grasp.contacts[2].position};
  robot.set_model(std::move(model), contacts, p.contact_allowance);
  robot.free_model_at(current);
  const JointPath path = plan_joint_path(plan.start_joints, plan.pregrasp_joints, s.arm.limits(), s.checker(robot),
                                         JointPathOptions{p.path_checks, p.planning_time, p.collision_step, p.seed});
  plan.figures.planning_s = path.planning_s;
  plan.figures.direct = path.direct;
  plan.figures.collision_checks += path.checks;
  if (!path.ok) return refuse(std::move(plan), Refusal::Path, path.why);
  plan.figures.path_waypoints = path.waypoints.size();
  for (std::size_t i = 1; i < path.waypoints.size(); ++i) plan.figures.path_length += (path.waypoints[i] - path.waypoints[i - 1]).norm();

  // The timeline: each step's motions, the hand's commands at the times the arm waits for them.
  plan.trajectory.names = s.arm.joint_names();
  TrajectoryBuilder t(current, s.max_velocity, s.max_acceleration, p.sample_period, plan.trajectory);
  auto hand = [&](HandCommand::Action action) {
    HandCommand c;
    c.action = action;
    c.opening = plan.opening;
    c.spread = plan.spread;
    c.force = action == HandCommand::Action::Close ? p.finger_force : 0.0;
    c.time = t.now();
    plan.hand.push_back(c);
    t.wait(p.hand_s);
  };
  auto step = [&](const char* name, const std::function<void()>& motions) {
    const double start = t.now();
    motions();
    plan.steps.push_back({name, start, t.now()});
  };
  step("plan", [&] {
    t.through(plan.backout_path);  // out of the model first: the hand opens where it is clear
    hand(HandCommand::Action::Open);
    t.through(path.waypoints);
  });
  step("approach", [&] { t.through(plan.approach_path); });
  step("close", [&] { hand(HandCommand::Action::Close); });
  step("lift", [&] { t.through(plan.lift_path); });
  step("hold", [&] { t.wait(p.hold_s); });
  if (p.retreat)
    step("retreat", [&] {
      t.through({plan.lift_path.rbegin(), plan.lift_path.rend()});
      hand(HandCommand::Action::Open);
      t.through({plan.approach_path.rbegin(), plan.approach_path.rend()});
    });
  return plan;
}

}  // namespace fba::motion
