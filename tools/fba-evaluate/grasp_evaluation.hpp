// What the grasp subcommand's single and batch modes share: the grasp in a run's summary.json,
// an object's name, and the true mesh placed where the run stood it.
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

namespace fba::evaluate {

// The grasp subcommand's option limits, for both modes: beyond them a run takes hours or the
// measure means nothing (friction above 10 makes almost every contact set force closure).
constexpr std::size_t kMaxRandomSets = 1'000'000;
constexpr std::size_t kMaxSamples = 1'000'000;
constexpr double kMaxFriction = 10.0;
constexpr int kMaxConeEdges = 64;

// The grasp in a parsed summary.json: its "grasp" object, else the grasp a component reported
// (fba-run's summary: components.NAME.results.grasp). nullopt when it has neither; throws
// std::invalid_argument, naming `path` and the member, for a grasp that is malformed.
std::optional<Grasp> summary_grasp(const nlohmann::json& summary, const std::string& path);

// "YcbBanana" for .../YcbBanana/model.obj, else the file's name.
std::string object_name(const std::string& mesh);

// The mesh file with every vertex moved by pose.
TriangleMesh load_posed(const std::string& path, const Eigen::Isometry3d& pose);

// A pose on the table as sim.hand takes it: turned by yaw_deg about z, then moved by (x, y).
Eigen::Isometry3d table_pose(double x, double y, double yaw_deg);

// fba-evaluate grasp --batch (grasp_batch.cpp).
int run_grasp_batch(const std::vector<std::string>& args);

}  // namespace fba::evaluate
