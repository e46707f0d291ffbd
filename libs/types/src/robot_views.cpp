// The views of the robot types: a pose, a joint state, a trajectory, a grasp, regions of interest.
// World frame, metres, radians, as the types hold them.
#include <algorithm>
#include <optional>

#include "fba/types/grasp.hpp"
#include "fba/types/joint_state.hpp"
#include "fba/types/joint_trajectory.hpp"
#include "fba/types/joint_trajectory_json.hpp"
#include "fba/types/pose.hpp"
#include "fba/types/regions_of_interest.hpp"
#include "fba/types/robot_description.hpp"
#include "view_json.hpp"
#include "views.hpp"

namespace fba::views {

namespace {

json numbers(const std::vector<double>& values, double scale) {
  json out = json::array();
  for (double v : values) out.push_back(number(v, scale));
  return out;
}

// GRASP of docs/live-view.md: contacts (thumb first) and their normals (unit, into the object),
// the palm's approach (unit), the total score and the palm's pose when known. Besides: each score,
// the pregrasp and the views the model had.
json grasp_json(const Grasp& g, const std::optional<Eigen::Isometry3d>& palm = std::nullopt) {
  json contacts = json::array(), normals = json::array();
  for (const GraspContact& c : g.contacts) {
    contacts.push_back(xyz(c.position));
    normals.push_back(xyz(c.normal, kUnit));
  }
  return {{"contacts", std::move(contacts)},
          {"normals", std::move(normals)},
          {"approach", xyz(g.approach, kUnit)},
          {"score", number(g.scores.total, kUnit)},
          {"palm", palm ? views::pose(*palm) : json(nullptr)},
          {"scores",
           {{"symmetry", number(g.scores.symmetry, kUnit)},
            {"safety_margin", number(g.scores.safety_margin, kUnit)},
            {"curvature", number(g.scores.curvature, kUnit)},
            {"total", number(g.scores.total, kUnit)}}},
          {"spread", number(g.spread, kMetres)},
          {"aperture", number(g.aperture, kMetres)},
          {"views", g.views}};
}

// A sample's view: what it shows, with its kind and the sample's stamp.
std::string stamped(json v, const char* kind, double stamp) {
  v["kind"] = kind;
  v["stamp"] = number(stamp, kUnit);
  return dump(v);
}

// Every view is shown or not, never thrown from: the reader is a live view, not the task.
template <class F>
std::string guarded(F&& f) noexcept {
  try {
    return f();
  } catch (...) {
    return {};
  }
}

}  // namespace

std::string pose_view(const Packet& p) {
  return guarded([&] {
    const Pose& pose = p.get<Pose>();
    return stamped(views::pose(pose.world_from_frame), "pose", pose.stamp);
  });
}

std::string joint_state_view(const Packet& p) {
  return guarded([&] {
    const JointState& s = p.get<JointState>();
    json v = {{"names", s.names}, {"positions", numbers(s.positions, kUnit)}};
    if (!s.velocities.empty()) v["velocities"] = numbers(s.velocities, kUnit);
    return stamped(std::move(v), "joints", s.stamp);
  });
}

std::string trajectory_view(const Packet& p) {
  return guarded([&] {
    const JointTrajectory& t = p.get<JointTrajectory>();
    return stamped(trajectory_json(t, kMaxTrajectoryPoints, kUnit), "trajectory", t.stamp);
  });
}

std::string grasp_view(const Packet& p) {
  return guarded([&] {
    const Grasp& g = p.get<Grasp>();
    return stamped({{"candidates", json::array()}, {"selected", grasp_json(g)}}, "grasps", g.stamp);
  });
}

std::string grasp_candidates_view(const Packet& p) {
  return guarded([&] {
    const GraspCandidates& gc = p.get<GraspCandidates>();
    json candidates = json::array();
    for (const GraspCandidates::Candidate& c : gc.candidates) {
      json g = grasp_json(c.grasp, c.palm);
      g["reliable"] = c.reliable;
      g["passed_over"] = c.passed_over;
      candidates.push_back(std::move(g));
    }
    return stamped({{"candidates", std::move(candidates)}, {"selected", nullptr}, {"total", gc.total}, {"views", gc.views}}, "grasps",
                   gc.stamp);
  });
}

std::string regions_view(const Packet& p) {
  return guarded([&] {
    const RegionsOfInterest& r = p.get<RegionsOfInterest>();
    json boxes = json::array();
    for (const Eigen::AlignedBox3d& b : r.boxes) {
      if (b.isEmpty()) continue;
      json box = xyz(b.min());
      for (const json& c : xyz(b.max())) box.push_back(c);
      boxes.push_back(std::move(box));
    }
    json points = json::array();
    for (const auto& s : r.points)
      points.push_back({{"position", xyz(s.position)}, {"normal", xyz(s.normal, kUnit)}, {"group", s.group}});
    return dump({{"kind", "regions"}, {"boxes", std::move(boxes)}, {"points", std::move(points)}, {"model_views", r.model_views}});
  });
}

std::string robot_view(const Packet& p) {
  return guarded([&] {
    const RobotDescription& r = p.get<RobotDescription>();
    return dump({{"kind", "robot"}, {"urdf", r.urdf}, {"name", r.name}});
  });
}

}  // namespace fba::views
