// grasp.synthesis: the paper's Algorithm 3. On every model update it analyses the octree's
// surface, forms three-finger candidates and scores them (S1, S3, S4). A candidate that reaches
// the reliability threshold on a resolved part of the model is selected; otherwise it says where
// information is missing (regions of interest: the carver's grasp-specific criterion and the
// exploration planner's request for a new view), until max_views, when it gives up with the reason.
// With the arm's joints (joint_state), a candidate the arm cannot reach is
// passed over (FBA_GRASP_REACH: the grasp plugin is linked with fba::motion, the reach planner).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <utility>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <fba/component.hpp>
#include <fba/thread_pool.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/types/silhouette.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/vision/octree_carver.hpp"
#include "fba/vision/ply_leaves_parameter.hpp"

#include "fba/grasp/grasp_json.hpp"
#include "fba/grasp/model_surface.hpp"
#include "fba/grasp/synthesis.hpp"
#include "grasp_pictures.hpp"
#include "model_text.hpp"
#include "reach_check.hpp"

#if FBA_GRASP_REACH
#include <fba/types/joint_state.hpp>

#include "fba/motion/hand_geometry.hpp"
#include "fba/motion/hand_placement.hpp"
#include "fba/motion/reach_parameters.hpp"
#include "fba/motion/reach_planner.hpp"
#include "motion_hand.hpp"
#endif

