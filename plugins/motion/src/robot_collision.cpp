#include "fba/motion/robot_collision.hpp"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/halfspace.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>

#include "fba/motion/hand_geometry.hpp"
#include "model_obstacles_impl.hpp"
#include "text.hpp"

namespace fba::motion {

namespace {

// One rigid shape of the robot.
struct Body {
  std::string name;
  std::unique_ptr<fcl::CollisionObjectd> object;
  std::size_t frame = 0;  // the arm link it moves with (ArmModel::link_names())
  std::size_t joints_before = 0;
  Eigen::Isometry3d frame_from_shape = Eigen::Isometry3d::Identity();
  // The hand's parts: where they sit on the palm (frame_from_shape follows from it).
  bool hand = false;
  bool finger = false;
  Eigen::Isometry3d palm_from_part = Eigen::Isometry3d::Identity();
  // The shape again, for a quick bound before FCL's exact test: a box's half sizes, or a segment
  // along z (half_length either side of the origin) swept by a radius (cylinder, sphere).
  bool box = false;
  Eigen::Vector3d half = Eigen::Vector3d::Zero();
  double radius = 0, half_length = 0;
  Eigen::Isometry3d shape_from_world = Eigen::Isometry3d::Identity();  // where it was placed last

  // Whether the ball at `centre` of radius r may touch the shape: far apart, FCL is not asked.
  bool may_touch(const Eigen::Vector3d& centre, double r) const {
    const Eigen::Vector3d p = shape_from_world * centre;
    if (box) return (p.cwiseAbs() - half).cwiseMax(0.0).norm() <= r;
    const double z = std::clamp(p.z(), -half_length, half_length);
    return (p - Eigen::Vector3d(0, 0, z)).norm() <= radius + r;
  }
};

void set_bound(Body& b, const arm::CollisionShape& s) {
  b.box = s.kind == arm::CollisionShape::Kind::Box;
  b.half = s.size / 2;
  b.radius = s.size.x();
  b.half_length = s.kind == arm::CollisionShape::Kind::Cylinder ? s.size.y() / 2 : 0.0;
}

void set_bound(Body& b, const HandPart& p) {
  b.box = p.kind == HandPart::Kind::Box;
  b.half = p.size;
  b.radius = p.size.x();
  b.half_length = b.box ? 0.0 : p.size.y() / 2;
}

std::shared_ptr<fcl::CollisionGeometryd> geometry_of(const arm::CollisionShape& s) {
  switch (s.kind) {
    case arm::CollisionShape::Kind::Box:
      return std::make_shared<fcl::Boxd>(s.size.x(), s.size.y(), s.size.z());
    case arm::CollisionShape::Kind::Cylinder:
      return std::make_shared<fcl::Cylinderd>(s.size.x(), s.size.y());
    case arm::CollisionShape::Kind::Sphere:
      return std::make_shared<fcl::Sphered>(s.size.x());
    case arm::CollisionShape::Kind::Mesh:
      break;
  }
  throw std::invalid_argument("link '" + s.link + "' collides as the mesh '" + s.mesh +
                              "'; reach planning checks boxes, cylinders and spheres only: give it one of those as <collision>");
}

std::shared_ptr<fcl::CollisionGeometryd> geometry_of(const HandPart& p) {
  if (p.kind == HandPart::Kind::Box) return std::make_shared<fcl::Boxd>(2 * p.size.x(), 2 * p.size.y(), 2 * p.size.z());
  return std::make_shared<fcl::Cylinderd>(p.size.x(), p.size.y());
}

bool touch(const fcl::CollisionObjectd& a, const fcl::CollisionObjectd& b) {
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  fcl::collide(&a, &b, request, result);
  return result.isCollision();
}

// The model's boxes body b touches, passing over the freed ones and the ones a finger may touch:
// the first one's index + 1 (0: none), or, with `touched`, every one marked there.
std::size_t model_contact(const Body& b, const ModelObstacles::Impl& model, const std::vector<bool>& allowed,
                          const std::vector<bool>& freed, std::vector<bool>* touched = nullptr) {
  std::size_t hit = 0;
  model.visit([&](const Eigen::Vector3d& centre, double radius) { return b.may_touch(centre, radius); },
              [&](std::uint32_t i) {
                if (freed[i] || (b.finger && allowed[i])) return false;
                const Eigen::AlignedBox3d& leaf = model.boxes[i];
                if (!b.may_touch(leaf.center(), leaf.sizes().norm() / 2) || !touch(*b.object, *model.objects[i])) return false;
                hit = i + 1;
                if (touched) (*touched)[i] = true;
                return touched == nullptr;
              });
  return hit;
}

}  // namespace

struct RobotCollision::Impl {
  const arm::ArmModel* arm = nullptr;
  Eigen::Isometry3d flange_from_palm = Eigen::Isometry3d::Identity();
  std::vector<Body> bodies;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;  // bodies not joined by a joint
  fcl::CollisionObjectd table{std::make_shared<fcl::Halfspaced>(Eigen::Vector3d::UnitZ(), 0.0)};
  std::shared_ptr<const ModelObstacles> model;
  std::vector<bool> allowed;  // per model box: a finger may touch it
  std::vector<bool> freed;    // per model box: the arm stood in it, so it is empty (free_model_at)
  bool check_model = true;
  bool model_hit = false;  // the last check's contact was with the model

