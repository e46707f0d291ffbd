// Grasp synthesis from surface samples (Recatala et al., criteria of Chinellato et al. 2005):
// graspable regions, candidate three-finger grasps a hand can reach (a thumb opposing two
// fingers), scored by S1 symmetry, S3 safety margin and S4 curvature, ranked. Independent of how
// the samples were obtained (octree, silhouettes, or a mesh in tests).
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include "fba/grasp/robot_hand.hpp"
#include "fba/parallel_for.hpp"
#include "fba/types/grasp.hpp"

namespace fba::grasp {

struct SurfaceSample {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, metres
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();    // outward; normalised on input
  double curvature = 0;    // mean curvature, 1/m: positive convex, negative concave, 0 flat
  bool uncertain = false;  // the model has not resolved this part of the surface to its finest depth
  bool unpinned = false;   // no two silhouettes' rims cross here: the model may lie off the object (mark_unobserved)
  bool unresolved() const { return uncertain || unpinned; }  // either: no contact is trusted here
};

// The hand: a three-fingered gripper whose thumb opposes two fingers side by side.
struct HandGeometry {
  double finger_width = 0.02;  // metres; two fingers closer than this collide
  // Distance from the thumb's contact to the midpoint of the fingers' contacts, metres.
  double aperture_min = 0.02;
  double aperture_max = 0.15;
  // Distance between the two fingers' contacts, metres (at least finger_width).
  double spread_min = 0.02;
  double spread_max = 0.10;
  // For reaching above a table (SynthesisParams::table_z), metres: the fingers run along the
  // approach and reach at least tip_length beyond their contacts (a finger touches no nearer its
  // end than its radius); the palm is a box palm_half_width (thumb to fingers, knuckles included) x
  // palm_half_depth (across) x palm_thickness whose face is palm_distance behind the contacts.
  // The defaults are a hand of the robot's size with rounded fingertips; a task with the robot's
  // hand gives it as robot_hand, and this one is not used against the table.
  double tip_length = 0.013;
  double palm_distance = 0.155;
  double palm_half_width = 0.13;
  double palm_half_depth = 0.065;
  double palm_thickness = 0.04;
};

// The threads synthesis, the model's surface and exploration run on (fba/parallel_for.hpp): in a
// component, the task's pool; empty: one after another. The results do not depend on it.
using fba::ParallelFor;

struct SynthesisParams {
  HandGeometry hand;
  // Samples closer than this are neighbours: about twice the sample spacing.
  double neighbour_radius = 0.01;
  // Neighbours whose normals differ by more than this are on two sides of an edge: not one region.
  double max_normal_step_deg = 30;
  // |curvature| above this is a sharp feature, never a graspable region; 0 means 2 / finger_width
  // (a radius of curvature below half a finger).
  double sharp_curvature = 0;
  // S4 maps curvature -scale .. 0 .. +scale (1/m) linearly to 1 .. 0.5 .. 0: slightly concave best.
  double curvature_scale = 25;
  // S3: a contact this far (metres) from its region's boundary scores 1; 0 means finger_width.
  double safety_reference = 0;
  // Metres: no contact nearer its region's boundary than this, measured over the region's surface
  // (the paper's safety margin S3 as a bound, not only a score): a contact that lands that far from
  // where the model puts it, by the model's error or the hand's, is still on the same face, pushing
  // along the normal the grasp was chosen for, not over an edge. 0: off.
  double edge_margin = 0;
  // Opposition: the thumb pushes within thumb_alignment_deg of the thumb-to-fingers axis, each
  // finger within finger_alignment_deg of the opposite direction (60 degrees is three contacts
  // 120 degrees apart), and the fingers' resultant within balance_deg of it, so that their sideways
  // pushes cancel. Each contact's normal lies within plane_alignment_deg of the contacts' plane:
  // three forces in equilibrium are coplanar. The defaults use under half the friction cone's half
  // angle (atan 0.5 = 27 degrees), leaving the rest for positioning and model errors; on the YCB
  // meshes, looser values (25 / 20 / 20) halve the median epsilon of the selected grasps.
  double thumb_alignment_deg = 12;
  double finger_alignment_deg = 65;
  double balance_deg = 10;
  double plane_alignment_deg = 10;
  double weight_symmetry = 1;
  double weight_safety = 1;
  double weight_curvature = 1;
  // S1 below this leaves a candidate out, whatever its total: the contacts' centre so far off the
  // object's, or their angles so far from 120 degrees, that the object's weight turns in the hand
  // when it is lifted. 0: off.
  double min_symmetry = 0;
  // The object's centre for S1 and force closure; default the mean of the samples.
  std::optional<Eigen::Vector3d> object_centre;
  // Of the two approach directions perpendicular to the contacts' plane, the one closer to this
  // (default from above: the object stands on a table).
  Eigen::Vector3d preferred_approach{0, 0, -1};
  // The table the object stands on, world z (z up), when known: a candidate is reachable only if
  // the hand comes from above (or level) and, at the grasp and at its pregrasp, its fingertips and
  // palm stay table_clearance above the table.
  std::optional<double> table_z;
  double table_clearance = 0.003;
  // The robot's hand (robot_hand.hpp). With table_z, whether the hand reaches into the table is
  // checked on its real shapes at each pose it takes (pregrasp, grasp, closed), whatever the
  // approach, and a candidate whose pads would put the fingers into the table is taken as a
  // fingertip pinch when that clears it (Grasp::pinch_depth up to the hand's). Without it,
  // HandGeometry's model, approaching from above or level.
  RobotHand robot_hand;
  double pregrasp_distance = 0.05;  // metres back along the approach where the hand starts
  // The hand's way to its contacts on the model: each finger, opened to the grasp's aperture, runs
  // along the approach and closes across it onto its contact; a model sample that stands more than
  // path_tolerance (metres) nearer the open finger than its contact, within the finger's width and
  // length, would be touched first; a sample inside the palm at the grasp blocks the hand. Such
  // candidates are left out. 0 turns the check off.
  double path_tolerance = 0.02;
  // Stability on the model itself (the model is what the robot knows): each candidate's contacts
  // and the model's inward normals must be force closure (grasp_quality.hpp: friction, 8-edge
  // cones, torques over the samples' largest distance from the object's centre), with a
  // Ferrari-Canny epsilon of at least min_model_epsilon; others are left out. Candidates whose
  // total reaches rank_total (when set: the reliability threshold) come first, most stable first,
  // so that of the reliable grasps the one that best resists disturbances is chosen; S1, S3, S4
  // and the total stay the scores reported.
  bool require_force_closure = true;
  double friction = 0.5;
  // How far (degrees) the model's normals may be off the true surface's at the same contacts. The
  // check narrows each friction cone so that, turned by up to this angle, it still lies inside the
  // full cone (both as the quality measure's pyramids): a grasp closed on the model stays closed
  // on any surface whose normals are within this angle of the model's. 0: the model's normals are
  // taken as true. Must be below the pyramid's inscribed half-angle (24.8 degrees for friction 0.5).
  double normal_error_deg = 0;
  double min_model_epsilon = 0;
  std::optional<double> rank_total;
  // With rank_total: the reliable candidates whose approach lies within this angle (degrees) of
  // preferred_approach rank before the steeper ones, most stable first within each. A hand
  // tilted far from its lift's direction lets held objects slip more in the lift test
  // (docs/grasp-loop.md, "The hand's tilt"). 0: no preference.
  double level_tilt_deg = 0;
  // With rank_total: a reliable candidate counts as level only when its squeeze axis (the thumb to
  // the fingers' midpoint, across the approach) also lies within this angle (degrees) of
  // perpendicular to preferred_approach, so that little of the weight bears along the squeeze, on
  // the fingers' hold rather than across their pads (docs/grasp-loop.md, "The hand's tilt").
  // 0: no preference.
  double level_squeeze_deg = 0;
  // Candidates checked for force closure on the model, best total first, among those the hand can
  // take (path_tolerance, checked on every candidate in turn): each check is a 6-D hull.
  std::size_t max_checks = 400;
  // Bounds on the search: thumbs tried, finger positions per thumb, candidates returned of each
  // kind (on resolved surface, on resolved contacts only, neither: GraspCandidate's flags).
  std::size_t max_thumbs = 80;
  std::size_t max_fingers = 300;
  std::size_t max_candidates = 20;
  ParallelFor parallel_for;  // the neighbourhoods and the candidates' search, over the thumbs
};

// A connected patch of graspable samples (not sharp, normals continuous).
struct GraspRegion {
  std::vector<std::size_t> samples;  // indices into the input
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // mean outward normal (unit, or zero if they cancel)
  double mean_curvature = 0;
  double uncertain_share = 0;  // share of its samples flagged uncertain
  Eigen::AlignedBox3d box;     // bounds of its samples
};

struct GraspCandidate {
  Grasp grasp;                          // contacts (thumb first), approach, pregrasp, scores
  std::array<std::size_t, 3> samples{}; // the contact samples, thumb first
  std::array<std::size_t, 3> regions{}; // their regions
  bool uncertain = false;               // a contact or the surface within neighbour_radius of it is uncertain or unpinned
  bool contacts_uncertain = false;      // a contact sample itself is
  double model_epsilon = 0;             // Ferrari-Canny epsilon on the model's contacts and normals
};

struct SynthesisResult {
  std::vector<GraspRegion> regions;
  std::vector<GraspCandidate> candidates;  // best total first, at most max_candidates of each kind, distinct
  // Regions where more views would help (any uncertain sample), most uncertain area first.
  std::vector<std::size_t> uncertain_regions;
  std::vector<double> boundary_distance;   // per input sample: distance to its region's boundary (m), 0 if none
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // the object's centre used (S1, force closure)
  std::size_t below_table = 0;  // candidates left out because the hand would reach into the table
  std::size_t hand_unfit = 0;    // candidates the robot's hand cannot take at all (SynthesisParams::robot_hand)
  std::size_t near_edge = 0;     // surface samples not taken as contacts: nearer a region's boundary than edge_margin
  std::size_t too_low = 0;       // surface samples not taken as contacts: a finger touching them would reach into the table
  std::size_t hand_blocked = 0;  // candidates left out because the model is in the hand's way
  std::size_t asymmetric = 0;    // candidates left out for an S1 below min_symmetry
  std::size_t not_force_closure = 0;  // candidates left out as not force closure (or too little epsilon) on the model
};

// The lowest point of the hand (world z) taking `grasp` (contacts, approach) as HandGeometry
// models it, with the hand moved back along the approach by `back` metres (0: at the grasp).
double hand_lowest_z(const Grasp& grasp, const HandGeometry& hand, double back = 0);

// A sample (index) that blocks the hand taking `grasp` (contacts, approach, aperture) as
// SynthesisParams::path_tolerance describes, or none. Throws std::invalid_argument for a sample
// that is not finite, or a finger_width that is not positive.
std::optional<std::size_t> hand_path_blocked(const Grasp& grasp, const HandGeometry& hand,
                                             std::span<const SurfaceSample> samples, double tolerance);

// Throws std::invalid_argument for empty or non-finite samples, a zero normal, or parameters out of
// range, naming the value found.
SynthesisResult synthesise(std::span<const SurfaceSample> samples, const SynthesisParams& params = {});

// Fills each sample's curvature from its neighbours within radius: the mean over neighbours q of
// -2 (q - p).n / |q - p|^2, which is the mean curvature on a smooth surface (1/R on a sphere,
// 1/(2R) on a cylinder) and large across an edge. Samples with no neighbour get 0.
void estimate_curvature(std::span<SurfaceSample> samples, double radius, const ParallelFor& parallel_for = {});

}  // namespace fba::grasp
