// grasp.synthesis: the paper's Algorithm 3. On every model update it analyses the octree's
// surface, forms three-finger candidates and scores them (S1, S3, S4). A candidate that reaches
// the reliability threshold on a resolved part of the model is selected; otherwise it says where
// information is missing (regions of interest: the carver's grasp-specific criterion and the
// exploration planner's request for a new view), until max_views, when it gives up with the reason.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include <fba/component.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/types/silhouette.hpp>

#include "fba/grasp/grasp_json.hpp"
#include "fba/grasp/model_surface.hpp"
#include "fba/grasp/synthesis.hpp"

namespace {

std::string fixed(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

class GraspSynthesisFilter final : public fba::Component {
 public:
  static constexpr fba::In<fba::Octree> kOctree{"octree", "the model after each update (connect with buffer: latest to skip models a newer one replaced)"};
  static constexpr fba::OptionalIn<fba::Silhouette> kSilhouette{
      "silhouette", "the silhouettes the model was carved from, kept in arrival order: their frames' indices are the grasp's views"};
  static constexpr fba::Out<fba::Grasp> kGrasp{"grasp", "the selected grasp (once)"};
  static constexpr fba::Out<fba::RegionsOfInterest> kRegions{
      "regions", "boxes of the candidate regions the model has not resolved: where the carver should refine and the next view should look"};
  static constexpr auto kFingerWidth = fba::Param<double>("finger_width", 0.02, "metres; two fingers closer than this collide").range(1e-4, 1);
  static constexpr auto kApertureMin =
      fba::Param<double>("aperture_min", 0.02, "metres: least distance from the thumb's contact to the fingers' midpoint").range(0, 2);
  static constexpr auto kApertureMax =
      fba::Param<double>("aperture_max", 0.15, "metres: largest distance from the thumb's contact to the fingers' midpoint").range(0, 2);
  static constexpr auto kSpreadMin = fba::Param<double>("spread_min", 0.02, "metres: least distance between the two fingers' contacts").range(0, 2);
  static constexpr auto kSpreadMax = fba::Param<double>("spread_max", 0.10, "metres: largest distance between the two fingers' contacts").range(0, 2);
  static constexpr auto kThreshold = fba::Param<double>(
      "threshold", 0.45,
      "reliability: a candidate whose total score reaches this on a resolved part of the model is selected (the dino at depths 5-7 "
      "reaches 0.46-0.58, carved YCB meshes 0.65-0.80)")
                                         .range(0, 1);
  static constexpr auto kMaxViews = fba::Param<int>(
      "max_views", 12, "gives up (grasp_synthesis_failed) when a model of this many views has no reliable candidate").range(1, 10000);
  static constexpr auto kWeightSymmetry = fba::Param<double>("weight_symmetry", 1.0, "weight of S1 in the total").at_least(0);
  static constexpr auto kWeightSafety = fba::Param<double>("weight_safety", 1.0, "weight of S3 in the total").at_least(0);
  static constexpr auto kWeightCurvature = fba::Param<double>("weight_curvature", 1.0, "weight of S4 in the total").at_least(0);
  static constexpr auto kNeighbourRadius = fba::Param<double>(
      "neighbour_radius", 0.0, "metres: the surface neighbourhood for normals, curvature and regions; 0: 3 edges of the finest leaf").at_least(0);
  static constexpr fba::EventOut kPlanningPerformed{
      "planning_performed",
      "no reliable grasp yet: regions were emitted for a new view; payload (JSON): views, samples, regions, candidates, "
      "uncertain_regions, regions_requested, best_total, seconds (wall time of the analysis), best (the best candidate's S1, S3, S4 and whether it is uncertain)"};
  static constexpr fba::EventOut kGraspSelected{"grasp_selected", "a reliable grasp was selected; payload: the grasp as JSON"};
  static constexpr fba::EventOut kFailed{"grasp_synthesis_failed", "the search gave up; payload: the reason"};

  static fba::Spec spec() {
    return fba::Spec::filter("grasp.synthesis",
                             "Selects a reliable three-finger grasp on an octree model, or asks for views where the model lacks detail.")
        .add(kOctree, kSilhouette, kGrasp, kRegions, kFingerWidth, kApertureMin, kApertureMax, kSpreadMin, kSpreadMax, kThreshold,
             kMaxViews, kWeightSymmetry, kWeightSafety, kWeightCurvature, kNeighbourRadius, kPlanningPerformed, kGraspSelected, kFailed)
        .add(kApertureMin < kApertureMax, kSpreadMin < kSpreadMax, kFingerWidth <= kSpreadMax)
        .check([](const fba::ParamValues& p) {
          if (p(kWeightSymmetry) + p(kWeightSafety) + p(kWeightCurvature) <= 0)
            return std::string("the weights weight_symmetry, weight_safety and weight_curvature are all 0; at least one must be > 0");
          return std::string();
        })
        .stages({"visual_analysis", "grasp_synthesis", "exploration_movement"},
                {{"visual_analysis", "grasp_synthesis"}, {"grasp_synthesis", "exploration_movement"}, {"exploration_movement", "grasp_synthesis"}});
  }

  explicit GraspSynthesisFilter(fba::Context& ctx)
      : ctx_(ctx), stages_(ctx), threshold_(ctx(kThreshold)), max_views_(ctx(kMaxViews)), radius_(ctx(kNeighbourRadius)) {
    params_.hand = {ctx(kFingerWidth), ctx(kApertureMin), ctx(kApertureMax), ctx(kSpreadMin), ctx(kSpreadMax)};
    params_.weight_symmetry = ctx(kWeightSymmetry);
    params_.weight_safety = ctx(kWeightSafety);
    params_.weight_curvature = ctx(kWeightCurvature);
  }

  void process() override {
    if (done_) return;  // a grasp was selected or the search gave up: the component's work is over
    if (auto s = ctx_(kSilhouette); s.has()) {
      const auto& frame = s.get().frame;
      view_index_.push_back(frame && frame->index >= 0 ? frame->index : int(view_index_.size()));
    }
    auto in = ctx_(kOctree);
    if (!in.has()) return;
    const fba::Octree& model = in.get();
    if (model.node_count == 0) return;  // no tree yet (the carver has no root box)
    if (stages_.current() != "grasp_synthesis") stages_.go("grasp_synthesis");
    analyse(model);
  }

 private:
  void analyse(const fba::Octree& model) {
    const auto start = std::chrono::steady_clock::now();
    const int views = model.views;
    const fba::grasp::ModelSurface surface = fba::grasp::model_surface(model, {radius_});
    if (surface.samples.empty())
      return fail("the model is empty after " + std::to_string(views) +
                  " views: no occupied leaf to grasp (no target in the silhouettes, or a root box that misses the object)");
    fba::grasp::SynthesisParams p = params_;
    p.neighbour_radius = surface.radius;
    const fba::grasp::SynthesisResult r = fba::grasp::synthesise(surface.samples, p);

    const double best_total = r.candidates.empty() ? 0.0 : r.candidates.front().grasp.scores.total;
    double best_resolved = 0;  // the best candidate whose contacts are all on resolved parts of the model
    for (const auto& c : r.candidates) {  // best first
      if (c.uncertain) continue;
      if (c.grasp.scores.total >= threshold_) return select(c.grasp, views);
      best_resolved = std::max(best_resolved, c.grasp.scores.total);
    }
    if (views >= max_views_) {
      std::string reason = "no reliable grasp after " + std::to_string(views) + " views: best total " + fixed(best_resolved) +
                           " < threshold " + fixed(threshold_);
      if (r.candidates.empty()) reason += " (no candidate the hand can reach)";
      else if (best_total > best_resolved)
        reason += " (a candidate of total " + fixed(best_total) + " touches a part of the model not yet resolved)";
      return fail(reason);
    }

    // Where more information would help: the unresolved regions of the best candidates, else every
    // unresolved region, else (all resolved, none reliable) the best candidates' regions, else (no
    // candidate at all) the whole model: more views may still carve it to a size the hand takes.
    std::set<std::size_t> wanted;
    for (const auto& c : r.candidates)
      for (std::size_t g : c.regions)
        if (r.regions[g].uncertain_share > 0) wanted.insert(g);
    if (wanted.empty()) wanted.insert(r.uncertain_regions.begin(), r.uncertain_regions.end());
    if (wanted.empty())
      for (const auto& c : r.candidates) wanted.insert(c.regions.begin(), c.regions.end());
    fba::RegionsOfInterest roi;
    const Eigen::Vector3d margin = Eigen::Vector3d::Constant(surface.finest_edge);
    for (std::size_t g : wanted) roi.boxes.emplace_back(r.regions[g].box.min() - margin, r.regions[g].box.max() + margin);
    if (roi.boxes.empty()) {
      Eigen::AlignedBox3d all;
      for (const auto& x : surface.samples) all.extend(x.position);
      roi.boxes.emplace_back(all.min() - margin, all.max() + margin);
    }
    const std::size_t requested = roi.boxes.size();
    roi.model_views = views;
    ctx_(kRegions).emit(std::move(roi));
    nlohmann::json j{{"views", views},
                     {"samples", surface.samples.size()},
                     {"regions", r.regions.size()},
                     {"candidates", r.candidates.size()},
                     {"uncertain_regions", r.uncertain_regions.size()},
                     {"regions_requested", requested},
                     {"best_total", best_total},
                     {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()}};
    if (!r.candidates.empty()) {
      const auto& b = r.candidates.front();
      j["best"] = {{"symmetry", b.grasp.scores.symmetry},
                   {"safety_margin", b.grasp.scores.safety_margin},
                   {"curvature", b.grasp.scores.curvature},
                   {"uncertain", b.uncertain}};
    }
    ctx_.emit(kPlanningPerformed, j.dump());
    stages_.go("exploration_movement");
  }

  void select(fba::Grasp g, int views) {
    // The carver integrates silhouettes in arrival order: the model's views are the first ones.
    for (int v = 0; v < views; ++v) g.views.push_back(v < int(view_index_.size()) ? view_index_[v] : v);
    g.stamp = ctx_(kOctree).packet().header().stamp_ns * 1e-9;
    ctx_.emit(kGraspSelected, fba::grasp::grasp_to_json(g).dump());
    ctx_(kGrasp).emit(std::move(g));
    done_ = true;
  }

  void fail(const std::string& reason) {
    ctx_.log().warn("grasp synthesis failed: {}", reason);
    ctx_.emit(kFailed, reason);
    done_ = true;
  }

  fba::Context& ctx_;
  fba::Stages stages_;
  fba::grasp::SynthesisParams params_;
  const double threshold_;
  const int max_views_;
  const double radius_;
  std::vector<int> view_index_;  // the silhouettes' view indices, in arrival order (their images are not kept)
  bool done_ = false;
};

}  // namespace

FBA_COMPONENT(GraspSynthesisFilter);