namespace {

using fba::grasp::fixed;
using fba::grasp::total_of;

class GraspSynthesisFilter final : public fba::Component {
 public:
  static constexpr fba::In<fba::Octree> kOctree{"octree", "the model after each update (connect with buffer: latest to skip models a newer one replaced)"};
  static constexpr fba::OptionalIn<fba::Silhouette> kSilhouette{
      "silhouette", "the silhouettes the model was carved from, kept in arrival order: their frames' indices are the grasp's views, "
      "and with rim_deg their rims pin the surface"};
  static constexpr fba::Out<fba::Grasp> kGrasp{"grasp", "the selected grasp (once)"};
  static constexpr fba::Out<fba::RegionsOfInterest> kRegions{
      "regions", "boxes of the candidate regions the model has not resolved: where the carver should refine and the next view should look"};
  static constexpr fba::Out<fba::GraspCandidates> kCandidates{
      "candidates", "after each analysis, its first candidates best first and the best one's palm at the pregrasp: for a live view"};
  static constexpr auto kFingerWidth = fba::Param<double>("finger_width", 0.02, "metres; two fingers closer than this collide").range(1e-4, 1);
  static constexpr auto kApertureMin =
      fba::Param<double>("aperture_min", 0.02, "metres: least distance from the thumb's contact to the fingers' midpoint").range(0, 2);
  static constexpr auto kApertureMax =
      fba::Param<double>("aperture_max", 0.15, "metres: largest distance from the thumb's contact to the fingers' midpoint").range(0, 2);
  static constexpr auto kSpreadMin = fba::Param<double>("spread_min", 0.02, "metres: least distance between the two fingers' contacts").range(0, 2);
  static constexpr auto kSpreadMax = fba::Param<double>("spread_max", 0.10, "metres: largest distance between the two fingers' contacts").range(0, 2);
  static constexpr auto kThreshold =
      fba::Param<double>("threshold", 0.45, "reliability: a candidate whose total score reaches this on a resolved part of the model is selected")
          .range(0, 1);
  static constexpr auto kMaxViews = fba::Param<int>(
      "max_views", 12,
      "the last view: a model of this many views with no reliable candidate on resolved surface selects one whose contacts are "
      "resolved (the surface around them need not be), else gives up (grasp_synthesis_failed)").range(1, 10000);
  static constexpr auto kContactsViews = fba::Param<int>(
      "contacts_views", 0,
      "from a model of this many views on, a reliable candidate whose contacts are resolved is selected though the surface around "
      "them is not all resolved (as at max_views); 0: only at max_views").range(0, 10000);
  static constexpr auto kStabilityShare = fba::Param<double>(
      "stability_share", 0.5,
      "before the last view, a reliable candidate on resolved surface is selected only when its epsilon on the model is at least "
      "this share of the best reliable candidate's, resolved or not: a grasp much less stable than one in sight waits for the "
      "views that resolve the better one (the cracker box's pinches at a corner: 0.005 against 0.024). 0: the first one")
                                               .range(0, 1);
  static constexpr auto kWeightSymmetry = fba::Param<double>("weight_symmetry", 1.0, "weight of S1 in the total").at_least(0);
  static constexpr auto kWeightSafety = fba::Param<double>("weight_safety", 1.0, "weight of S3 in the total").at_least(0);
  static constexpr auto kWeightCurvature = fba::Param<double>("weight_curvature", 1.0, "weight of S4 in the total").at_least(0);
  static constexpr auto kCurvatureScale = fba::Param<double>(
      "curvature_scale", 25.0,
      "1/m: S4 maps a contact's mean curvature -scale .. 0 .. +scale linearly to 1 .. 0.5 .. 0 (slightly concave best); a "
      "convex cylinder of radius r has 1/(2r), so at 25 any cylinder under 2 cm in radius scores 0").range(1, 1000);
  static constexpr auto kSafetyReference = fba::Param<double>(
      "safety_reference", 0.0,
      "metres: S3 scores a contact this far from its region's boundary (over the surface) 1, nearer linearly less; 0: "
      "finger_width").range(0, 1);
  static constexpr auto kMinSymmetry = fba::Param<double>(
      "min_symmetry", 0.0,
      "S1 below this leaves a candidate out whatever its total: its contacts' centre so far off the object's, or their "
      "angles so far from 120 degrees, that the object's weight turns in the hand in the lift; 0: off").range(0, 1);
  static constexpr auto kNeighbourRadius = fba::Param<double>(
      "neighbour_radius", 0.0, "metres: the surface neighbourhood for normals, curvature and regions; 0: 3 edges of the finest leaf").at_least(0);
  static constexpr auto kRimDeg = fba::Param<double>(
      "rim_deg", 0.0,
      "a silhouette fixes the surface only on its rim: with rim_deg > 0, a contact counts as resolved only where the rims of two "
      "posed silhouettes pass (their lines of sight within this angle of the model's tangent plane) with their cones' planes "
      "within this angle of each other (15 suits the sim: from views on one side the far side of the model lies centimetres "
      "off the object); 0: off").range(0, 60);
  static constexpr auto kRimSeparationDeg = fba::Param<double>(
      "rim_separation_deg", 20.0, "the two grazing lines of sight must differ by at least this angle to pin the surface down")
                                                .range(1, 89);
  static constexpr auto kPathTolerance = fba::Param<double>(
      "path_tolerance", 0.02,
      "metres: a candidate is left out when the model stands more than this nearer an open finger than its contact (it would be "
      "touched first) or reaches behind the palm; the hand of the sim's lift test. 0: off (a grasp that is never executed)")
                                             .range(0, 1);
  static constexpr auto kLevelTiltDeg = fba::Param<double>(
      "level_tilt_deg", 30.0,
      "degrees: the reliable candidates whose approach is within this angle of straight down rank before the steeper ones (most "
      "stable first within each), since a tilted hand lets objects slip in the lift; 0: no preference").range(0, 180);
  static constexpr auto kLevelSqueezeDeg = fba::Param<double>(
      "level_squeeze_deg", 10.0,
      "degrees: a reliable candidate ranks with the level ones (level_tilt_deg) only if its squeeze axis (the thumb to the "
      "fingers) is also within this angle of level, so that little of the object's weight bears along the squeeze, on the "
      "fingers' hold rather than across their pads; 0: no preference").range(0, 90);
  static constexpr auto kNormalErrorDeg = fba::Param<double>(
      "normal_error_deg", 0.0,
      "degrees the model's normals may be off the object's: a candidate must stay force closure with each normal turned this far "
      "(its friction cones narrowed to fit); 0: the model's normals are taken as true")
                                              .range(0, 24);
  static constexpr auto kEdgeMarginMm = fba::Param<double>(
      "edge_margin_mm", -1.0,
      "millimetres: no contact nearer its graspable region's edge than this, measured over the region (the safety margin S3 as a "
      "bound): a contact that lands off where the model puts it stays on its face. -1: the model's finest leaf edge, the error of a "
      "surface two views' rims pin; 0: off").range(-1, 100);
  static inline const auto kTableZ = fba::Param<std::vector<double>>(
      "table_z", {}, "[z]: the table the object stands on (world z, up); grasps whose hand would reach into it are left out. "
      "Empty: no table")
      .size({0, 1});
  static constexpr auto kPlyLeaves = fba::vision::PlyLeavesParameter::kPlyLeaves;  // shared with vision.octree_carver
  static constexpr fba::EventOut kPlanningPerformed{
      "planning_performed",
      "no reliable grasp yet: regions were emitted for a new view; payload (JSON): views, samples, regions, candidates, "
      "candidates left out (below_table, hand_blocked, asymmetric, not_force_closure), uncertain_regions, regions_requested, points_requested (contacts to graze), best_total, seconds (wall time of the analysis), best (the best candidate's S1, S3, S4 and whether it is uncertain)"};
  static constexpr fba::EventOut kGraspSelected{"grasp_selected", "a reliable grasp was selected; payload: the grasp as JSON, with its Ferrari-Canny epsilon on the model (model_epsilon)"};
  static constexpr fba::EventOut kFailed{"grasp_synthesis_failed", "the search gave up; payload: the reason"};
#if FBA_GRASP_REACH
  static constexpr fba::OptionalIn<fba::JointState> kJointState{
      "joint_state",
      "the arm's joints (the newest is used): once one has arrived, a candidate the arm cannot reach is passed over (its pregrasp "
      "has no IK solution near these joints, or the arm there, the approach or the lift collides: motion.reach_planner's "
      "reachable(), with the reach parameters below, which the planner shares). Best candidates first, until one is reachable. "
      "Whether the arm can start from where it stands (its hand, opened for the candidate's pregrasp, clear of the table, the arm "
      "and the model, or backed out of the model) is checked for the one about to be selected: one it cannot start for gives way "
      "to the next it can, and is selected only when none can, the result ('reach', 'start') saying so"};
  static constexpr fba::EventOut kUnreachable{
      "unreachable",
      "no candidate on the model is reachable by the arm; synthesis asks for views as when none is reliable. "
      "Payload (JSON): views, candidates, checked, passed_over (per refusal: count and an example reason), unchecked (beyond "
      "reach_checks), seconds"};
  static constexpr auto kRobotHand = fba::Param<bool>(
      "robot_hand", true,
      "the table is checked on the robot's own hand as reach planning poses it (palm and finger links at the pregrasp, at the grasp "
      "and closed), and a grasp whose pads would put the fingers into the table is taken as a fingertip pinch; false: synthesis's "
      "approximate hand, approaching from above or level");
  static constexpr auto kReachChecks = fba::Param<int>(
      "reach_checks", 4,
      "with joint_state: at most this many candidates of one model are checked as far as the arm's inverse kinematics (tens of "
      "milliseconds each when there is no solution), best first; the ones after them are neither selected on that model nor passed "
      "over; at the last view (max_views) every candidate is checked, since no other model will come").range(1, 1000);
#endif

