#include "arm_model.hpp"
#include "urdf_text.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <mutex>
#include <random>
#include <sstream>

#include <console_bridge/console.h>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

namespace fba::arm {

namespace {

constexpr double kTwoPi = 2.0 * M_PI;

std::string number(double x) {
  std::ostringstream s;
  s.precision(6);
  s << x;
  return s.str();
}

// urdfdom reports why a file does not parse through console_bridge, as log lines on stderr; this
// collects them for the error message instead. console_bridge's handler is process-wide, hence
// the lock.
class CollectMessages final : public console_bridge::OutputHandler {
 public:
  CollectMessages() : lock_(mutex()), previous_(console_bridge::getOutputHandler()) { console_bridge::useOutputHandler(this); }
  ~CollectMessages() override { console_bridge::useOutputHandler(previous_); }
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) text_ += (text_.empty() ? "" : "; ") + text;
  }
  const std::string& text() const { return text_; }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  console_bridge::OutputHandler* previous_;
  std::string text_;
};

Eigen::Isometry3d to_eigen(const KDL::Frame& f) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) t.linear()(r, c) = f.M(r, c);
    t.translation()(r) = f.p(r);
  }
  return t;
}

KDL::Frame to_kdl(const Eigen::Isometry3d& t) {
  const Eigen::Matrix3d& m = t.linear();
  return KDL::Frame(KDL::Rotation(m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2)),
                    KDL::Vector(t.translation().x(), t.translation().y(), t.translation().z()));
}

KDL::JntArray to_kdl(const Eigen::VectorXd& q) {
  KDL::JntArray a(static_cast<unsigned>(q.size()));
  a.data = q;
  return a;
}

}  // namespace

