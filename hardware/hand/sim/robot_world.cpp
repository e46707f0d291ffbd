#include "robot_world.hpp"

#include "urdf_text.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <fmt/format.h>
#include <urdf_parser/urdf_parser.h>

#include "fba/geometry/convex_hull.hpp"

namespace fba::sim_hand {

namespace {

// The roles of the hand's joints, by the URDF's names.
enum class Role { Arm, Close, Spread, Phalanx };

Role role_of(const std::string& name) {
  auto ends = [&](const char* suffix) {
    const std::string s(suffix);
    return name.size() > s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0;
  };
  const bool finger = name.rfind("thumb_", 0) == 0 || name.rfind("finger_a_", 0) == 0 || name.rfind("finger_b_", 0) == 0;
  if (!finger) return Role::Arm;
  if (ends("_close")) return Role::Close;
  if (ends("_spread")) return Role::Spread;
  return Role::Phalanx;
}

// MuJoCo's tuning by role, which URDF has no element for. Rotor inertia seen at the joint
// (armature): a geared arm joint's motor, about 0.3 kg m^2 for the UR5's 150 N m joints and
// 0.06 for its 28 N m wrist (the effort times 2e-3); the hand's values are the MJCF hand's, with
// which the lift test was tuned.
double armature(Role r, double effort) {
  switch (r) {
    case Role::Arm: return 2e-3 * effort;
    case Role::Close: return 0.05;
    case Role::Spread: return 0.2;
    case Role::Phalanx: return 0.005;
  }
  return 0;
}

// The phalanges' springs, N m/rad: stiff enough to keep a finger straight, soft enough to yield a
// little under load; the proximal ones twice the others, the thumb's twice the fingers' (it
// opposes two).
double phalanx_stiffness(const std::string& joint) {
  const double k = joint.back() == '1' ? 40 : 20;
  return joint.rfind("thumb_", 0) == 0 ? 2 * k : k;
}
// The scissor's slides: stiff, as the Robotiq's scissor drive is not back-drivable. N/m.
constexpr double kSpreadStiffness = 20000;

// The footprint's spheres (see robot_world_mjcf): small against a voxel, so that their tops stay
// inside the object's lowest boxes. m.
constexpr double kFootRadius = 0.0005;

std::string num(double v) { return fmt::format("{:.17g}", v); }
std::string vec(double x, double y, double z) { return num(x) + " " + num(y) + " " + num(z); }
std::string pos_quat(const urdf::Pose& p) {
  return "pos=\"" + vec(p.position.x, p.position.y, p.position.z) + "\" quat=\"" + num(p.rotation.w) + " " + num(p.rotation.x) + " " +
         num(p.rotation.y) + " " + num(p.rotation.z) + "\"";
}

Eigen::Vector3d eigen(const urdf::Vector3& v) { return {v.x, v.y, v.z}; }
Eigen::Isometry3d eigen(const urdf::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  t.translation() = eigen(p.position);
  return t;
}

// The collision classes: the robot touches the table and the object, not itself.
constexpr const char* kRobotContact = R"(contype="2" conaffinity="1")";

// One link's collision shapes as MJCF geoms. A cylinder capped by two spheres of its radius at its
// ends is the capsule URDF cannot write; MuJoCo collides capsules exactly.
std::string geoms(const urdf::Link& link, bool hand) {
  struct Shape {
    const urdf::Collision* c;
    bool used = false;
  };
  std::vector<Shape> shapes;
  for (const auto& c : link.collision_array)
    if (c && c->geometry) shapes.push_back({c.get()});
  std::string out;
  int count = 0;
  auto name = [&] { return count++ == 0 ? link.name : link.name + "_" + std::to_string(count); };
  const std::string contact = std::string(kRobotContact) + (hand ? R"( condim="4")" : R"( condim="3")");
  for (auto& s : shapes) {
    if (s.used || s.c->geometry->type != urdf::Geometry::CYLINDER) continue;
    const auto& cyl = static_cast<const urdf::Cylinder&>(*s.c->geometry);
    const Eigen::Isometry3d t = eigen(s.c->origin);
    const Eigen::Vector3d a = t * Eigen::Vector3d(0, 0, -cyl.length / 2), b = t * Eigen::Vector3d(0, 0, cyl.length / 2);
    Shape* caps[2] = {nullptr, nullptr};
    for (auto& o : shapes) {
      if (o.used || &o == &s || o.c->geometry->type != urdf::Geometry::SPHERE) continue;
      if (static_cast<const urdf::Sphere&>(*o.c->geometry).radius != cyl.radius) continue;
      const Eigen::Vector3d centre = eigen(o.c->origin.position);
      for (int k = 0; k < 2; ++k)
        if (!caps[k] && (centre - (k == 0 ? a : b)).norm() < 1e-9) caps[k] = &o;
    }
    if (!caps[0] || !caps[1]) continue;
    s.used = caps[0]->used = caps[1]->used = true;
    out += fmt::format(R"(      <geom name="{}" type="capsule" fromto="{} {}" size="{}" {}/>)", name(), vec(a.x(), a.y(), a.z()),
                       vec(b.x(), b.y(), b.z()), num(cyl.radius), contact) +
           "\n";
  }
  for (auto& s : shapes) {
    if (s.used) continue;
    const urdf::Geometry& g = *s.c->geometry;
    std::string type, size;
    switch (g.type) {
      case urdf::Geometry::BOX: {
        const auto& d = static_cast<const urdf::Box&>(g).dim;
        type = "box", size = vec(d.x / 2, d.y / 2, d.z / 2);
        break;
      }
      case urdf::Geometry::CYLINDER: {
        const auto& c = static_cast<const urdf::Cylinder&>(g);
        type = "cylinder", size = num(c.radius) + " " + num(c.length / 2);
        break;
      }
      case urdf::Geometry::SPHERE:
        type = "sphere", size = num(static_cast<const urdf::Sphere&>(g).radius);
        break;
      case urdf::Geometry::MESH:
        throw RobotWorldError("link '" + link.name + "' collides as a mesh ('" + static_cast<const urdf::Mesh&>(g).filename +
                              "'); the lift test's world takes boxes, cylinders and spheres: give it one of those as <collision>");
    }
    out += fmt::format(R"(      <geom name="{}" type="{}" size="{}" {} {}/>)", name(), type, size, pos_quat(s.c->origin), contact) + "\n";
  }
  return out;
}

struct Writer {
  const urdf::ModelInterface& model;
  std::string bodies, actuators;

