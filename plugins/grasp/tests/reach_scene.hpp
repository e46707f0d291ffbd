// grasp.synthesis's reach check in a task: test.reach_scene, a sensor defined here (registered
// with the built plugins in reach_registry()), sends the arm's joints and then a model of boxes
// standing in the task's workspace, carved exactly at depth 6, to grasp.synthesis; the test reads
// the selected grasp, the regions asked for, the events and the reported results.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <fba/component.hpp>
#include <fba/registry.hpp>
#include <fba/task.hpp>
#include <fba/task_config.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/types/grasp.hpp>

#include "support/built_plugins.hpp"
#include "support/reach_scenes.hpp"
#include "support/build_paths.hpp"
#include "support/voxel_shapes.hpp"

namespace fba::grasp::test::reach {

fba::Octree box_model_of(const std::vector<double>& boxes);

class SceneSensor final : public fba::Component {
 public:
  static constexpr fba::Out<fba::JointState> kJointState{"joint_state", "the arm's joints, first (none when `joints` is empty)"};
  static constexpr fba::Out<fba::Octree> kOctree{"octree", "then the model"};
  static inline const auto kBoxes = fba::Param<std::vector<double>>(
      "boxes", std::vector<double>{}, "boxes standing in the workspace, 6 numbers each: centre x, y, z and size x, y, z (metres)");
  static inline const auto kJoints = fba::Param<std::vector<double>>("joints", std::vector<double>{}, "the arm's joints, in its order");
  static fba::Spec spec() {
    return fba::Spec::sensor("test.reach_scene", "The arm's joints, then a model of boxes.").add(kJointState, kOctree, kBoxes, kJoints);
  }
  explicit SceneSensor(fba::Context& ctx) : ctx_(ctx) {}
  void process() override {
    if (sent_++ == 0) {
      const std::vector<double> q = ctx_(kJoints);
      if (!q.empty()) {
        fba::JointState s;
        s.names = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"};
        s.positions = q;
        ctx_(kJointState).emit(std::move(s));
      }
      return;
    }
    ctx_(kOctree).emit(box_model_of(ctx_(kBoxes)));
    ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  int sent_ = 0;
};

// The plugins this build made, and test.reach_scene.
inline const fba::Registry& reach_registry() {
  static const fba::Registry r = fba::test::built_plugins_and_own("reach_scene");
  return r;
}

// The model test.reach_scene makes of `boxes`.
inline fba::Octree box_model_of(const std::vector<double>& b) {
  std::vector<Sdf> boxes;
  for (std::size_t i = 0; i + 6 <= b.size(); i += 6) boxes.push_back(box_sdf({b[i], b[i + 1], b[i + 2]}, {b[i + 3], b[i + 4], b[i + 5]}));
  return voxelise(
      [&](const Eigen::Vector3d& p) {
        double d = 1e9;
        for (const auto& f : boxes) d = std::min(d, f(p));
        return d;
      },
      motion::test::workspace(), 6);
}

// One box standing on the table at (x, y), as `boxes` takes it.
inline std::vector<double> standing(const Eigen::Vector3d& size, double x = 0, double y = 0) {
  return {x, y, size.z() / 2, size.x(), size.y(), size.z()};
}

inline std::string numbers(const std::vector<double>& v) {
  std::string t = "[";
  for (std::size_t i = 0; i < v.size(); ++i) t += (i ? ", " : "") + std::to_string(v[i]);
  return t + "]";
}

// What synthesis did with the scene: the grasps, the regions asked for, the candidates shown, the
// events and results.
struct Outcome {
  fba::RunResult run;
  std::vector<fba::Grasp> grasps;
  std::vector<fba::GraspCandidates> candidates;
  std::vector<fba::RegionsOfInterest> regions;
  std::vector<fba::Event> events(const std::string& name) const {
    std::vector<fba::Event> out;
    for (const auto& e : run.events)
      if (e.name == name) out.push_back(e);
    return out;
  }
  std::string result(const std::string& name) const {
    for (const auto& c : run.components)
      if (c.name == "synthesis") {
        const auto it = c.results.find(name);
        return it == c.results.end() ? "" : it->second;
      }
    return "";
  }
};

// grasp.synthesis (with `synthesis_params`, YAML flow-map entries) on the boxes, with the arm at
// `joints`; its joint_state is wired when `joints` is not empty, or `wired` says so (and none
// arrives).
inline Outcome synthesise(const std::vector<double>& boxes, const Eigen::VectorXd& joints, const std::string& synthesis_params = "",
                          bool wired = false) {
  const bool arm = joints.size() > 0 || wired;
  const std::vector<double> q(joints.data(), joints.data() + joints.size());
  const std::string yaml = "task: reach_scene\ncomponents:\n"
                           "  scene: { type: test.reach_scene, params: { boxes: " + numbers(boxes) + ", joints: " + numbers(q) + " } }\n"
                           "  synthesis: { type: grasp.synthesis, params: { " + synthesis_params + " } }\n"
                           "connections:\n  - scene.octree -> synthesis.octree\n" +
                           (arm ? "  - scene.joint_state -> synthesis.joint_state\n" : "") +
                           "on:\n  synthesis.grasp_synthesis_failed: stop_failure\n";
  fba::RunOptions options;
  options.executor = fba::ExecutorKind::Deterministic;
  fba::Task task(fba::load_task_text(yaml, "reach_scene.yaml", ".", reach_registry()), options);
  const auto& grasps = task.tap("synthesis.grasp");
  const auto& regions = task.tap("synthesis.regions");
  const auto& candidates = task.tap("synthesis.candidates");
  Outcome out;
  out.run = task.run();
  for (const auto& p : grasps) out.grasps.push_back(p.get<fba::Grasp>());
  for (const auto& p : regions) out.regions.push_back(p.get<fba::RegionsOfInterest>());
  for (const auto& p : candidates) out.candidates.push_back(p.get<fba::GraspCandidates>());
  return out;
}

}  // namespace fba::grasp::test::reach