double angle_between(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

struct ArmModel::Impl {
  std::string origin, base, tip;
  KDL::Chain chain;
  std::vector<std::string> names;
  std::vector<JointLimits> limits;
  std::vector<bool> revolute;  // a revolute or continuous joint: positions equal modulo 2 pi
  std::vector<std::string> links;  // each segment's child link
  std::vector<CollisionShape> shapes;
};

namespace {

Eigen::Isometry3d to_eigen(const urdf::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  t.translation() << p.position.x, p.position.y, p.position.z;
  return t;
}

// Whether a movable joint lies beyond `link`: it is the base of another mechanism (the hand).
bool carries_joints(const urdf::Link& link) {
  for (const auto& j : link.child_joints)
    if (j && j->type != urdf::Joint::FIXED) return true;
  for (const auto& child : link.child_links)
    if (child && carries_joints(*child)) return true;
  return false;
}

// The <collision> shapes of `link` and of the links fixed to it off the chain, placed in the frame
// of the chain link they move with; not those of a mechanism mounted there (carries_joints).
void add_shapes(const urdf::Link& link, const Eigen::Isometry3d& frame_from_link, std::size_t frame, std::size_t joints_before,
                const std::vector<std::string>& chain_links, std::vector<CollisionShape>& out) {
  for (const auto& c : link.collision_array) {
    if (!c || !c->geometry) continue;
    CollisionShape s;
    s.link = link.name;
    s.frame = frame;
    s.joints_before = joints_before;
    s.frame_from_shape = frame_from_link * to_eigen(c->origin);
    switch (c->geometry->type) {
      case urdf::Geometry::BOX: {
        const auto& d = static_cast<const urdf::Box&>(*c->geometry).dim;
        s.kind = CollisionShape::Kind::Box;
        s.size << d.x, d.y, d.z;
        break;
      }
      case urdf::Geometry::CYLINDER: {
        const auto& g = static_cast<const urdf::Cylinder&>(*c->geometry);
        s.kind = CollisionShape::Kind::Cylinder;
        s.size << g.radius, g.length, 0;
        break;
      }
      case urdf::Geometry::SPHERE:
        s.kind = CollisionShape::Kind::Sphere;
        s.size << static_cast<const urdf::Sphere&>(*c->geometry).radius, 0, 0;
        break;
      case urdf::Geometry::MESH:
        s.kind = CollisionShape::Kind::Mesh;
        s.mesh = static_cast<const urdf::Mesh&>(*c->geometry).filename;
        break;
    }
    out.push_back(std::move(s));
  }
  for (const auto& j : link.child_joints) {
    if (!j || j->type != urdf::Joint::FIXED) continue;
    if (std::find(chain_links.begin(), chain_links.end(), j->child_link_name) != chain_links.end()) continue;
    for (const auto& child : link.child_links)
      if (child && child->name == j->child_link_name && !carries_joints(*child))
        add_shapes(*child, frame_from_link * to_eigen(j->parent_to_joint_origin_transform), frame, joints_before, chain_links, out);
  }
}

}  // namespace

ArmModel::ArmModel(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ArmModel::ArmModel(ArmModel&&) noexcept = default;
ArmModel& ArmModel::operator=(ArmModel&&) noexcept = default;
ArmModel::~ArmModel() = default;

ArmModel::ArmModel(const std::filesystem::path& urdf, const std::string& base_link, const std::string& tip_link) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(urdf, ec))
    throw ArmModelError("URDF " + urdf.string() + (std::filesystem::exists(urdf, ec) ? " is not a regular file" : " does not exist"));
  std::ifstream in(urdf, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw ArmModelError("cannot read URDF " + urdf.string());
  *this = from_string(text.str(), urdf.string(), base_link, tip_link);
}

ArmModel ArmModel::from_string(const std::string& xml, const std::string& origin, const std::string& base_link,
                               const std::string& tip_link) {
  std::string problem;
  const urdf::ModelInterfaceSharedPtr model = parse_urdf(xml, problem);
  if (!model) throw ArmModelError("URDF " + origin + " does not parse: " + problem);
  std::vector<urdf::LinkSharedPtr> links;
  model->getLinks(links);
  for (const std::string& name : {base_link, tip_link}) {
    if (model->getLink(name)) continue;
    std::string list;
    for (const auto& l : links) list += (list.empty() ? "" : ", ") + l->name;
    throw ArmModelError("no link '" + name + "' in " + origin + "; links: " + list);
  }
  KDL::Tree tree;
  if (!kdl_parser::treeFromUrdfModel(*model, tree)) throw ArmModelError("URDF " + origin + ": kdl_parser cannot build a kinematic tree from it");
  auto impl = std::make_unique<Impl>();
  impl->origin = origin;
  impl->base = base_link;
  impl->tip = tip_link;
  if (!tree.getChain(base_link, tip_link, impl->chain))
    throw ArmModelError("no kinematic chain from '" + base_link + "' to '" + tip_link + "' in " + origin);
  for (unsigned i = 0; i < impl->chain.getNrOfSegments(); ++i) {
    const KDL::Joint& j = impl->chain.getSegment(i).getJoint();
    if (j.getType() == KDL::Joint::Fixed) continue;
    const auto joint = model->getJoint(j.getName());
    if (!joint) throw ArmModelError("URDF " + origin + ": KDL names a joint '" + j.getName() + "' the URDF does not have");
    JointLimits l;
    const bool continuous = joint->type == urdf::Joint::CONTINUOUS;
    if (!continuous && !joint->limits)
      throw ArmModelError("URDF " + origin + ": joint '" + joint->name + "' has no <limit>; every movable joint of an arm needs one");
    l.lower = continuous ? -std::numeric_limits<double>::infinity() : joint->limits->lower;
    l.upper = continuous ? std::numeric_limits<double>::infinity() : joint->limits->upper;
    l.velocity = joint->limits ? joint->limits->velocity : 0.0;
    if (!(l.velocity > 0))
      throw ArmModelError("URDF " + origin + ": joint '" + joint->name + "' has no velocity limit (<limit velocity> must be > 0)");
    if (!(l.lower <= l.upper))
      throw ArmModelError("URDF " + origin + ": joint '" + joint->name + "' has lower limit " + number(l.lower) + " above upper " +
                          number(l.upper));
    impl->names.push_back(joint->name);
    impl->limits.push_back(l);
    impl->revolute.push_back(joint->type == urdf::Joint::REVOLUTE || continuous);
  }
  if (impl->names.empty())
    throw ArmModelError("no movable joint between '" + base_link + "' and '" + tip_link + "' in " + origin);
  // The collision shapes of the chain's links, each in the frame of the link it moves with.
  for (unsigned i = 0; i < impl->chain.getNrOfSegments(); ++i) impl->links.push_back(impl->chain.getSegment(i).getName());
  std::size_t joints = 0;
  for (unsigned i = 0; i < impl->chain.getNrOfSegments(); ++i) {
    if (impl->chain.getSegment(i).getJoint().getType() != KDL::Joint::Fixed) ++joints;
    if (const auto link = model->getLink(impl->links[i]))
      add_shapes(*link, Eigen::Isometry3d::Identity(), i, joints, impl->links, impl->shapes);
  }
  return ArmModel(std::move(impl));
}

const std::string& ArmModel::base_link() const { return impl_->base; }
const std::vector<std::string>& ArmModel::link_names() const { return impl_->links; }
const std::vector<CollisionShape>& ArmModel::collision_shapes() const { return impl_->shapes; }

const std::string& ArmModel::tip_link() const { return impl_->tip; }
const std::vector<std::string>& ArmModel::joint_names() const { return impl_->names; }
const std::vector<JointLimits>& ArmModel::limits() const { return impl_->limits; }

std::vector<Eigen::Isometry3d> ArmModel::link_poses(const Eigen::VectorXd& joints) const {
  if (static_cast<std::size_t>(joints.size()) != size())
    throw std::invalid_argument("link poses: " + std::to_string(joints.size()) + " joint positions given, the arm has " +
                                std::to_string(size()));
  KDL::ChainFkSolverPos_recursive fk(impl_->chain);
  std::vector<KDL::Frame> frames(impl_->chain.getNrOfSegments());
  fk.JntToCart(to_kdl(joints), frames);
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(frames.size());
  for (const KDL::Frame& f : frames) poses.push_back(to_eigen(f));
  return poses;
}

Eigen::Isometry3d ArmModel::forward(const Eigen::VectorXd& joints) const {
  if (static_cast<std::size_t>(joints.size()) != size())
    throw std::invalid_argument("forward kinematics: " + std::to_string(joints.size()) + " joint positions given, the arm has " +
                                std::to_string(size()));
  KDL::ChainFkSolverPos_recursive fk(impl_->chain);
  KDL::Frame f;
  fk.JntToCart(to_kdl(joints), f);
  return to_eigen(f);
}

std::string ArmModel::limit_violation(const Eigen::VectorXd& joints) const {
  if (static_cast<std::size_t>(joints.size()) != size())
    return std::to_string(joints.size()) + " joint positions given, the arm has " + std::to_string(size());
  for (std::size_t i = 0; i < size(); ++i) {
    const JointLimits& l = impl_->limits[i];
    const double q = joints(static_cast<Eigen::Index>(i));
    if (!std::isfinite(q) || q < l.lower || q > l.upper)
      return "joint '" + impl_->names[i] + "' at " + number(q) + (impl_->revolute[i] ? " rad" : " m") + " is outside [" +
             number(l.lower) + ", " + number(l.upper) + "]";
  }
  return {};
}

IkResult ArmModel::inverse(const Eigen::Isometry3d& base_from_tip, const Eigen::VectorXd& seed, const IkOptions& options) const {
  const auto n = static_cast<Eigen::Index>(size());
  if (seed.size() != n)
    throw std::invalid_argument("inverse kinematics: a seed of " + std::to_string(seed.size()) + " joints, the arm has " +
                                std::to_string(n));
  // Orientation weighted like 10 cm per radian: both matter to where the camera looks.
  Eigen::Matrix<double, 6, 1> weights;
  weights << 1, 1, 1, 0.1, 0.1, 0.1;
  KDL::ChainIkSolverPos_LMA solver(impl_->chain, weights, 1e-10, 500);
  const KDL::Frame goal = to_kdl(base_from_tip);
  std::mt19937_64 random(options.seed);

  // Time to move there from the seed at full speed: the measure of "nearest".
  auto motion_time = [&](const Eigen::VectorXd& q) {
    double t = 0;
    for (Eigen::Index i = 0; i < n; ++i) t = std::max(t, std::abs(q(i) - seed(i)) / impl_->limits[i].velocity);
    return t;
  };
  // A revolute joint's position modulo 2 pi: the equivalent value within the limits nearest the seed.
  auto wrap = [&](Eigen::VectorXd& q) {
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!impl_->revolute[i]) continue;
      const JointLimits& l = impl_->limits[i];
      double best = q(i);
      bool inside = best >= l.lower && best <= l.upper;
      const double base = q(i) + kTwoPi * std::round((seed(i) - q(i)) / kTwoPi);
      for (int k = -2; k <= 2; ++k) {
        const double c = base + k * kTwoPi;
        if (c < l.lower || c > l.upper) continue;
        if (!inside || std::abs(c - seed(i)) < std::abs(best - seed(i))) best = c;
        inside = true;
      }
      q(i) = best;
    }
  };

  IkResult best;
  double best_score = std::numeric_limits<double>::infinity();  // of an attempt that is not a solution
  bool found = false;
  double found_time = 0;
  int made = 0;
  for (int attempt = 0; attempt < std::max(1, options.attempts); ++attempt) {
    made = attempt + 1;
    Eigen::VectorXd start(n);
    if (attempt == 0) {
      start = seed;
    } else {
      for (Eigen::Index i = 0; i < n; ++i) {
        const JointLimits& l = impl_->limits[i];
        const double lo = std::isfinite(l.lower) ? l.lower : -M_PI, hi = std::isfinite(l.upper) ? l.upper : M_PI;
        start(i) = std::uniform_real_distribution<double>(lo, hi)(random);
      }
    }
    KDL::JntArray out(static_cast<unsigned>(n));
    solver.CartToJnt(to_kdl(start), goal, out);
    Eigen::VectorXd q = out.data;
    if (!q.allFinite()) continue;
    wrap(q);
    const Eigen::Isometry3d reached = forward(q);
    const double position_error = (reached.translation() - base_from_tip.translation()).norm();
    const double orientation_error = angle_between(reached, base_from_tip);
    const bool close = position_error <= options.position_tolerance && orientation_error <= options.orientation_tolerance;
    const std::string violation = limit_violation(q);
    const std::string refused = close && violation.empty() && options.accept ? options.accept(q) : std::string();
    if (close && violation.empty() && !refused.empty()) {
      // A solution the caller refuses: the first one (from the seed, when it gives one) says why.
      if (!found && best_score > -1) {
        best_score = -1;
        best = IkResult{false, q, position_error, orientation_error, "every solution found is refused: " + refused};
      }
      continue;
    }
    if (close && violation.empty()) {
      const double t = motion_time(q);
      if (!found || t < found_time) {
        best = IkResult{true, q, position_error, orientation_error, {}};
        found = true;
        found_time = t;
      }
      if (attempt == 0) break;  // from the current joints: the nearest there is
      continue;
    }
    if (found) continue;
    // Not a solution: keep the closest miss, one that only breaks a limit before any other.
    const double score = (close ? 0.0 : 1.0) + position_error + 0.1 * orientation_error;
    if (score < best_score) {
      best_score = score;
      best = IkResult{false, q, position_error, orientation_error,
                      close ? "the only solutions found break a limit: " + violation
                            : "no joint positions reach it: the closest of " + std::to_string(std::max(1, options.attempts)) +
                                  " attempts is " + number(position_error) + " m and " +
                                  number(orientation_error * 180.0 / M_PI) + " deg away"};
    }
  }
  if (!found && best.joints.size() == 0) {
    best.joints = seed;
    best.why = "the solver gave no finite joint positions";
  }
  best.attempts = made;
  return best;
}