  void place(Body& b, const Eigen::Isometry3d& world_from_shape) {
    b.object->setTransform(world_from_shape);
    b.object->computeAABB();
    b.shape_from_world = world_from_shape.inverse();
  }

  // What body b touches of the table and the model, or "".
  std::string world_contact(const Body& b) {
    if (b.object->getAABB().min_.z() < 0 && touch(*b.object, table)) return b.name + " touches the table";
    if (!model || !check_model || model->size() == 0) return {};
    const std::size_t hit = model_contact(b, *model->impl_, allowed, freed);
    if (hit == 0) return {};
    model_hit = true;
    return b.name + " touches the model at " + text::point(model->box(hit - 1).center());
  }
};

Eigen::Isometry3d urdf_flange_from_palm(const std::string& urdf_xml, const std::string& origin, const std::string& base_link,
                                        const std::string& flange_link, const std::string& palm_link) {
  const arm::ArmModel to_flange = arm::ArmModel::from_string(urdf_xml, origin, base_link, flange_link);
  const arm::ArmModel to_palm = arm::ArmModel::from_string(urdf_xml, origin, base_link, palm_link);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(to_flange.size()));
  return to_flange.forward(zero).inverse() * to_palm.forward(zero);  // the same at any joints: a fixed joint
}

RobotCollision::RobotCollision(const arm::ArmModel& arm, const Eigen::Isometry3d& flange_from_palm)
    : impl_(std::make_unique<Impl>()) {
  auto& s = *impl_;
  s.arm = &arm;
  s.flange_from_palm = flange_from_palm;
  for (const arm::CollisionShape& shape : arm.collision_shapes()) {
    Body b;
    b.name = shape.link;
    b.object = std::make_unique<fcl::CollisionObjectd>(geometry_of(shape));
    b.frame = shape.frame;
    b.joints_before = shape.joints_before;
    b.frame_from_shape = shape.frame_from_shape;
    set_bound(b, shape);
    s.bodies.push_back(std::move(b));
  }
  // The hand moves with the flange, the chain's last link.
  const std::size_t flange = arm.link_names().size() - 1;
  for (const HandPart& part : hand_parts(hand::kPalmHalfWidth, hand::kSpreadMin)) {
    Body b;
    b.name = part.name;
    b.object = std::make_unique<fcl::CollisionObjectd>(geometry_of(part));
    b.frame = flange;
    b.joints_before = arm.size();
    b.hand = true;
    b.finger = part.name != "palm";
    b.palm_from_part = part.palm_from_part;
    b.frame_from_shape = flange_from_palm * part.palm_from_part;
    set_bound(b, part);
    s.bodies.push_back(std::move(b));
  }
  for (std::size_t i = 0; i < s.bodies.size(); ++i)
    for (std::size_t j = i + 1; j < s.bodies.size(); ++j) {
      const std::size_t a = s.bodies[i].joints_before, b = s.bodies[j].joints_before;
      if ((a > b ? a - b : b - a) >= 2) s.pairs.emplace_back(i, j);
    }
}

