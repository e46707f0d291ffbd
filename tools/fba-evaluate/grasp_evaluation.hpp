// What the grasp subcommand's single and batch modes share: the grasp in a run's summary.json
// (run_summary.hpp), an object's name, and the true mesh, checked closed, placed where the run stood it.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "fba/types/grasp.hpp"
#include "fba/types/mesh.hpp"
#include "run_summary.hpp"

#include "evaluate.hpp"

namespace fba::evaluate {

// The grasp subcommand's option limits, for both modes: beyond them a run takes hours or the
// measure means nothing (friction above 10 makes almost every contact set force closure).
constexpr std::size_t kMaxRandomSets = 1'000'000;
constexpr std::size_t kMaxSamples = 1'000'000;
constexpr double kMaxFriction = 10.0;
constexpr int kMaxConeEdges = 64;

// "YcbBanana" for .../YcbBanana/model.obj, else the file's name.
std::string object_name(const std::string& mesh);

// The closed mesh file with every vertex moved by pose.
TriangleMesh load_posed(const std::string& path, const Eigen::Isometry3d& pose);

// A pose on the table as sim.hand takes it: turned by yaw_deg about z, then moved by (x, y).
Eigen::Isometry3d table_pose(double x, double y, double yaw_deg);

// fba-evaluate grasp --batch (grasp_batch.cpp).
int run_grasp_batch(const std::vector<std::string>& args);

}  // namespace fba::evaluate