  void body(const urdf::Link& link, const urdf::Joint& joint, int depth, bool hand) {
    hand = hand || link.name == "palm";
    const std::string pad(static_cast<std::size_t>(4 + 2 * depth), ' ');
    bodies += pad + fmt::format(R"(<body name="{}" {}>)", link.name, pos_quat(joint.parent_to_joint_origin_transform)) + "\n";
    if (const auto& i = link.inertial; i && i->mass > 0) {
      // MuJoCo takes a full inertia in the body's frame only: turned there from the inertial's.
      Eigen::Matrix3d inertia;
      inertia << i->ixx, i->ixy, i->ixz, i->ixy, i->iyy, i->iyz, i->ixz, i->iyz, i->izz;
      const Eigen::Matrix3d r = eigen(i->origin).linear();
      const Eigen::Matrix3d body = r * inertia * r.transpose();
      const auto& p = i->origin.position;
      bodies += pad + fmt::format(R"(  <inertial pos="{}" mass="{}" fullinertia="{} {} {} {} {} {}"/>)", vec(p.x, p.y, p.z), num(i->mass),
                                  num(body(0, 0)), num(body(1, 1)), num(body(2, 2)), num(body(0, 1)), num(body(0, 2)), num(body(1, 2))) +
                "\n";
    }
    if (joint.type != urdf::Joint::FIXED) movable(joint, pad);
    // A link without shapes keeps its frame as a site: the pads, the flange.
    if (link.collision_array.empty()) bodies += pad + fmt::format(R"(  <site name="{}"/>)", link.name) + "\n";
    bodies += geoms(link, hand);
    children(link, depth + 1, hand);
    bodies += pad + "</body>\n";
  }