std::string with_fixed_joint_origins(const std::string& urdf_xml, const std::map<std::string, Eigen::Isometry3d>& origins,
                                     const std::string& origin_name) {
  if (origins.empty()) return urdf_xml;
  TiXmlDocument doc;
  doc.Parse(urdf_xml.c_str());
  if (doc.Error()) throw ArmModelError(origin_name + " is not XML: " + doc.ErrorDesc());
  TiXmlElement* robot = doc.RootElement();
  if (!robot || std::string(robot->Value()) != "robot") throw ArmModelError(origin_name + " has no <robot> element");
  std::map<std::string, TiXmlElement*> fixed;
  std::string fixed_names;
  for (TiXmlElement* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const char* name = j->Attribute("name");
    const char* type = j->Attribute("type");
    if (!name || !type || std::string(type) != "fixed") continue;
    fixed[name] = j;
    fixed_names += (fixed_names.empty() ? "" : ", ") + std::string(name);
  }
  for (const auto& [name, pose] : origins) {
    const auto it = fixed.find(name);
    if (it == fixed.end())
      throw ArmModelError("cannot set the origin of joint '" + name + "' in " + origin_name + ": it has no fixed joint of that name; its fixed joints: " +
                          fixed_names);
    TiXmlElement* joint = it->second;
    while (TiXmlElement* old = joint->FirstChildElement("origin")) joint->RemoveChild(old);
    // rpy about the fixed x, y, z axes: R = Rz(yaw) Ry(pitch) Rx(roll).
    const Eigen::Vector3d ypr = pose.linear().eulerAngles(2, 1, 0);
    std::ostringstream xyz, rpy;
    xyz.precision(17);
    rpy.precision(17);
    xyz << pose.translation().x() << ' ' << pose.translation().y() << ' ' << pose.translation().z();
    rpy << ypr[2] << ' ' << ypr[1] << ' ' << ypr[0];
    TiXmlElement element("origin");
    element.SetAttribute("xyz", xyz.str());
    element.SetAttribute("rpy", rpy.str());
    joint->InsertEndChild(element);
  }
  TiXmlPrinter printer;
  doc.Accept(&printer);
  return printer.CStr();
}

