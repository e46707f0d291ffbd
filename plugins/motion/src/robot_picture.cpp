#include "fba/motion/robot_picture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/object_families.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/motion/hand_geometry.hpp"
#include "fba/vision/caption.hpp"
#include "fba/vision/octree_carver.hpp"

namespace fba::motion {

namespace {

using C = RobotPictureColours;
const cv::Scalar kContact[3] = {{40, 40, 230}, {40, 170, 40}, {230, 120, 30}};  // thumb, finger 1, finger 2
constexpr double kTableZ = 0.0;        // the planner's table: the half-space below world z = 0
constexpr double kTableTile = 0.1;     // m: the table's squares, for scale
constexpr int kSegments = 32;          // around each cylinder and sphere

// The camera's fixed direction from what it frames: from the arm's side (-y), turned this far
// towards the object's side of the arm (+x), and this far above the horizontal.
constexpr double kAzimuthDeg = 30;
constexpr double kElevationDeg = 20;

cv::Scalar scalar(const cv::Vec3b& c) { return {double(c[0]), double(c[1]), double(c[2])}; }

std::string fixed(double v, const char* format = "%.3f") {
  char s[48];
  std::snprintf(s, sizeof s, format, v);
  return s;
}

void append(TriangleMesh& into, const TriangleMesh& part, const Eigen::Isometry3d& pose) {
  const int base = static_cast<int>(into.vertices.size());
  for (const auto& v : part.vertices) into.vertices.push_back((pose * v.cast<double>()).cast<float>());
  for (const auto& t : part.triangles) into.triangles.push_back(t + Eigen::Vector3i::Constant(base));
}

// The robot's meshes at one pose, world coordinates: the arm's links, the wrist camera, the hand.
struct RobotMeshes {
  TriangleMesh arm, camera, hand;
};

RobotMeshes robot_meshes(const ReachPlanner& planner, const Eigen::VectorXd& joints, double opening, double spread) {
  const arm::ArmModel& arm = planner.arm();
  const std::vector<Eigen::Isometry3d> frames = arm.link_poses(joints);
  RobotMeshes out;
  for (const arm::CollisionShape& s : arm.collision_shapes()) {
    TriangleMesh m;
    switch (s.kind) {
      case arm::CollisionShape::Kind::Box: m = geometry::make_box(-s.size / 2, s.size / 2); break;
      case arm::CollisionShape::Kind::Cylinder: m = geometry::make_cylinder_shape(s.size.x(), s.size.y(), kSegments); break;
      case arm::CollisionShape::Kind::Sphere:
        m = geometry::make_uv_sphere(Eigen::Vector3d::Zero(), s.size.x(), kSegments, kSegments / 2);
        break;
      case arm::CollisionShape::Kind::Mesh:
        throw std::invalid_argument("robot picture: link '" + s.link + "' has a mesh collision shape (" + s.mesh +
                                    "); only boxes, cylinders and spheres are drawn, as only they are checked");
    }
    // The wrist camera's link by its name, as the URDF and the collision messages call it.
    append(s.link == "camera" ? out.camera : out.arm, m, frames.at(s.frame) * s.frame_from_shape);
  }
  const Eigen::Isometry3d palm = arm.forward(joints) * planner.params().flange_from_palm;
  for (const HandPart& p : hand_parts(opening, spread)) {
    const TriangleMesh m = p.kind == HandPart::Kind::Box ? geometry::make_box(-p.size, p.size)
                                                         : geometry::make_cylinder_shape(p.size.x(), p.size.y(), kSegments);
    append(out.hand, m, palm * p.palm_from_part);
  }
  return out;
}

// The leaves the pictures draw: every occupied one not wholly below the table.
TriangleMesh model_mesh(const Octree& model) {
  return vision::surface_mesh(model, [](const OctreeCell& c) { return c.box().max().z() > kTableZ; });
}

// Where the object is at the pose: where it stands until the fingers close, carried with the hand
// (a straight lift) at the top of the lift.
Eigen::Vector3d object_offset(const ReachPlan& plan, PlanPose pose) {
  return pose == PlanPose::Lift ? Eigen::Vector3d(plan.lift_palm.translation() - plan.grasp_palm.translation())
                                : Eigen::Vector3d::Zero();
}

void check_plan(const ReachPlan& plan) {
  if (!plan.ok) throw std::invalid_argument("robot picture: the plan was refused (" + plan.why + "): there is no pose to draw");
}

double step_time(const ReachPlan& plan, PlanPose pose) {
  const char* name = pose == PlanPose::Pregrasp ? "approach" : "lift";
  for (const ReachStep& s : plan.steps)
    if (s.name == name) return pose == PlanPose::Pregrasp ? s.start_s : s.end_s;
  throw std::invalid_argument(std::string("robot picture: the plan has no step '") + name +
                              "' (a plan from reachable() has no timeline): a whole plan, from plan(), is drawn");
}

void add_points(std::vector<Eigen::Vector3d>& points, const TriangleMesh& m) {
  for (const auto& v : m.vertices) points.push_back(v.cast<double>());
}

// The table under what the camera looks at: its top at kTableZ in kTableTile squares, two meshes
// (every other square in each), over the area the robot and the model stand on and a square more
// on each side, on a slab as thick as a square is wide (an infinite plane's squares shrink to a
// flicker towards the horizon).
struct TableMeshes {
  TriangleMesh light, dark, slab;
};

TableMeshes table_meshes(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  const auto index = [](double v) { return static_cast<long>(std::floor(v / kTableTile)); };
  const long x0 = index(lo.x()) - 1, x1 = index(hi.x()) + 1, y0 = index(lo.y()) - 1, y1 = index(hi.y()) + 1;
  TableMeshes t;
  for (long i = x0; i <= x1; ++i)
    for (long j = y0; j <= y1; ++j) {
      TriangleMesh& m = (i + j) % 2 == 0 ? t.light : t.dark;
      const int base = static_cast<int>(m.vertices.size());
      for (const auto& [di, dj] : {std::pair{0, 0}, std::pair{1, 0}, std::pair{1, 1}, std::pair{0, 1}})
        m.vertices.emplace_back(float((i + di) * kTableTile), float((j + dj) * kTableTile), float(kTableZ));
      m.triangles.emplace_back(base, base + 1, base + 2);
      m.triangles.emplace_back(base, base + 2, base + 3);
    }
  // Just below the squares, so that their faces are the ones drawn on top.
  t.slab = geometry::make_box(Eigen::Vector3d(double(x0) * kTableTile, double(y0) * kTableTile, kTableZ - kTableTile),
                              Eigen::Vector3d(double(x1 + 1) * kTableTile, double(y1 + 1) * kTableTile, kTableZ - 1e-4));
  return t;
}

// What the pictures frame: the robot at both poses and the leaves, where they are at either.
std::vector<Eigen::Vector3d> framed_points(const ReachPlanner& planner, const ReachPlan& plan, const Octree& model) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& [q, opening] : {std::pair{plan.pregrasp_joints, plan.opening}, std::pair{plan.lift_joints, plan.width}}) {
    const RobotMeshes r = robot_meshes(planner, q, opening, plan.spread);
    add_points(points, r.arm);
    add_points(points, r.camera);
    add_points(points, r.hand);
  }
  model.for_each_occupied_leaf([&](const OctreeCell& c) {
    if (c.box().max().z() <= kTableZ) return;
    for (const PlanPose pose : {PlanPose::Pregrasp, PlanPose::Lift}) {
      points.push_back(c.box().min() + object_offset(plan, pose));
      points.push_back(c.box().max() + object_offset(plan, pose));
    }
  });
  return points;
}

}  // namespace