  void movable(const urdf::Joint& j, const std::string& pad) {
    std::string type;
    switch (j.type) {
      case urdf::Joint::REVOLUTE:
      case urdf::Joint::CONTINUOUS: type = "hinge"; break;
      case urdf::Joint::PRISMATIC: type = "slide"; break;
      default:
        throw RobotWorldError("joint '" + j.name + "' is floating or planar; the lift test's world takes fixed, revolute, continuous and "
                              "prismatic joints");
    }
    const Role role = role_of(j.name);
    const double effort = j.limits ? j.limits->effort : 0;
    std::string attributes = fmt::format(R"(name="{}" type="{}" axis="{}" armature="{}")", j.name, type,
                                         vec(j.axis.x, j.axis.y, j.axis.z), num(armature(role, effort)));
    if (j.type != urdf::Joint::CONTINUOUS && j.limits)
      attributes += fmt::format(R"( range="{} {}")", num(j.limits->lower), num(j.limits->upper));
    if (j.dynamics && j.dynamics->damping > 0) attributes += fmt::format(R"( damping="{}")", num(j.dynamics->damping));
    bodies += pad + "  <joint " + attributes + "/>\n";
    if (!(effort > 0)) throw RobotWorldError("joint '" + j.name + "' has no effort limit (<limit effort> must be > 0)");
    switch (role) {
      case Role::Arm:
      case Role::Close:
        actuators += fmt::format(R"(    <motor name="{}" joint="{}" ctrlrange="{} {}"/>)", j.name, j.name, num(-effort), num(effort)) + "\n";
        break;
      case Role::Phalanx:
        actuators += fmt::format(R"(    <position name="{}" joint="{}" kp="{}" ctrlrange="{} {}" forcerange="{} {}"/>)", j.name, j.name,
                                 num(phalanx_stiffness(j.name)), num(j.limits->lower), num(j.limits->upper), num(-effort), num(effort)) +
                     "\n";
        break;
      case Role::Spread:
        actuators += fmt::format(R"(    <position name="{}" joint="{}" kp="{}" ctrlrange="{} {}" forcerange="{} {}"/>)", j.name, j.name,
                                 num(kSpreadStiffness), num(j.limits->lower), num(j.limits->upper), num(-effort), num(effort)) +
                     "\n";
        break;
    }
  }