Eigen::Isometry3d pose_from_xyz_rpy(const std::vector<double>& v, const std::string& what) {
  if (v.size() != 6) throw std::invalid_argument(what + ": expected [x, y, z, roll, pitch, yaw] (6 values); found " + std::to_string(v.size()));
  for (double x : v)
    if (!std::isfinite(x)) throw std::invalid_argument(what + ": every value must be finite");
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() << v[0], v[1], v[2];
  return t;
}

JointTrajectory::JointTrajectory(Eigen::VectorXd start, Eigen::VectorXd goal, const Eigen::VectorXd& max_velocity,
                                 const Eigen::VectorXd& max_acceleration)
    : start_(std::move(start)), goal_(std::move(goal)) {
  const Eigen::Index n = start_.size();
  if (goal_.size() != n || max_velocity.size() != n || max_acceleration.size() != n)
    throw std::invalid_argument("trajectory: start, goal and limits differ in size");
  // The path parameter s runs from 0 to 1; joint i moves by d_i * s, so its speed is |d_i| * ds/dt.
  v_ = a_ = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(max_velocity(i) > 0) || !(max_acceleration(i) > 0))
      throw std::invalid_argument("trajectory: velocity and acceleration limits must be > 0");
    const double d = std::abs(goal_(i) - start_(i));
    if (d == 0) continue;
    v_ = std::min(v_, max_velocity(i) / d);
    a_ = std::min(a_, max_acceleration(i) / d);
  }
  if (!std::isfinite(v_)) {  // already there
    v_ = a_ = 0;
    return;
  }
  if (v_ * v_ / a_ >= 1.0) {  // too short to reach full speed: accelerate half way, then brake
    ramp_ = std::sqrt(1.0 / a_);
    v_ = a_ * ramp_;
    duration_ = 2 * ramp_;
  } else {
    ramp_ = v_ / a_;
    duration_ = ramp_ + 1.0 / v_;
  }
}

void JointTrajectory::sample(double t, Eigen::VectorXd& positions, Eigen::VectorXd& velocities) const {
  if (!(t < duration_)) {
    positions = goal_;
    velocities = Eigen::VectorXd::Zero(goal_.size());
    return;
  }
  t = std::max(t, 0.0);
  double s = 0, ds = 0;
  if (t < ramp_) {
    s = 0.5 * a_ * t * t;
    ds = a_ * t;
  } else if (t < duration_ - ramp_) {
    s = 0.5 * a_ * ramp_ * ramp_ + v_ * (t - ramp_);
    ds = v_;
  } else {
    const double left = duration_ - t;
    s = 1.0 - 0.5 * a_ * left * left;
    ds = a_ * left;
  }
  const Eigen::VectorXd d = goal_ - start_;
  positions = start_ + d * s;
  velocities = d * ds;
}

}  // namespace fba::arm

namespace fba::arm {

urdf::ModelInterfaceSharedPtr parse_urdf(const std::string& xml, std::string& problem) {
  CollectMessages messages;
  urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(xml);
  if (!model) problem = messages.text().empty() ? "no robot in it" : messages.text();
  return model;
}

}  // namespace fba::arm