CameraModel robot_picture_camera(const ReachPlanner& planner, const ReachPlan& plan, const Octree& model, cv::Size size) {
  check_plan(plan);
  if (size.width < 64 || size.height < 64)
    throw std::invalid_argument("robot picture: the size " + std::to_string(size.width) + " x " + std::to_string(size.height) +
                                " is under 64 x 64");
  const std::vector<Eigen::Vector3d> points = framed_points(planner, plan, model);
  Eigen::AlignedBox3d box;
  for (const auto& p : points) box.extend(p);
  const Eigen::Vector3d centre = box.center();
  const double az = kAzimuthDeg * M_PI / 180, el = kElevationDeg * M_PI / 180;
  const Eigen::Vector3d toward = std::cos(el) * Eigen::Vector3d(std::sin(az), -std::cos(az), 0) + std::sin(el) * Eigen::Vector3d::UnitZ();
  // As near as the points fill 90% of the picture's half-width or half-height.
  return geometry::framing_camera(points, centre, toward, Eigen::Vector3d::UnitZ(), size.width, size.height, 0.9);
}

cv::Mat robot_picture(const ReachPlanner& planner, const ReachPlan& plan, const Grasp& grasp, const Octree& model, PlanPose pose,
                      const CameraModel& camera, const std::string& object) {
  check_plan(plan);
  const double t = step_time(plan, pose);
  const bool lift = pose == PlanPose::Lift;
  const Eigen::VectorXd& joints = lift ? plan.lift_joints : plan.pregrasp_joints;
  const double opening = lift ? plan.width : plan.opening;
  const RobotMeshes robot = robot_meshes(planner, joints, opening, plan.spread);
  const Eigen::Vector3d offset = object_offset(plan, pose);
  TriangleMesh leaves;
  append(leaves, model_mesh(model), Eigen::Isometry3d(Eigen::Translation3d(offset)));

  geometry::RenderOptions look;
  look.background_top = look.background_bottom = C::background;
  // Lit from above, behind the camera's left shoulder, so that the faces turned different ways
  // shade differently.
  look.light_towards_world = (camera.camera_from_world.linear().transpose() * Eigen::Vector3d(-0.3, -0.5, -1.0)).normalized();
  look.ambient = 0.4;
  look.diffuse = 0.6;
  Eigen::AlignedBox3d footprint;
  for (const auto& p : framed_points(planner, plan, model)) footprint.extend(p);
  const TableMeshes table = table_meshes(footprint.min().head<2>(), footprint.max().head<2>());
  const cv::Vec3b table_dark(cv::Vec3b(C::table * 0.85));
  geometry::RenderResult scene = geometry::render(TriangleMesh{}, camera, look);  // the background
  const std::pair<const TriangleMesh*, cv::Vec3b> parts[] = {
      {&table.light, C::table}, {&table.dark, table_dark}, {&table.slab, table_dark}, {&robot.arm, C::arm},
      {&robot.camera, C::camera}, {&robot.hand, C::hand}, {&leaves, C::model}};
  for (const auto& [mesh, colour] : parts) {
    if (mesh->triangles.empty()) continue;
    look.object_colour = colour;
    geometry::composite(scene, geometry::render(*mesh, camera, look));
  }
  cv::Mat picture = scene.colour;

  // The contacts, drawn over everything so that one behind the object as seen still shows; at the
  // lift, where the object carried them.
  for (std::size_t i = 0; i < 3; ++i) {
    Eigen::Vector2d px;
    if (!geometry::project(camera, grasp.contacts[i].position + offset, px)) continue;
    const cv::Point at(static_cast<int>(std::lround(px.x())), static_cast<int>(std::lround(px.y())));
    cv::circle(picture, at, 7, {255, 255, 255}, cv::FILLED, cv::LINE_AA);
    cv::circle(picture, at, 5, kContact[i], cv::FILLED, cv::LINE_AA);
  }

  const Eigen::Vector3d palm = (lift ? plan.lift_palm : plan.pregrasp_palm).translation();
  vision::Caption caption;
  caption.title = (object.empty() ? std::string("the object") : object) +
                  (lift ? ": the robot at the top of the lift, the fingers closed" : ": the robot at the pregrasp, the hand open") +
                  " (t = " + fixed(t, "%.2f") + " s)";
  caption.details = "palm at " + vision::position_text(palm.x(), palm.y(), palm.z()) + "; hand opening " +
                    fixed(opening * 1000, "%.0f") + " mm, spread " + fixed(plan.spread * 1000, "%.0f") + " mm; " +
                    (lift ? "lifted " + fixed(offset.z() * 1000, "%.0f") + " mm" : "standoff before the approach");
  caption.legend = {{scalar(C::arm), "arm (URDF shapes)"},
                    {scalar(C::camera), "wrist camera"},
                    {scalar(C::hand), lift ? "hand, closed" : "hand, open"},
                    {scalar(C::model), lift ? "carved model, carried up" : "carved model (occupied leaves)"},
                    {scalar(C::table), "table, 10 cm squares"},
                    {kContact[0], "thumb contact", vision::LegendMark::Dot},
                    {kContact[1], "finger 1 contact", vision::LegendMark::Dot},
                    {kContact[2], "finger 2 contact", vision::LegendMark::Dot}};
  return vision::captioned(picture, caption);
}

std::vector<std::filesystem::path> write_robot_pictures(const std::filesystem::path& dir, const ReachPlanner& planner,
                                                        const ReachPlan& plan, const Grasp& grasp, const Octree& model,
                                                        const std::string& object) {
  const CameraModel camera = robot_picture_camera(planner, plan, model);
  std::vector<std::filesystem::path> written;
  for (const auto& [pose, name] : {std::pair{PlanPose::Pregrasp, "robot_pregrasp.png"}, std::pair{PlanPose::Lift, "robot_lift.png"}}) {
    const std::filesystem::path file = dir / name;
    if (!cv::imwrite(file.string(), robot_picture(planner, plan, grasp, model, pose, camera, object)))
      throw std::runtime_error("could not write " + file.string());
    written.push_back(file);
  }
  return written;
}

}  // namespace fba::motion
