// vision.model_accuracy: how close the carved model is to the object, where the object is known (a
// simulated scene's mesh). At the end of the stream, the last model is compared with the mesh's true
// solid voxelisation at the model's own resolution and root box: an independent truth, unlike a
// re-projection onto the silhouettes that were carved. The result is an event, so the run's
// summary.json carries it.
#include <cstdio>
#include <optional>

#include <fba/component.hpp>
#include <fba/types/octree.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/voxelize.hpp"

namespace {

class ModelAccuracy final : public fba::Component {
 public:
  static constexpr fba::In<fba::Octree> kOctree{"octree", "the carved model; the last one received is scored"};
  static constexpr fba::Param<std::filesystem::path> kMesh{
      "mesh", fba::required, "the object's true mesh, in the world frame of the model (the simulated camera's mesh)"};
  static constexpr fba::Param<bool> kTableClip{
      "table_clip", true, "ignore voxels below the mesh's lowest point: no view sees under an object standing on a table"};
  static constexpr auto kMaxDepth = fba::Param<int>(
      "max_depth", 9, "score models up to this depth (a dense grid of 8^depth voxels; deeper ones are refused)").range(1, 10);
  static constexpr fba::EventOut kAccuracy{
      "accuracy",
      "the last model against the mesh's true voxelisation; payload (JSON): voxel_iou, truth_voxels, model_voxels, carved_away "
      "(truly occupied voxels the model lacks), depth, views, mesh_inside_box"};

  static fba::Spec spec() {
    // A sink, as io.recorder is: the actuator kind, though it moves nothing.
    return fba::Spec::actuator("vision.model_accuracy",
                             "Scores the last carved model against the true voxelisation of the object's mesh, as an event.")
        .add(kOctree, kMesh, kTableClip, kMaxDepth, kAccuracy);
  }

  explicit ModelAccuracy(fba::Context& ctx)
      : ctx_(ctx), mesh_(fba::geometry::load_mesh(ctx(kMesh))), table_clip_(ctx(kTableClip)), max_depth_(ctx(kMaxDepth)) {}

  void process() override { model_ = ctx_(kOctree).share(); }

  void end_of_stream() override {
    if (!model_ || model_->node_count == 0) {
      ctx_.log().warn("no model arrived: nothing to score");
      return;
    }
    const fba::Octree& m = *model_;
    if (m.max_depth > max_depth_)
      throw std::runtime_error("the model's depth " + std::to_string(m.max_depth) + " is above max_depth " +
                               std::to_string(max_depth_) + ": its dense grid would take " +
                               std::to_string(2ull << (3 * m.max_depth)) + " bytes (two grids of 8^" +
                               std::to_string(m.max_depth) + " voxels, a byte each)");
    const auto mesh_box = fba::geometry::mesh_bounds(mesh_);
    // A mesh outside the model's root box is most likely not the object the camera saw (a
    // --set that changed one mesh parameter and not the other): said, as the score means nothing.
    const double slack = 0.01 * m.bounds.sizes().x();
    const Eigen::AlignedBox3d grown(m.bounds.min().array() - slack, m.bounds.max().array() + slack);
    const bool inside = grown.contains(mesh_box);
    if (!inside)
      ctx_.log().warn("the mesh {} does not fit the model's root box: is it the object the camera saw?", ctx_(kMesh).string());
    std::optional<double> z_min;
    if (table_clip_) z_min = mesh_box.min().z();
    const auto truth = fba::geometry::voxelize(mesh_, m.bounds, m.max_depth, z_min);
    auto model = fba::geometry::rasterize_octree(m);
    if (z_min) fba::geometry::clip_below(model, *z_min);
    const double iou = fba::geometry::iou(truth, model);
    const std::size_t away = fba::geometry::carved_away(truth, model);
    char json[320];
    std::snprintf(json, sizeof json,
                  "{\"voxel_iou\": %.6f, \"truth_voxels\": %zu, \"model_voxels\": %zu, \"carved_away\": %zu, \"depth\": %d, "
                  "\"views\": %d, \"mesh_inside_box\": %s}",
                  iou, truth.count(), model.count(), away, m.max_depth, m.views, inside ? "true" : "false");
    ctx_.log().info("voxel IoU {:.4f} against the mesh's voxelisation at {}^3 ({} truly occupied voxels carved away)", iou,
                    1 << m.max_depth, away);
    ctx_.emit(kAccuracy, json);
  }

 private:
  fba::Context& ctx_;
  const fba::TriangleMesh mesh_;
  const bool table_clip_;
  const int max_depth_;
  std::shared_ptr<const fba::Octree> model_;
};

}  // namespace

FBA_COMPONENT(ModelAccuracy);