  static fba::Spec spec() {
    fba::Spec spec = fba::Spec::filter("grasp.synthesis",
                                       "Selects a reliable three-finger grasp on an octree model, or asks for views where the model lacks "
                                       "detail."
#if FBA_GRASP_REACH
                                       " With the arm's joints (joint_state), only grasps the arm can reach."
#else
                                       " Built without the reach check (plugins/motion was left out of the build: OMPL, FCL or KDL "
                                       "missing), so it has no joint_state input and selects grasps the arm may not reach."
#endif
    );
    spec.add(kOctree, kSilhouette, kGrasp, kRegions, kCandidates, kFingerWidth, kApertureMin, kApertureMax, kSpreadMin, kSpreadMax, kThreshold,
             kMaxViews, kContactsViews, kStabilityShare, kWeightSymmetry, kWeightSafety, kWeightCurvature, kCurvatureScale, kSafetyReference, kMinSymmetry, kNeighbourRadius, kRimDeg, kRimSeparationDeg, kPathTolerance, kLevelTiltDeg, kLevelSqueezeDeg, kNormalErrorDeg, kEdgeMarginMm, kTableZ, kPlyLeaves, kPlanningPerformed, kGraspSelected, kFailed)
        .add(kApertureMin < kApertureMax, kSpreadMin < kSpreadMax, kFingerWidth <= kSpreadMax)
        .check([](const fba::ParamValues& p) {
          if (p(kWeightSymmetry) + p(kWeightSafety) + p(kWeightCurvature) <= 0)
            return std::string("the weights weight_symmetry, weight_safety and weight_curvature are all 0; at least one must be > 0");
          return std::string();
        })
        .stages({"visual_analysis", "grasp_synthesis", "exploration_movement"},
                {{"visual_analysis", "grasp_synthesis"}, {"grasp_synthesis", "exploration_movement"}, {"exploration_movement", "grasp_synthesis"}});
#if FBA_GRASP_REACH
    spec.add(kJointState, kUnreachable, kReachChecks, kRobotHand);
    fba::motion::ReachParameters::add(spec);  // motion.reach_planner's and the robot's, declared once
#endif
    return spec;
  }

  explicit GraspSynthesisFilter(fba::Context& ctx)
      : ctx_(ctx), stages_(ctx), threshold_(ctx(kThreshold)), max_views_(ctx(kMaxViews)), contacts_views_(ctx(kContactsViews)), stability_share_(ctx(kStabilityShare)),
        radius_(ctx(kNeighbourRadius)), rim_deg_(ctx(kRimDeg)), rim_separation_deg_(ctx(kRimSeparationDeg)) {
    params_.hand = {ctx(kFingerWidth), ctx(kApertureMin), ctx(kApertureMax), ctx(kSpreadMin), ctx(kSpreadMax)};
    params_.weight_symmetry = ctx(kWeightSymmetry);
    params_.weight_safety = ctx(kWeightSafety);
    params_.weight_curvature = ctx(kWeightCurvature);
    params_.curvature_scale = ctx(kCurvatureScale);
    params_.safety_reference = ctx(kSafetyReference);
    params_.min_symmetry = ctx(kMinSymmetry);
    if (const auto table = ctx(kTableZ); !table.empty()) params_.table_z = table[0];
    params_.path_tolerance = ctx(kPathTolerance);
    params_.normal_error_deg = ctx(kNormalErrorDeg);
    params_.level_tilt_deg = ctx(kLevelTiltDeg);
    params_.level_squeeze_deg = ctx(kLevelSqueezeDeg);
    ply_leaves_ = fba::vision::PlyLeavesParameter::read(ctx);
    edge_margin_ = ctx(kEdgeMarginMm) / 1000;
    params_.rank_total = threshold_;  // of the reliable candidates, the most stable on the model first
    // The model's surface and the search borrow the task's threads, as carving does: the loop waits
    // on each analysis, and the other core would sit idle.
    params_.parallel_for = ctx.thread_pool().as_parallel_for();
#if FBA_GRASP_REACH
    // The table is checked on the robot's own hand, as reach planning poses it.
    standoff_ = ctx(fba::motion::ReachParameters::kStandoff);
    if (ctx(kRobotHand)) params_.robot_hand = fba::grasp::motion_hand(standoff_, fba::motion::ReachParams{}.clearance);
    // The arm's reach, when its joints are wired: the planner's check, with its parameters and the
    // robot's.
    if (ctx(kJointState).connected()) {
      const fba::arm::RobotDescription robot = fba::arm::RobotParameters::read(ctx);
      // Whether the arm reaches a candidate, not yet how: the grasp alone (its pregrasp, approach and
      // lift), from where the arm stands, the first IK solution enough.
      fba::motion::ReachParams quick;
      quick.first_solution = true;
      quick.check_start = false;
      reach_.emplace(fba::motion::ReachParameters::planner(ctx, robot, quick));
      // The one to select: the whole plan, path search and all, as motion.reach_planner makes it
      // (the same parameters, the same seed, from the same joints), so that no grasp selected is
      // one the arm then cannot take.
      reach_plan_.emplace(fba::motion::ReachParameters::planner(ctx, robot));
      reach_checks_ = ctx(kReachChecks);
      params_.pregrasp_distance = reach_->params().standoff;  // the table's check at the pregrasp, where the path ends
    }
#endif
  }

  void process() override {
    if (done_) return;  // a grasp was selected or the search gave up: the component's work is over
    if (auto s = ctx_(kSilhouette); s.has()) {
      const auto& frame = s.get().frame;
      view_index_.push_back(frame && frame->index >= 0 ? frame->index : int(view_index_.size()));
      if (frame && frame->has_pose) {
        if (rim_deg_ > 0) rims_.push_back(fba::grasp::silhouette_rim(s.get()));
        last_frame_ = frame;
        views_.push_back(frame->camera);
      }
    }
    auto in = ctx_(kOctree);
    if (!in.has()) return;
    const fba::Octree& model = in.get();
    if (model.node_count == 0) return;  // no tree yet (the carver has no root box)
    if (stages_.current() != "grasp_synthesis") stages_.go("grasp_synthesis");
    const auto start = std::chrono::steady_clock::now();
    analyse(model);
    // The wall time of each view's analyses (a view's model may come twice: refined where synthesis
    // asked), the result "seconds_per_view", in view order: the figure synthesis's speed is judged by.
    if (model.views >= 1) {
      seconds_per_view_.resize(std::max<std::size_t>(seconds_per_view_.size(), std::size_t(model.views)), 0.0);
      seconds_per_view_[model.views - 1] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      ctx_.report("seconds_per_view", nlohmann::json(seconds_per_view_).dump());
    }
  }