  void children(const urdf::Link& link, int depth, bool hand) {
    for (const auto& j : link.child_joints) {
      if (!j) continue;
      const auto child = model.getLink(j->child_link_name);
      if (child) body(*child, *j, depth, hand);
    }
  }
};


// The corners of the object's footprint on the table: the convex hull of the bottom corners of the
// boxes whose bottom is the object's (within a tenth of the thinnest box).
std::vector<Eigen::Vector2d> footprint(const std::vector<Eigen::AlignedBox3d>& boxes, double bottom) {
  double thinnest = INFINITY;
  for (const auto& b : boxes) thinnest = std::min(thinnest, b.sizes().z());
  std::vector<Eigen::Vector2d> corners;
  for (const auto& b : boxes)
    if (b.min().z() <= bottom + 0.1 * thinnest)
      for (double x : {b.min().x(), b.max().x()})
        for (double y : {b.min().y(), b.max().y()}) corners.emplace_back(x, y);
  return geometry::convex_hull_2d(std::move(corners));
}

}  // namespace

std::string robot_world_mjcf(const std::string& urdf_xml, const std::string& origin_name, const WorldObject& object) {
  std::string problem;
  const urdf::ModelInterfaceSharedPtr model = arm::parse_urdf(urdf_xml, problem);
  if (!model) throw RobotWorldError("URDF " + origin_name + " does not parse: " + problem);
  const auto root = model->getRoot();
  if (!root) throw RobotWorldError("URDF " + origin_name + " has no root link");
  Writer w{*model, {}, {}};
  w.bodies += geoms(*root, false);  // the root is the world: its shapes, if any, stand still
  w.children(*root, 0, false);

  // The object: its boxes collide with the robot, and the convex hull of their corners with the
  // table. A plane touches a solid only on the solid's convex hull, so the table's contacts are
  // exactly the boxes' (the few MuJoCo makes for a convex mesh on a plane, where the boxes on the
  // table would have made four each: hundreds of constraints a step, in MuJoCo 2.2's dense
  // buffers). A convex object given as its hull touches the robot as that hull ("object_shape"),
  // and still the table as its boxes' hull: a ball's is flat across its lowest voxels and stands
  // where it was put, as a real ball does, where the hull's lowest vertex would tip it and roll it
  // centimetres from where the camera saw it. Its mass properties are then MuJoCo's, from the hull
  // (the voxels' centroid lies up to half a voxel off a ball's centre).
  // On a flat base MuJoCo 2.2 keeps the hull's deepest vertex and its neighbours on the hull, one to
  // three contacts that move about the base's vertices: a superquadric rocked on them and walked
  // across the table before the hand came (docs/results.md). A small sphere at each corner of the
  // footprint ("object_foot_N", its bottom at the hull's) gives the table one steady contact
  // there; the hull still takes the table when the object tips off its base.
  std::string object_xml, assets;
  if (!object.boxes.empty()) {
    const bool hull = !object.hull.empty();
    Eigen::AlignedBox3d bounds;
    for (const auto& b : object.boxes) bounds.extend(b);
    const Eigen::Vector3d c = bounds.center();
    object_xml += fmt::format(R"(    <body name="object" pos="{}">)", vec(c.x(), c.y(), c.z())) + "\n";
    object_xml += R"(      <freejoint name="object"/>)" "\n";
    const Eigen::Vector3d com = object.centroid - c;
    const Eigen::Matrix3d inertia = object.mass * object.inertia;
    if (!hull)
      object_xml += fmt::format(R"(      <inertial pos="{}" mass="{}" fullinertia="{} {} {} {} {} {}"/>)", vec(com.x(), com.y(), com.z()),
                                num(object.mass), num(inertia(0, 0)), num(inertia(1, 1)), num(inertia(2, 2)), num(inertia(0, 1)),
                                num(inertia(0, 2)), num(inertia(1, 2))) +
                    "\n";
    std::string corners;
    for (std::size_t i = 0; i < object.boxes.size(); ++i) {
      const Eigen::Vector3d p = object.boxes[i].center() - c, h = object.boxes[i].sizes() / 2;
      if (!hull)
        object_xml += fmt::format(R"(      <geom name="object_{}" type="box" pos="{}" size="{}" contype="0" conaffinity="2" condim="4" )"
                                  R"(rgba="0.8 0.3 0.2 1"/>)",
                                  i, vec(p.x(), p.y(), p.z()), vec(h.x(), h.y(), h.z())) +
                      "\n";
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d q = object.boxes[i].corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)) - c;
        corners += vec(q.x(), q.y(), q.z()) + " ";
      }
    }
    assets = "  <asset>\n    <mesh name=\"object_hull\" vertex=\"" + corners + "\"/>\n";
    if (hull) {
      std::string points;
      for (const auto& p : object.hull) points += vec(p.x() - c.x(), p.y() - c.y(), p.z() - c.z()) + " ";
      assets += "    <mesh name=\"object_shape\" vertex=\"" + points + "\"/>\n";
      object_xml += fmt::format(R"(      <geom name="object_shape" type="mesh" mesh="object_shape" contype="0" conaffinity="2" condim="4" )"
                                R"(mass="{}" rgba="0.8 0.3 0.2 1"/>)",
                                num(object.mass)) +
                    "\n";
    }
    assets += "  </asset>\n";
    object_xml += fmt::format(R"(      <geom name="object_hull" type="mesh" mesh="object_hull" contype="4" conaffinity="1" condim="4" rgba="0 0 0 0"{}/>)",
                              hull ? R"( mass="0")" : "") +
                  "\n";
    const std::vector<Eigen::Vector2d> foot = footprint(object.boxes, bounds.min().z());
    for (std::size_t i = 0; i < foot.size(); ++i)
      object_xml += fmt::format(R"(      <geom name="object_foot_{}" type="sphere" size="{}" pos="{}" contype="4" conaffinity="1" condim="4" )"
                                R"(mass="0" rgba="0 0 0 0"/>)",
                                i, num(kFootRadius), vec(foot[i].x() - c.x(), foot[i].y() - c.y(), bounds.min().z() + kFootRadius - c.z())) +
                    "\n";
    object_xml += "    </body>\n";
  }

  // Friction: MuJoCo's soft contacts have no sticking state, so an object held well inside its
  // friction cones creeps out of the hand at a steady rate (google-deepmind/mujoco#3328: about
  // 0.15 mm/s with this recipe); the noslip post-solver removes that drift (about a hundredfold)
  // and leaves real slip, outside the cones, as it is.
  // Room for the contacts: MuJoCo 2.2 drops those beyond its buffer, warning only (the fingers
  // would pass through the object), and its constraint buffer is dense (njmax squared).
  constexpr int contacts = 400;
  return fmt::format(R"(<mujoco model="{} with a table and the object">
  <compiler angle="radian" autolimits="true" inertiafromgeom="auto"/>
  <option timestep="0.002" cone="elliptic" impratio="10" noslip_iterations="10" gravity="0 0 -9.81"/>
  <size nconmax="{}" njmax="{}"/>
  <default>
    <geom friction="{} 0.005 0.0001" density="1000" rgba="0.3 0.3 0.35 1"/>
  </default>
{}  <worldbody>
    <geom name="table" type="plane" size="2 2 0.01" contype="1" conaffinity="1" rgba="0.6 0.5 0.4 1"/>
    <light pos="0 0 2" dir="0 0 -1"/>
{}{}  </worldbody>
  <actuator>
{}  </actuator>
</mujoco>
)",
                     model->getName(), contacts, 4 * contacts, num(object.friction), assets, w.bodies, object_xml, w.actuators);
}

}  // namespace fba::sim_hand