RobotCollision::~RobotCollision() = default;
RobotCollision::RobotCollision(RobotCollision&&) noexcept = default;
RobotCollision& RobotCollision::operator=(RobotCollision&&) noexcept = default;

const arm::ArmModel& RobotCollision::arm() const { return *impl_->arm; }
const Eigen::Isometry3d& RobotCollision::flange_from_palm() const { return impl_->flange_from_palm; }

void RobotCollision::set_hand(double opening, double spread) {
  const auto parts = hand_parts(opening, spread);
  for (Body& b : impl_->bodies) {
    if (!b.hand) continue;
    for (const HandPart& p : parts)
      if (p.name == b.name) b.palm_from_part = p.palm_from_part;
    b.frame_from_shape = impl_->flange_from_palm * b.palm_from_part;
  }
}

void RobotCollision::set_model(std::shared_ptr<const ModelObstacles> model, std::span<const Eigen::Vector3d> contacts,
                               double radius) {
  auto& s = *impl_;
  s.model = std::move(model);
  s.allowed.assign(s.model ? s.model->size() : 0, false);
  s.freed.assign(s.allowed.size(), false);
  for (std::size_t i = 0; i < s.allowed.size(); ++i)
    for (const Eigen::Vector3d& c : contacts)
      if (s.model->box(i).exteriorDistance(c) <= radius) s.allowed[i] = true;
}

void RobotCollision::check_model(bool on) { impl_->check_model = on; }

void RobotCollision::free_model_at(const Eigen::VectorXd& joints, bool with_hand) {
  auto& s = *impl_;
  if (!s.model || s.model->size() == 0) return;
  const std::vector<Eigen::Isometry3d> links = s.arm->link_poses(joints);
  for (Body& b : s.bodies) {
    if ((b.hand && !with_hand) || b.joints_before == 0) continue;  // the base stands on the table
    s.place(b, links[b.frame] * b.frame_from_shape);
    std::vector<bool> touched(s.freed.size(), false);
    model_contact(b, *s.model->impl_, s.allowed, s.freed, &touched);
    for (std::size_t i = 0; i < touched.size(); ++i)
      if (touched[i]) s.freed[i] = true;
  }
}

std::string RobotCollision::collision(const Eigen::VectorXd& joints) {
  auto& s = *impl_;
  s.model_hit = false;
  const std::vector<Eigen::Isometry3d> links = s.arm->link_poses(joints);
  for (Body& b : s.bodies) s.place(b, links[b.frame] * b.frame_from_shape);
  // Bodies that do not move stand on the table, where the arm's base is bolted.
  for (const Body& b : s.bodies) {
    if (b.joints_before == 0) continue;
    if (std::string c = s.world_contact(b); !c.empty()) return c;
  }
  for (const auto& [i, j] : s.pairs) {
    const Body& a = s.bodies[i];
    const Body& b = s.bodies[j];
    if (a.object->getAABB().overlap(b.object->getAABB()) && touch(*a.object, *b.object)) return b.name + " touches " + a.name;
  }
  return {};
}

std::string RobotCollision::hand_collision(const Eigen::Isometry3d& world_from_palm) {
  auto& s = *impl_;
  s.model_hit = false;
  for (Body& b : s.bodies) {
    if (!b.hand) continue;
    s.place(b, world_from_palm * b.palm_from_part);
    if (std::string c = s.world_contact(b); !c.empty()) return c;
  }
  return {};
}

bool RobotCollision::model_hit() const { return impl_->model_hit; }

}  // namespace fba::motion