 private:
  // One model: its surface, the candidates on it, and the decision: a grasp selected, the search
  // given up, or views asked for where the model would resolve the candidates.
  void analyse(const fba::Octree& model) {
    const auto start = std::chrono::steady_clock::now();
    const int views = model.views;
    ctx_.report("views", std::to_string(views));  // analysed so far: the run's figure when it ends
    write_model(model);
    // The model's views are the first silhouettes (the carver takes them in arrival order).
    const std::span<const fba::grasp::SilhouetteRim> rims = std::span(rims_).first(std::min<std::size_t>(rims_.size(), std::size_t(views)));
    const fba::grasp::ModelSurface surface = fba::grasp::model_surface(model, {radius_, params_.table_z, params_.parallel_for});
    if (const std::string why = fba::grasp::empty_surface_reason(model, surface, views, params_.table_z.value_or(0)); !why.empty()) return fail(why);
    fba::grasp::ModelSurface observed = surface;
    if (rim_deg_ > 0 && !rims.empty()) fba::grasp::mark_unobserved(observed.samples, rims, surface.finest_edge, rim_deg_, rim_separation_deg_);
    fba::grasp::SynthesisParams p = params_;
    p.neighbour_radius = surface.radius;
    p.edge_margin = edge_margin_ >= 0 ? edge_margin_ : surface.finest_edge;
    const fba::grasp::SynthesisResult r = fba::grasp::synthesise(observed.samples, p);

    // The candidates come reliable first, the most stable on the model first: not by total.
    const fba::grasp::GraspCandidate* best =
        r.candidates.empty() ? nullptr : &*std::max_element(r.candidates.begin(), r.candidates.end(), [](const auto& a, const auto& b) {
          return a.grasp.scores.total < b.grasp.scores.total;
        });
    // What the search saw: why a model gives few or weak candidates.
    ctx_.log().debug("views {}: {} of {} occupied leaves joined to the table; {} surface samples in {} regions; {} candidates "
                     "(best total {:.3f}); left out: {} into the table, {} blocked by the model, {} under min_symmetry, {} not force closure",
                     views, surface.leaves - surface.unsupported_leaves, surface.leaves, observed.samples.size(), r.regions.size(),
                     r.candidates.size(), total_of(best), r.below_table, r.hand_blocked, r.asymmetric, r.not_force_closure);
    // The arm's reach, checked as the selection comes to each candidate, best first: the best
    // reachable candidate is the one the others are weighed against, and the one selected must be
    // reachable. Those passed over are reported (with the result, whatever it is) and asked no
    // views for.
    fba::grasp::ReachCheck reach = reach_check(model, r.candidates);
    struct ReportReach {  // on every way out below: the checks made are known once the decision is
      GraspSynthesisFilter& self;
      const fba::grasp::SynthesisResult& result;
      fba::grasp::ReachCheck& reach;
      int views;
      ~ReportReach() {
        self.report_reach(reach, views);
        self.report_candidates(result.candidates, reach, views);
        self.show_candidates(result.candidates, reach, views);
      }
    } report_reach_at_end{*this, r, reach, views};
    std::optional<std::size_t> first_reachable;
    for (std::size_t i = 0; i < r.candidates.size() && !first_reachable; ++i)
      if (reach.reachable(i)) first_reachable = i;
    if (reach.active && !r.candidates.empty() && !first_reachable) say_unreachable(reach, views, r.candidates.size());
    const double best_epsilon = first_reachable ? r.candidates[*first_reachable].model_epsilon : 0.0;
    if (select_on_resolved_surface(r, reach, views, best_epsilon)) return;
    if (contacts_views_ > 0 && views >= contacts_views_ && views < max_views_ && select_on_resolved_contacts(r, reach, views)) return;
    if (views >= max_views_) return settle_at_last_view(r, reach, views, first_reachable.has_value(), best);

    // One request per view: the carver's refinement on it brings a new model of the same views,
    // whose regions differ a little again; answering each would circle between the two for ever.
    // The view asked for is still on its way: back to waiting for it.
    if (views == requested_views_) return stages_.go("exploration_movement");
    requested_views_ = views;
    fba::RegionsOfInterest roi = regions_to_resolve(r, reach, surface, observed.samples, !rims.empty(), views);
    ask_for_ways_in(roi, r, reach);
    const std::size_t requested = roi.boxes.size();
    const std::size_t points = roi.points.size();
    regions_asked_ = roi.boxes;
    ctx_(kRegions).emit(std::move(roi));
    nlohmann::json j{{"views", views},
                     {"samples", surface.samples.size()},
                     {"regions", r.regions.size()},
                     {"candidates", r.candidates.size()},
                     {"below_table", r.below_table},
                     {"hand_blocked", r.hand_blocked},
                     {"asymmetric", r.asymmetric},
                     {"not_force_closure", r.not_force_closure},
                     {"uncertain_regions", r.uncertain_regions.size()},
                     {"regions_requested", requested},
                     {"points_requested", points},
                     {"best_total", total_of(best)},
                     {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()}};
    if (reach.active)
      j["reach"] = {{"checked", reach.passed.checked},
                    {"passed_over", reach.passed.json()},
                    {"unchecked", reach.unchecked},
                    {"seconds", reach.passed.seconds}};
    if (!r.candidates.empty()) {
      const auto& b = r.candidates.front();
      j["best"] = {{"symmetry", b.grasp.scores.symmetry},
                   {"safety_margin", b.grasp.scores.safety_margin},
                   {"curvature", b.grasp.scores.curvature},
                   {"uncertain", b.uncertain}};
    }
    ctx_.emit(kPlanningPerformed, j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    stages_.go("exploration_movement");
  }


  fba::grasp::ReachCheck reach_check([[maybe_unused]] const fba::Octree& model, [[maybe_unused]] const std::vector<fba::grasp::GraspCandidate>& candidates) {
    fba::grasp::ReachCheck reach;
#if FBA_GRASP_REACH
    const fba::JointState* state = reach_ ? ctx_(kJointState).latest() : nullptr;
    if (reach_ && !state && !told_no_joints_) {
      ctx_.log().info("no joint state has arrived yet: the candidates are not checked for the arm's reach");
      told_no_joints_ = true;
    }
    if (!state) return reach;
    reach.active = true;
    reach.log = &ctx_.log();
    // At the last view no other model will come to pick from: every candidate may be checked.
    reach.budget = model.views >= max_views_ ? candidates.size() : static_cast<std::size_t>(reach_checks_);
    reach.state.assign(candidates.size(), -1);
    reach.ahead.resize(candidates.size());
    reach.parallel_for = params_.parallel_for;
    reach.batch = static_cast<std::size_t>(ctx_.thread_pool().size()) + 1;
    std::string why;
    const std::optional<Eigen::VectorXd> joints = fba::motion::arm_joints(reach_->arm(), *state, why);
    // The model's obstacles, built once for the checks of this model.
    auto obstacles = std::make_shared<std::shared_ptr<const fba::motion::ModelObstacles>>();
    reach.prepare = [&model, obstacles] { *obstacles = fba::motion::ReachPlanner::obstacles(model); };
    auto check_with = [&candidates, joints, why, obstacles](const fba::motion::ReachPlanner& planner, bool whole) {
      return [&planner, &candidates, joints, why, obstacles, whole](std::size_t i) -> fba::grasp::ReachCheck::Verdict {
        if (!joints) return {false, false, fba::motion::to_string(fba::motion::Refusal::Start), why, false, true};
        const fba::motion::ReachPlan plan =
            whole ? planner.plan(candidates[i].grasp, *obstacles, *joints) : planner.reachable(candidates[i].grasp, *obstacles, *joints);
        return {plan.ok, plan.figures.ik_attempts > 0, fba::motion::to_string(plan.refusal), plan.why, plan.model_blocked,
                plan.refusal == fba::motion::Refusal::Start};
      };
    };
    reach.check = check_with(*reach_, false);
    reach.check_plan = check_with(*reach_plan_, true);
#endif
    return reach;
  }

  void say_unreachable([[maybe_unused]] const fba::grasp::ReachCheck& reach, [[maybe_unused]] int views, [[maybe_unused]] std::size_t candidates) {
#if FBA_GRASP_REACH
    ctx_.log().info("none of the {} candidates is reachable by the arm, passed over: {}{}", candidates,
                    reach.passed.text(), reach.unchecked_text());
    ctx_.emit(kUnreachable, nlohmann::json{{"views", views},
                                           {"candidates", candidates},
                                           {"checked", reach.passed.checked},
                                           {"passed_over", reach.passed.json()},
                                           {"unchecked", reach.unchecked},
                                           {"seconds", reach.passed.seconds}}
                                .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
#endif
  }

  // The reach check's figures on the model analysed last (the one a grasp was selected on, or the
  // search gave up on), as the result "reach". Called from a destructor: throws nothing.
  void report_reach(const fba::grasp::ReachCheck& reach, int views) noexcept {
    if (!reach.active) return;
    try {
      ctx_.report("reach", nlohmann::json{{"views", views},
                                          {"checked", reach.passed.checked},
                                          {"passed_over_count", reach.passed.total},
                                          {"passed_over", reach.passed.json()},
                                          {"unchecked", reach.unchecked},
                                          {"start", reach.start},
                                          {"seconds", reach.passed.seconds}}
                               .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    } catch (const std::exception& e) {
      ctx_.log().error("could not report the reach check: {}", e.what());
    }
  }

  // The candidates of the model analysed last (the one a grasp was selected on, or the search gave
  // up on), best total first, as the result "candidates": {"views", "grasps": [GRASP...]}, each
  // GRASP as docs/live-view.md has it (contacts, inward normals, approach, score) with its
  // model_epsilon, whether it is reliable (its surface resolved) and whether the arm's reach check
  // passed it over: for the summary's readers (a live view has the first few, show_candidates).
  // Called from a destructor: throws nothing.
  void report_candidates(const std::vector<fba::grasp::GraspCandidate>& candidates, const fba::grasp::ReachCheck& reach, int views) noexcept {
    try {
      auto xyz = [](const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
      nlohmann::json grasps = nlohmann::json::array();
      for (std::size_t i = 0; i < candidates.size(); ++i) {
        const fba::grasp::GraspCandidate& c = candidates[i];
        nlohmann::json contacts = nlohmann::json::array(), normals = nlohmann::json::array();
        for (const auto& contact : c.grasp.contacts) {
          contacts.push_back(xyz(contact.position));
          normals.push_back(xyz(contact.normal));
        }
        grasps.push_back({{"contacts", std::move(contacts)},
                          {"normals", std::move(normals)},
                          {"approach", xyz(c.grasp.approach)},
                          {"score", c.grasp.scores.total},
                          {"model_epsilon", c.model_epsilon},
                          {"reliable", !c.uncertain},
                          {"passed_over", reach.passed_over(i)}});
      }
      ctx_.report("candidates", nlohmann::json{{"views", views}, {"grasps", std::move(grasps)}}
                                    .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    } catch (const std::exception& e) {
      ctx_.log().error("could not report the candidates: {}", e.what());
    }
  }

  // The first candidates of the model analysed, on the output `candidates` for a live view: a few,
  // so that the view stays small, and the best one with its palm (the one selected, else the first not
  // passed over). Called from a destructor: throws nothing.
  void show_candidates(const std::vector<fba::grasp::GraspCandidate>& candidates, const fba::grasp::ReachCheck& reach, int views) noexcept {
    constexpr std::size_t kShown = 24;
    try {
      std::optional<std::size_t> best = reach.selected;
      for (std::size_t i = 0; i < candidates.size() && !best; ++i)
        if (!reach.passed_over(i)) best = i;
      fba::GraspCandidates shown;
      shown.total = candidates.size();
      shown.views = views;
      shown.stamp = ctx_(kOctree).packet().header().stamp_ns * 1e-9;
      for (std::size_t i = 0; i < candidates.size(); ++i)
        if (i < kShown || i == best)  // the best with its palm, wherever it ranks
          shown.candidates.push_back({candidates[i].grasp, !candidates[i].uncertain, reach.passed_over(i),
                                      i == best ? pregrasp_palm(candidates[i].grasp) : std::nullopt});
      ctx_(kCandidates).emit(std::move(shown));
    } catch (const std::exception& e) {
      ctx_.log().error("could not show the candidates: {}", e.what());
    }
  }

  // Where the palm stands at a grasp's pregrasp, as the reach planner places it (world_from_palm);
  // none when the hand cannot take the grasp, or without the reach planner in the build.
  std::optional<Eigen::Isometry3d> pregrasp_palm([[maybe_unused]] const fba::Grasp& g) const {
#if FBA_GRASP_REACH
    const fba::motion::HandPlacement hand = fba::motion::place_hand(g, fba::motion::ReachParams{}.clearance);
    if (!hand.why.empty()) return std::nullopt;
    return Eigen::Translation3d(-hand.world_from_palm.linear().col(2) * standoff_) * hand.world_from_palm;
#else
    return std::nullopt;
#endif
  }

  // Selects the best reliable candidate the arm reaches whose contacts and the surface around them
  // are resolved, in the candidates' order (best first); before the last view, only when it is at
  // least stability_share as stable as the best reachable candidate (`best_epsilon`), resolved or
  // not: views may still resolve that one. Returns whether it selected one.
  bool select_on_resolved_surface(const fba::grasp::SynthesisResult& r, fba::grasp::ReachCheck& reach, int views, double best_epsilon) {
    auto take = [&](std::size_t i) {
      const auto& c = r.candidates[i];
      ctx_.log().info("selected: total {:.3f} (S1 {:.3f}, S3 {:.3f}, S4 {:.3f}), epsilon {:.4f} on the model about its centre "
                      "({:.3f}, {:.3f}, {:.3f})",
                      c.grasp.scores.total, c.grasp.scores.symmetry, c.grasp.scores.safety_margin, c.grasp.scores.curvature,
                      c.model_epsilon, r.centre.x(), r.centre.y(), r.centre.z());
      reach.selected = i;
      select(c.grasp, c.model_epsilon, views, "surface");
      return true;
    };
    reach.first_start.reset();
    for (std::size_t i = 0; i < r.candidates.size(); ++i) {  // best first
      const auto& c = r.candidates[i];
      if (c.uncertain || c.grasp.scores.total < threshold_ || !reach.reachable(i)) continue;
      if (views < max_views_ && c.model_epsilon < stability_share_ * best_epsilon) {
        if (reach.first_start) break;  // a more stable one the arm cannot start for: taken below
        ctx_.log().info("not selected yet: the most stable reliable candidate on resolved surface has epsilon {:.4f} on the "
                        "model, below {:.2f} of the best reliable candidate's {:.4f}, whose surface is not all resolved",
                        c.model_epsilon, stability_share_, best_epsilon);
        return false;  // the reliable ones after it are less stable still
      }
      if (reach.plannable(i) == fba::grasp::ReachCheck::Plan::ok) return take(i);
    }
    return reach.first_start && take(reach.start_anyway());
  }

  // Selects the best reliable candidate the arm reaches whose contacts are resolved (pinned by two
  // views, with rim_deg), the surface around them not all resolved. Returns whether it selected one.
  bool select_on_resolved_contacts(const fba::grasp::SynthesisResult& r, fba::grasp::ReachCheck& reach, int views) {
    auto take = [&](std::size_t i) {
      const auto& c = r.candidates[i];
      ctx_.log().info("selected after {} views, on resolved contacts whose surroundings are not all resolved: total {:.3f} "
                      "(S1 {:.3f}, S3 {:.3f}, S4 {:.3f}), epsilon {:.4f} on the model",
                      views, c.grasp.scores.total, c.grasp.scores.symmetry, c.grasp.scores.safety_margin, c.grasp.scores.curvature,
                      c.model_epsilon);
      reach.selected = i;
      select(c.grasp, c.model_epsilon, views, "contacts");
      return true;
    };
    reach.first_start.reset();
    for (std::size_t i = 0; i < r.candidates.size(); ++i)
      if (const auto& c = r.candidates[i]; !c.contacts_uncertain && c.grasp.scores.total >= threshold_ && reach.reachable(i) &&
                                           reach.plannable(i) == fba::grasp::ReachCheck::Plan::ok)
        return take(i);
    return reach.first_start && take(reach.start_anyway());
  }

  // The last view, and no candidate selected on resolved surface: settle for a reliable candidate
  // whose contacts are resolved (pinned by two views, with rim_deg), though the surface around them
  // is not all resolved yet: on thin, curved objects such as the banana two rims cross on little
  // of the surface, and a whole neighbourhood is rarely pinned. Else the search gives up, saying
  // what held the candidates back.
  void settle_at_last_view(const fba::grasp::SynthesisResult& r, fba::grasp::ReachCheck& reach, int views, bool any_reachable,
                           const fba::grasp::GraspCandidate* best) {
    if (select_on_resolved_contacts(r, reach, views)) return;
    if (reach.active && !r.candidates.empty() && !any_reachable)
      return fail("no grasp the arm can reach after " + std::to_string(views) + " views: none of the " +
                  std::to_string(r.candidates.size()) + " candidates is reachable by the arm; passed over: " + reach.passed.text() +
                  reach.unchecked_text());
    const std::string passed = reach.passed.total > 0 ? "; passed over as out of the arm's reach: " + reach.passed.text() : "";
    fail(fba::grasp::no_reliable_grasp_reason(r, views, best, threshold_, rim_deg_ > 0) + passed);
  }

  // Where more information would help: the unresolved regions of the best candidates, else every
  // unresolved region, else (all resolved, none reliable) the best candidates' regions, else (no
  // candidate at all) the whole model: more views may still carve it to a size the hand takes.
  // The candidates the arm cannot reach are left out: views that resolve them would not help.
  // With rims (rim_deg), also the unpinned points the next view should graze.
  fba::RegionsOfInterest regions_to_resolve(const fba::grasp::SynthesisResult& r, const fba::grasp::ReachCheck& reach,
                                            const fba::grasp::ModelSurface& surface,
                                            const std::vector<fba::grasp::SurfaceSample>& observed, bool rims, int views) const {
    std::vector<const fba::grasp::GraspCandidate*> kept;
    for (std::size_t i = 0; i < r.candidates.size(); ++i)
      if (!reach.passed_over(i)) kept.push_back(&r.candidates[i]);
    std::set<std::size_t> wanted;
    for (const auto* c : kept)
      for (std::size_t g : c->regions)
        if (r.regions[g].uncertain_share > 0) wanted.insert(g);
    if (wanted.empty()) wanted.insert(r.uncertain_regions.begin(), r.uncertain_regions.end());
    if (wanted.empty())
      for (const auto* c : kept) wanted.insert(c->regions.begin(), c->regions.end());
    fba::RegionsOfInterest roi;
    const Eigen::Vector3d margin = Eigen::Vector3d::Constant(surface.finest_edge);
    for (std::size_t g : wanted) roi.boxes.emplace_back(r.regions[g].box.min() - margin, r.regions[g].box.max() + margin);
    if (roi.boxes.empty()) {
      Eigen::AlignedBox3d all;
      for (const auto& x : surface.samples) all.extend(x.position);
      roi.boxes.emplace_back(all.min() - margin, all.max() + margin);
    }
    if (rim_deg_ > 0 && rims) {
      roi.points = unpinned_under_fingers(kept, observed, surface.radius);
      roi.rim_deg = rim_deg_;
      roi.rim_separation_deg = rim_separation_deg_;
    }
    roi.model_views = views;
    return roi;
  }

  // What keeps the best candidates from selection for want of two grazing views: the unpinned
  // surface under their fingers (each contact and its neighbourhood within `radius`, as synthesis
  // judges it), one group per candidate. The next view should graze it. The candidates above the
  // threshold, else the best few.
  std::vector<fba::RegionsOfInterest::SurfacePoint> unpinned_under_fingers(const std::vector<const fba::grasp::GraspCandidate*>& kept,
                                                                    const std::vector<fba::grasp::SurfaceSample>& samples,
                                                                    double radius) const {
    std::vector<fba::RegionsOfInterest::SurfacePoint> points;
    constexpr std::size_t kMostCandidates = 5, kFewCandidates = 3;
    const bool any_reliable = !kept.empty() && kept.front()->grasp.scores.total >= threshold_;
    const double r2 = radius * radius;
    for (std::size_t i = 0; i < kept.size() && i < (any_reliable ? kMostCandidates : kFewCandidates); ++i) {
      const auto& c = *kept[i];
      if (any_reliable && c.grasp.scores.total < threshold_) break;
      for (const auto& x : samples) {
        if (!x.unpinned) continue;
        bool near = false;
        for (std::size_t contact : c.samples) near |= (x.position - samples[contact].position).squaredNorm() <= r2;
        if (near) points.push_back({x.position, x.normal.normalized(), int(i)});
      }
    }
    return points;
  }

  // resolved: what the model had resolved (and two views pinned, with rim_deg) under the fingers:
  // "surface", each contact and its neighbourhood, or "contacts", the contacts only (after the
  // last view). model_epsilon: the grasp's Ferrari-Canny epsilon on the model, which fba::Grasp
  // does not carry: the result and the event hold it beside the grasp ("model_epsilon"), for the
  // run's last line and the summary's readers.
  void select(fba::Grasp g, double model_epsilon, int views, const char* resolved) {
    ctx_.report("resolved", nlohmann::json(resolved).dump());
    // The carver integrates silhouettes in arrival order: the model's views are the first ones.
    for (int v = 0; v < views; ++v) g.views.push_back(v < int(view_index_.size()) ? view_index_[v] : v);
    g.stamp = ctx_(kOctree).packet().header().stamp_ns * 1e-9;
    nlohmann::json selected = fba::grasp::grasp_to_json(g);
    selected["model_epsilon"] = model_epsilon;
    const std::string json = selected.dump();
    ctx_.report("grasp", json);
    ctx_.emit(kGraspSelected, json);
    write_pictures(&g, ctx_(kOctree).get());
    ctx_(kGrasp).emit(std::move(g));
    done_ = true;
  }

  // The space the hand sweeps for the best candidates the model blocked: what blocks them may be
  // space no view has carved yet, which the generic criterion leaves in coarse nodes (over a small
  // object, most of a node's projection outside the silhouette keeps it unsplit), so the carver is
  // asked to refine it, and carves what its views already show empty. Kept asked for on every
  // later model (the carver keeps detail only where the regions of the moment ask), the latest few.
  void ask_for_ways_in([[maybe_unused]] fba::RegionsOfInterest& roi, [[maybe_unused]] const fba::grasp::SynthesisResult& r,
                       [[maybe_unused]] const fba::grasp::ReachCheck& reach) {
#if FBA_GRASP_REACH
    constexpr std::size_t kSweptCandidates = 3, kSweptKept = 6;
    for (std::size_t k = 0; k < reach.model_blocked.size() && k < kSweptCandidates; ++k) {
      const Eigen::AlignedBox3d box = hand_sweep(r.candidates[reach.model_blocked[k]].grasp);
      // The same candidate blocked again on a refined model: asked for once.
      if (std::none_of(swept_.begin(), swept_.end(), [&](const Eigen::AlignedBox3d& b) { return b.isApprox(box); }))
        swept_.push_back(box);
    }
    if (swept_.size() > kSweptKept) swept_.erase(swept_.begin(), swept_.end() - kSweptKept);
    roi.boxes.insert(roi.boxes.end(), swept_.begin(), swept_.end());
#endif
  }

#if FBA_GRASP_REACH
  // The space the open hand passes through on its way in: from the contacts back along the
  // approach past the palm's back at the standoff, as wide as the open hand around the contacts.
  Eigen::AlignedBox3d hand_sweep(const fba::Grasp& g) const {
    const Eigen::Vector3d back = -g.approach.normalized() * (fba::motion::hand::kPadDistance + reach_->params().standoff);
    const Eigen::Vector3d side = Eigen::Vector3d::Constant(0.5 * fba::motion::hand::kSpreadMax);
    Eigen::AlignedBox3d box;
    for (const auto& c : g.contacts) box.extend(c.position).extend(c.position + back);
    return {box.min() - side, box.max() + side};
  }
#endif

  // With an output folder, every model analysed, as exploration/model_<views>views.ply: the loop's
  // iterations, up to the model the grasp was selected on (or the search gave up on). A refined
  // model of the same views replaces the file: the last one is what that view's decision used.
  void write_model(const fba::Octree& model) {
    if (ctx_.output_dir().empty()) return;
    const auto dir = ctx_.output_dir() / "exploration";
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    const auto ply = dir / ("model_" + std::to_string(model.views) + "views.ply");
    try {
      fba::geometry::write_ply(fba::vision::ply_mesh(model, ply_leaves_, model_views(model)), ply);
    } catch (const std::exception& e) {  // an artefact lost is reported; the search goes on
      ctx_.log().error("could not write {}: {}", ply.string(), e.what());
    }
  }

  // With an output folder: the loop's pictures (grasp_pictures.hpp), of the model analysed last and
  // the grasp when one was selected.
  void write_pictures(const fba::Grasp* g, const fba::Octree& model) {
    if (ctx_.output_dir().empty()) return;
    fba::vision::ModelPictureOptions o;
    if (last_frame_) o.object = fba::vision::object_name(last_frame_->source);
    o.views = model_views(model);
    o.regions = regions_asked_;
    o.table_z = params_.table_z;
    if (g) o.grasp = *g;
    fba::grasp::write_loop_pictures(ctx_.output_dir(), model, o, last_frame_, ctx_.log());
  }

  // The cameras of the model's views: the first ones (the carver takes them in arrival order).
  std::vector<fba::CameraModel> model_views(const fba::Octree& model) const {
    const std::size_t n = std::min(views_.size(), static_cast<std::size_t>(std::max(0, model.views)));
    return {views_.begin(), views_.begin() + static_cast<std::ptrdiff_t>(n)};
  }

  void fail(const std::string& reason) {
    ctx_.log().warn("grasp synthesis failed: {}", reason);
    if (auto in = ctx_(kOctree); in.has()) write_pictures(nullptr, in.get());
    ctx_.report("failure", nlohmann::json(reason).dump());
    ctx_.emit(kFailed, reason);
    done_ = true;
  }

  fba::Context& ctx_;
  fba::Stages stages_;
  fba::grasp::SynthesisParams params_;
  const double threshold_;
  const int max_views_;
  const int contacts_views_;
  const double stability_share_;
  const double radius_;
  const double rim_deg_;
  const double rim_separation_deg_;
  double edge_margin_ = 0;  // metres; negative: the model's finest leaf edge
  std::vector<fba::grasp::SilhouetteRim> rims_;   // the posed silhouettes' rims, in arrival order
  std::shared_ptr<const fba::Frame> last_frame_;  // the last posed view: the pictures of the grasp are drawn on it
  std::vector<fba::CameraModel> views_;           // the posed views' cameras, in arrival order: the pictures' views
  std::vector<Eigen::AlignedBox3d> regions_asked_;  // the regions last asked to be refined
  fba::vision::PlyLeaves ply_leaves_ = fba::vision::PlyLeaves::Seen;
  std::vector<int> view_index_;  // the silhouettes' view indices, in arrival order (their images are not kept)
  int requested_views_ = -1;      // the model views of the last regions request
  std::vector<double> seconds_per_view_;  // wall seconds of the analyses of each view's models (index: views - 1)
  bool done_ = false;
#if FBA_GRASP_REACH
  std::vector<Eigen::AlignedBox3d> swept_;  // the hand's way in for candidates the model blocked (hand_sweep)
  std::optional<fba::motion::ReachPlanner> reach_, reach_plan_;  // with joint_state connected: the grasp alone, and the whole plan
  double standoff_ = 0;  // metres back along the approach from the grasp to the pregrasp (the reach planner's)
  int reach_checks_ = 0;
  bool told_no_joints_ = false;
#endif
};

}  // namespace

FBA_COMPONENT(GraspSynthesisFilter);
