#include "fba/grasp/synthesis.hpp"

#include "fba/grasp/angles.hpp"
#include "fba/grasp/grasp_quality.hpp"
#include "neighbour_grid.hpp"
#include "parallel.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <numbers>
#include <optional>
#include <queue>
#include <random>
#include <string>
#include <utility>

namespace fba::grasp {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// The half-angle (degrees) of the round cone inside the friction cone's pyramid (QualityParams'
// edges): turned by any angle, a pyramid keeps only that. A pyramid whose edges lie within this
// less normal_error_deg of the model's normal lies inside the pyramid about any normal within
// normal_error_deg of it, so a grasp closed on the model stays closed on such a surface.
double inscribed_cone_deg(double friction) {
  return std::atan(friction * std::cos(std::numbers::pi / QualityParams{}.cone_edges)) / kDeg;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("grasp synthesis: " + what);
}

std::string num(double v) { return std::to_string(v); }

void check_params(const SynthesisParams& p) {
  const HandGeometry& h = p.hand;
  require(h.finger_width > 0, "hand.finger_width must be > 0, found " + num(h.finger_width));
  require(h.aperture_min >= 0 && h.aperture_max > h.aperture_min,
          "hand aperture range must satisfy 0 <= min < max, found " + num(h.aperture_min) + " .. " + num(h.aperture_max));
  require(h.spread_min >= 0 && h.spread_max > h.spread_min && h.spread_max >= h.finger_width,
          "hand spread range must satisfy 0 <= min < max and max >= finger_width, found " + num(h.spread_min) +
              " .. " + num(h.spread_max));
  require(p.neighbour_radius > 0, "neighbour_radius must be > 0, found " + num(p.neighbour_radius));
  require(p.max_normal_step_deg > 0 && p.max_normal_step_deg <= 180,
          "max_normal_step_deg must be in (0, 180], found " + num(p.max_normal_step_deg));
  require(p.sharp_curvature >= 0, "sharp_curvature must be >= 0, found " + num(p.sharp_curvature));
  require(p.curvature_scale > 0, "curvature_scale must be > 0, found " + num(p.curvature_scale));
  require(p.min_symmetry >= 0 && p.min_symmetry <= 1, "min_symmetry must be in [0, 1], found " + num(p.min_symmetry));
  require(p.safety_reference >= 0, "safety_reference must be >= 0, found " + num(p.safety_reference));
  require(p.edge_margin >= 0 && std::isfinite(p.edge_margin), "edge_margin must be finite and >= 0, found " + num(p.edge_margin));
  require(p.robot_hand.pinch_depth >= 0 && std::isfinite(p.robot_hand.pinch_depth),
          "robot_hand.pinch_depth must be finite and >= 0, found " + num(p.robot_hand.pinch_depth));
  require(p.thumb_alignment_deg > 0 && p.thumb_alignment_deg <= 90,
          "thumb_alignment_deg must be in (0, 90], found " + num(p.thumb_alignment_deg));
  require(p.finger_alignment_deg > 0 && p.finger_alignment_deg <= 90,
          "finger_alignment_deg must be in (0, 90], found " + num(p.finger_alignment_deg));
  require(p.balance_deg > 0 && p.balance_deg <= 90, "balance_deg must be in (0, 90], found " + num(p.balance_deg));
  require(p.plane_alignment_deg > 0 && p.plane_alignment_deg <= 90,
          "plane_alignment_deg must be in (0, 90], found " + num(p.plane_alignment_deg));
  require(p.weight_symmetry >= 0 && p.weight_safety >= 0 && p.weight_curvature >= 0 &&
              p.weight_symmetry + p.weight_safety + p.weight_curvature > 0,
          "criterion weights must be >= 0 and not all 0");
  require(!p.object_centre || p.object_centre->allFinite(), "object_centre is not finite");
  require(p.preferred_approach.allFinite() && p.preferred_approach.norm() > 0, "preferred_approach must be non-zero");
  require(!p.table_z || std::isfinite(*p.table_z), "table_z is not finite");
  require(p.table_clearance >= 0 && p.pregrasp_distance >= 0, "table_clearance and pregrasp_distance must be >= 0");
  require(h.tip_length >= 0 && h.palm_distance >= 0 && h.palm_half_width >= 0 && h.palm_half_depth >= 0 && h.palm_thickness >= 0,
          "the hand's tip_length and palm dimensions must be >= 0");
  require(p.max_thumbs > 0 && p.max_fingers > 1 && p.max_candidates > 0 && p.max_checks > 0,
          "search bounds must be positive");
  require(p.friction >= 0 && std::isfinite(p.friction), "friction must be finite and >= 0, found " + num(p.friction));
  require(p.normal_error_deg == 0 || (p.normal_error_deg > 0 && p.normal_error_deg < inscribed_cone_deg(p.friction)),
          "normal_error_deg must be >= 0 and below the friction cone's half-angle (" + num(inscribed_cone_deg(p.friction)) +
              " degrees inside its " + std::to_string(QualityParams{}.cone_edges) + "-edge pyramid), found " + num(p.normal_error_deg));
  require(p.min_model_epsilon >= 0 && std::isfinite(p.min_model_epsilon),
          "min_model_epsilon must be finite and >= 0, found " + num(p.min_model_epsilon));
  require(!p.rank_total || std::isfinite(*p.rank_total), "rank_total is not finite");
  require(p.level_tilt_deg >= 0 && p.level_tilt_deg <= 180, "level_tilt_deg must be within [0, 180], found " + num(p.level_tilt_deg));
  require(p.level_squeeze_deg >= 0 && p.level_squeeze_deg <= 90,
          "level_squeeze_deg must be within [0, 90], found " + num(p.level_squeeze_deg));
  require(p.path_tolerance >= 0 && std::isfinite(p.path_tolerance), "path_tolerance must be finite and >= 0, found " + num(p.path_tolerance));
}

std::vector<SurfaceSample> normalised_input(std::span<const SurfaceSample> in) {
  require(!in.empty(), "no surface samples (expected at least 3)");
  std::vector<SurfaceSample> out(in.begin(), in.end());
  for (std::size_t i = 0; i < out.size(); ++i) {
    auto& s = out[i];
    require(s.position.allFinite() && std::isfinite(s.curvature),
            "sample " + std::to_string(i) + " has a non-finite position or curvature");
    require(s.normal.allFinite() && s.normal.norm() > 1e-12, "sample " + std::to_string(i) + " has a zero normal");
    s.normal.normalize();
  }
  return out;
}

}  // namespace

namespace {

// The hand as lift_test.cpp poses it for a grasp: palm frame a (approach), u (thumb to fingers,
// across the approach), y = a x u; the palm centred between thumb and fingers; each finger's axis
// a pad radius plus its share of the opening beyond its contact.
struct HandPose {
  Eigen::Vector3d a, u, y;
  Eigen::Vector3d palm_centre;             // on the contacts' level along a
  std::array<Eigen::Vector3d, 3> outward;  // each finger's opening direction (thumb -u, fingers +u)
  double open = 0;                         // how far each pad stands off its contact, open
};

HandPose hand_pose(const Grasp& g) {
  HandPose h;
  h.a = g.approach.normalized();
  const Eigen::Vector3d thumb = g.contacts[0].position;
  const Eigen::Vector3d mid = (g.contacts[1].position + g.contacts[2].position) / 2;
  Eigen::Vector3d u = (mid - thumb) - h.a * h.a.dot(mid - thumb);
  const double width = u.norm();
  h.u = width > 1e-12 ? Eigen::Vector3d(u / width) : h.a.unitOrthogonal();
  h.y = h.a.cross(h.u);
  double along = 0;
  for (const auto& c : g.contacts) along += c.position.dot(h.a) / 3;
  h.palm_centre = h.u * (thumb.dot(h.u) + mid.dot(h.u)) / 2 + h.y * mid.dot(h.y) + h.a * along;
  h.outward = {-h.u, h.u, h.u};
  h.open = std::max(0.0, (g.aperture - width) / 2);
  return h;
}

}  // namespace

double hand_lowest_z(const Grasp& g, const HandGeometry& hand, double back) {
  const HandPose h = hand_pose(g);
  const double radius = hand.finger_width / 2;
  const double across = std::sqrt(std::max(0.0, 1 - h.a.z() * h.a.z()));  // a finger's radius seen from below
  double lowest = INFINITY;
  for (std::size_t k = 0; k < 3; ++k) {
    // The finger from its contact to its tip; the other way it rises to the palm, checked below.
    const Eigen::Vector3d at = g.contacts[k].position + h.outward[k] * (h.open + radius) - h.a * back;
    lowest = std::min({lowest, at.z() - radius * across, at.z() + h.a.z() * hand.tip_length - radius * across});
  }
  const Eigen::Vector3d palm = h.palm_centre - h.a * (back + hand.palm_distance + hand.palm_thickness / 2);
  lowest = std::min(lowest, palm.z() - std::abs(h.u.z()) * hand.palm_half_width - std::abs(h.y.z()) * hand.palm_half_depth -
                                std::abs(h.a.z()) * hand.palm_thickness / 2);
  return lowest;
}

namespace {

// Whether the model sample q stands in the hand's way (hand_path_blocked's rule). With margin > 0,
// whether any point within margin of q could: a cell of samples is passed over when its ball
// cannot.
bool in_hand_way(const Eigen::Vector3d& q, const Grasp& g, const HandPose& h, const HandGeometry& hand, double tolerance,
                 double margin = 0) {
  const double radius = hand.finger_width / 2;
  // The palm: the object may not reach behind its face within its footprint.
  const Eigen::Vector3d rel = q - h.palm_centre;
  if (rel.dot(h.a) < -hand.palm_distance + margin && std::abs(rel.dot(h.u)) < hand.palm_half_width + margin &&
      std::abs(rel.dot(h.y)) < hand.palm_half_depth + margin)
    return true;
  // Each finger, from its tip back to the palm, within its width: nothing between the open pad
  // and the contact (it would be touched first), nor where the open finger comes in.
  for (std::size_t k = 0; k < 3; ++k) {
    const Eigen::Vector3d d = q - g.contacts[k].position;
    const double along = d.dot(h.a);
    const double side = std::abs(d.dot(h.y));
    if (along > hand.tip_length + margin || along < -hand.palm_distance - margin || side >= radius + margin) continue;
    const double outward = d.dot(h.outward[k]);
    if (margin > 0) {
      // The round finger's correction below lies between 0 and its radius.
      if (outward + margin > tolerance && outward - radius - margin < h.open + 2 * radius) return true;
      continue;
    }
    // The round finger reaches a sample off its centre line that much later.
    const double out = outward - (radius - std::sqrt(radius * radius - side * side));
    if (out > tolerance && out < h.open + 2 * radius) return true;
  }
  return false;
}

// The model's samples in cubic cells, each with the ball that holds its samples: the hand's-way
// check tests a cell's samples only where its ball could reach into the palm's or a finger's
// volume, a few cells of the hundreds.
class SampleCells {
 public:
  SampleCells(std::span<const SurfaceSample> samples, double size) : samples_(samples) {
    NeighbourGrid(samples, size).for_each_cell([&](const std::vector<std::size_t>& members) {
      Cell& cell = cells_.emplace_back(Cell{members});
      for (std::size_t i : members) cell.centre += samples[i].position / static_cast<double>(members.size());
      for (std::size_t i : members) cell.radius = std::max(cell.radius, (samples[i].position - cell.centre).norm());
    });
  }

  std::optional<std::size_t> hand_path_blocked(const Grasp& g, const HandGeometry& hand, double tolerance) const {
    const HandPose h = hand_pose(g);
    for (const Cell& cell : cells_) {
      if (!in_hand_way(cell.centre, g, h, hand, tolerance, cell.radius)) continue;
      for (std::size_t i : cell.samples)
        if (in_hand_way(samples_[i].position, g, h, hand, tolerance)) return i;
    }
    return std::nullopt;
  }

 private:
  struct Cell {
    std::vector<std::size_t> samples;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // of its samples
    double radius = 0;                                 // the farthest sample from the centre
  };
  std::span<const SurfaceSample> samples_;
  std::vector<Cell> cells_;
};

}  // namespace

std::optional<std::size_t> hand_path_blocked(const Grasp& g, const HandGeometry& hand, std::span<const SurfaceSample> samples,
                                             double tolerance) {
  require(hand.finger_width > 0, "hand.finger_width must be > 0, found " + num(hand.finger_width));
  return SampleCells(samples, hand.finger_width).hand_path_blocked(g, hand, tolerance);
}

namespace {

enum class TableFit { Clear, Table, Unfit };

// Whether the robot's hand takes `g` clear of the table: on its pads, else as the deepest pinch it
// takes (written into g.pinch_depth), which stands the hand back so that the fingertips end
// nearest the contacts' level.
TableFit table_fit(Grasp& g, const RobotHand& hand, double table_z, double clearance) {
  auto fit = [&] {
    const PosedHand posed = hand.pose(g);
    if (!posed.why.empty()) return TableFit::Unfit;
    for (const HandShape& shape : posed.shapes)
      if (lowest_z(shape) < table_z + clearance) return TableFit::Table;
    return TableFit::Clear;
  };
  g.pinch_depth = 0;
  const TableFit on_pads = fit();
  if (on_pads != TableFit::Table || hand.pinch_depth <= 0) return on_pads;
  g.pinch_depth = hand.pinch_depth;
  const TableFit pinch = fit();
  if (pinch != TableFit::Clear) g.pinch_depth = 0;
  return pinch;
}

}  // namespace

void estimate_curvature(std::span<SurfaceSample> samples, double radius, const ParallelFor& parallel_for) {
  require(radius > 0, "curvature radius must be > 0, found " + num(radius));
  const std::vector<std::vector<std::size_t>> nb = NeighbourGrid(samples, radius).neighbourhoods(false, parallel_for);
  std::vector<double> k(samples.size(), 0.0);
  for_each_chunk(parallel_for, samples.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Vector3d n = samples[i].normal.normalized();
      double sum = 0;
      int count = 0;
      for (std::size_t j : nb[i]) {
        const Eigen::Vector3d d = samples[j].position - samples[i].position;
        const double d2 = d.squaredNorm();
        if (d2 < 1e-6 * radius * radius) continue;  // a duplicate says nothing about the bending
        sum += -2.0 * d.dot(n) / d2;
        ++count;
      }
      k[i] = count ? sum / count : 0.0;
    }
  });
  for (std::size_t i = 0; i < samples.size(); ++i) samples[i].curvature = k[i];
}

namespace {

constexpr std::size_t kNoRegion = std::numeric_limits<std::size_t>::max();

// Each sample's neighbours (NeighbourGrid::neighbourhoods).
using Neighbourhoods = std::vector<std::vector<std::size_t>>;

// The graspable regions: connected samples whose |curvature| is at most `sharp` and whose normals
// turn by at most `max_step` (radians) between neighbours, appended to `regions`. Returns each
// sample's region, kNoRegion for a sample in none (a sharp feature).
std::vector<std::size_t> grow_regions(const std::vector<SurfaceSample>& s, const Neighbourhoods& nb, double sharp, double max_step,
                                      std::vector<GraspRegion>& regions) {
  const std::size_t n = s.size();
  std::vector<bool> graspable(n);
  for (std::size_t i = 0; i < n; ++i) graspable[i] = std::abs(s[i].curvature) <= sharp;
  std::vector<std::size_t> region_of(n, kNoRegion);
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (!graspable[seed] || region_of[seed] != kNoRegion) continue;
    const std::size_t r = regions.size();
    GraspRegion region;
    std::vector<std::size_t> stack{seed};
    region_of[seed] = r;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      region.samples.push_back(i);
      for (std::size_t j : nb[i])
        if (graspable[j] && region_of[j] == kNoRegion && angle_between(s[i].normal, s[j].normal) <= max_step) {
          region_of[j] = r;
          stack.push_back(j);
        }
    }
    double k = 0, unsure = 0;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    for (std::size_t i : region.samples) {
      region.centroid += s[i].position;
      normal += s[i].normal;
      k += s[i].curvature;
      unsure += s[i].unresolved() ? 1 : 0;
      region.box.extend(s[i].position);
    }
    const double m = static_cast<double>(region.samples.size());
    region.centroid /= m;
    region.normal = normal.norm() > 1e-9 * m ? normal.normalized() : Eigen::Vector3d::Zero();
    region.mean_curvature = k / m;
    region.uncertain_share = unsure / m;
    regions.push_back(std::move(region));
  }
  return region_of;
}

// The safety margin: each sample's distance within its region to the region's boundary, where a
// sample borders another region, an ungraspable sample, or no samples at all (its neighbours all
// lie to one side); 0 for a sample in no region, 1e3 in a closed region (no boundary).
std::vector<double> boundary_distances(const std::vector<SurfaceSample>& s, const Neighbourhoods& nb,
                                       const std::vector<std::size_t>& region_of, double neighbour_radius) {
  const std::size_t n = s.size();
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (std::size_t i = 0; i < n; ++i) {
    if (region_of[i] == kNoRegion) continue;
    bool boundary = nb[i].size() < 3;
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    for (std::size_t j : nb[i]) {
      if (region_of[j] != region_of[i]) boundary = true;
      offset += s[j].position - s[i].position;
    }
    if (!nb[i].empty()) {
      offset /= static_cast<double>(nb[i].size());
      offset -= offset.dot(s[i].normal) * s[i].normal;
      if (offset.norm() > 0.35 * neighbour_radius) boundary = true;  // a one-sided neighbourhood
    }
    if (boundary) {
      dist[i] = 0;
      queue.push({0.0, i});
    }
  }
  while (!queue.empty()) {
    const auto [d, i] = queue.top();
    queue.pop();
    if (d > dist[i]) continue;
    for (std::size_t j : nb[i]) {
      if (region_of[j] != region_of[i]) continue;
      const double nd = d + (s[j].position - s[i].position).norm();
      if (nd < dist[j]) {
        dist[j] = nd;
        queue.push({nd, j});
      }
    }
  }
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = region_of[i] == kNoRegion ? 0.0 : std::min(dist[i], 1e3);
  return out;
}

// The regions with unresolved samples (where more views would help), the most unresolved area
// first.
std::vector<std::size_t> uncertain_regions(const std::vector<GraspRegion>& regions) {
  std::vector<std::size_t> out;
  for (std::size_t r = 0; r < regions.size(); ++r)
    if (regions[r].uncertain_share > 0) out.push_back(r);
  std::stable_sort(out.begin(), out.end(), [&](std::size_t a, std::size_t b) {
    const auto& ra = regions[a];
    const auto& rb = regions[b];
    return ra.uncertain_share * ra.samples.size() > rb.uncertain_share * rb.samples.size();
  });
  return out;
}

// The samples a contact may take: in a region, at least edge_margin inside it, and high enough for
// a finger to touch above the table; shuffled with a fixed seed, so that its first entries (the
// thumbs tried) are an even, reproducible subset of the surface. Counts the samples left out in
// result.near_edge and result.too_low.
std::vector<std::size_t> contact_pool(const std::vector<SurfaceSample>& s, const std::vector<std::size_t>& region_of,
                                      const SynthesisParams& p, SynthesisResult& result) {
  std::vector<std::size_t> pool;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (region_of[i] == kNoRegion) continue;
    const bool near_edge = result.boundary_distance[i] < p.edge_margin;
    const bool too_low = !near_edge && p.table_z && p.robot_hand.tip_beyond_contact &&
                         s[i].position.z() - *p.robot_hand.tip_beyond_contact < *p.table_z + p.table_clearance;
    result.near_edge += near_edge;
    result.too_low += too_low;
    if (!near_edge && !too_low) pool.push_back(i);
  }
  std::mt19937 rng(0);
  std::shuffle(pool.begin(), pool.end(), rng);
  return pool;
}

// The object's centre for S1 and force closure: the given one, else the samples' mean.
Eigen::Vector3d object_centre(const std::vector<SurfaceSample>& s, const SynthesisParams& p) {
  if (p.object_centre) return *p.object_centre;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& x : s) centre += x.position / static_cast<double>(s.size());
  return centre;
}

// The candidates of one thumb, in the order of its finger pairs, and how many the table left out.
struct ThumbCandidates {
  std::vector<GraspCandidate> candidates;
  std::size_t below_table = 0, hand_unfit = 0;
};

// Candidates: a thumb opposing two fingers, within the hand's reach, in equilibrium, scored (S1,
// S3, S4 and their weighted total) and clear of the table.
class CandidateSearch {
 public:
  CandidateSearch(const std::vector<SurfaceSample>& s, const Neighbourhoods& nb, const std::vector<std::size_t>& region_of,
                  const std::vector<double>& boundary_distance, const std::vector<std::size_t>& pool, const Eigen::Vector3d& centre,
                  const SynthesisParams& p)
      : s_(s), nb_(nb), region_of_(region_of), boundary_distance_(boundary_distance), pool_(pool), centre_(centre), p_(p),
        hand_(p.hand),
        safety_ref_(p.safety_reference > 0 ? p.safety_reference : p.hand.finger_width),
        cos_thumb_(std::cos(p.thumb_alignment_deg * kDeg)),
        cos_finger_(std::cos(p.finger_alignment_deg * kDeg)),
        balance_(p.balance_deg * kDeg),
        sin_plane_(std::sin(p.plane_alignment_deg * kDeg)),
        reach_(std::hypot(p.hand.aperture_max, p.hand.spread_max / 2)),
        min_spread2_(std::max(p.hand.spread_min, p.hand.finger_width) * std::max(p.hand.spread_min, p.hand.finger_width)),
        max_spread2_(p.hand.spread_max * p.hand.spread_max),
        preferred_(p.preferred_approach.normalized()),
        weights_(p.weight_symmetry + p.weight_safety + p.weight_curvature) {}

  ThumbCandidates for_thumb(std::size_t t) const {
    ThumbCandidates out;
    const std::vector<std::size_t> fingers = opposable_fingers(t);
    for (std::size_t a = 0; a < fingers.size(); ++a) {
      for (std::size_t b = a + 1; b < fingers.size(); ++b) {
        const std::size_t f1 = fingers[a], f2 = fingers[b];
        const std::optional<Opposition> o = opposition(t, f1, f2);
        if (!o) continue;
        GraspCandidate cand = scored_candidate(t, f1, f2, *o);
        const TableFit fit = table_check(cand.grasp);
        if (fit != TableFit::Clear) {
          ++(fit == TableFit::Unfit ? out.hand_unfit : out.below_table);
          continue;
        }
        mark_uncertain(cand);
        out.candidates.push_back(std::move(cand));
      }
    }
    return out;
  }

 private:
  // How a thumb and two fingers oppose: the normal of their plane, the fingers' spread and the
  // thumb's distance from the fingers' midpoint.
  struct Opposition {
    Eigen::Vector3d normal;
    double spread, aperture;
  };

  // Finger positions thumb t can oppose: in reach, facing back towards the thumb; at most
  // max_fingers, in the pool's order.
  std::vector<std::size_t> opposable_fingers(std::size_t t) const {
    const Eigen::Vector3d tp = s_[t].position;
    const Eigen::Vector3d tn = -s_[t].normal;  // inward: where the thumb pushes
    std::vector<std::size_t> fingers;
    for (std::size_t f : pool_) {
      if (fingers.size() >= p_.max_fingers) break;
      const Eigen::Vector3d d = tp - s_[f].position;
      const double len = d.norm();
      if (len < hand_.aperture_min || len > reach_) continue;
      if (-s_[f].normal.dot(d / len) < cos_finger_) continue;
      if (tn.dot(-d / len) < cos_thumb_ * 0.5) continue;  // loose: the exact axis needs both fingers
      fingers.push_back(f);
    }
    return fingers;
  }

  // Whether thumb t and fingers f1, f2 oppose each other as the hand can: spread and aperture in
  // its ranges, each contact pushing along the thumb-to-fingers axis, the fingers side by side and
  // their sideways pushes cancelling, and all three able to push within their plane.
  std::optional<Opposition> opposition(std::size_t t, std::size_t f1, std::size_t f2) const {
    const Eigen::Vector3d tp = s_[t].position;
    const Eigen::Vector3d tn = -s_[t].normal;
    const Eigen::Vector3d p1 = s_[f1].position, p2 = s_[f2].position;
    const double spread2 = (p1 - p2).squaredNorm();  // no root for the many pairs out of range
    if (spread2 < min_spread2_ || spread2 > max_spread2_) return std::nullopt;
    const double spread = std::sqrt(spread2);
    const Eigen::Vector3d mid = (p1 + p2) / 2;
    const double aperture = (mid - tp).norm();
    if (aperture < hand_.aperture_min || aperture > hand_.aperture_max) return std::nullopt;
    const Eigen::Vector3d axis = (mid - tp) / aperture;
    if (tn.dot(axis) < cos_thumb_) return std::nullopt;
    if (-s_[f1].normal.dot(-axis) < cos_finger_ || -s_[f2].normal.dot(-axis) < cos_finger_) return std::nullopt;
    // The fingers' sideways pushes cancel: their resultant opposes the thumb.
    const Eigen::Vector3d resultant = -s_[f1].normal - s_[f2].normal;
    if (angle_between(resultant, -axis) > balance_) return std::nullopt;
    if (std::abs((p1 - p2).dot(axis)) > 0.5 * spread) return std::nullopt;  // side by side, not one behind the other
    const Eigen::Vector3d plane = (p1 - tp).cross(p2 - tp);
    if (plane.norm() < 1e-12) return std::nullopt;
    const Eigen::Vector3d normal = plane.normalized();
    // Three forces in equilibrium lie in one plane: each contact must be able to push within it.
    if (std::abs(s_[t].normal.dot(normal)) > sin_plane_ || std::abs(s_[f1].normal.dot(normal)) > sin_plane_ ||
        std::abs(s_[f2].normal.dot(normal)) > sin_plane_)
      return std::nullopt;
    return Opposition{normal, spread, aperture};
  }

  // The grasp of thumb t and fingers f1, f2 (contacts, approach nearest the preferred one, spread,
  // aperture) with its scores, its samples and their regions.
  GraspCandidate scored_candidate(std::size_t t, std::size_t f1, std::size_t f2, const Opposition& o) const {
    const Eigen::Vector3d tp = s_[t].position, p1 = s_[f1].position, p2 = s_[f2].position;
    // S1: angles around the object's centre (projected on the contacts' plane) near 120 degrees,
    // and the triangle's centre near the object's.
    const Eigen::Vector3d c = centre_ - (centre_ - tp).dot(o.normal) * o.normal;
    const std::array<Eigen::Vector3d, 3> v = {tp - c, p1 - c, p2 - c};
    double deviation = 0;
    for (int k = 0; k < 3; ++k) deviation = std::max(deviation, std::abs(angle_between(v[k], v[(k + 1) % 3]) / kDeg - 120.0));
    const double radius = (v[0].norm() + v[1].norm() + v[2].norm()) / 3;
    const double off_centre = ((tp + p1 + p2) / 3 - centre_).norm();
    const double symmetry = std::max(0.0, 1 - deviation / 120.0) * std::max(0.0, 1 - off_centre / std::max(radius, 1e-12));
    const double safety = std::min({s3(t), s3(f1), s3(f2)});
    const double curvature = (s4(t) + s4(f1) + s4(f2)) / 3;

    GraspCandidate cand;
    Grasp& g = cand.grasp;
    g.contacts = {GraspContact{tp, -s_[t].normal}, GraspContact{p1, -s_[f1].normal}, GraspContact{p2, -s_[f2].normal}};
    g.approach = o.normal.dot(preferred_) >= 0 ? o.normal : Eigen::Vector3d(-o.normal);
    g.spread = o.spread;
    g.aperture = std::min(o.aperture + hand_.finger_width, hand_.aperture_max + hand_.finger_width);
    g.scores = {symmetry, safety, curvature,
                (p_.weight_symmetry * symmetry + p_.weight_safety * safety + p_.weight_curvature * curvature) / weights_};
    cand.samples = {t, f1, f2};
    cand.regions = {region_of_[t], region_of_[f1], region_of_[f2]};
    return cand;
  }

  // S3: how far inside its region a sample lies, 1 from safety_reference on.
  double s3(std::size_t i) const { return std::min(1.0, boundary_distance_[i] / safety_ref_); }
  // S4: slightly concave best, then flat, then convex.
  double s4(std::size_t i) const { return std::clamp(0.5 - 0.5 * s_[i].curvature / p_.curvature_scale, 0.0, 1.0); }

  // Whether the hand takes g clear of the table (Clear without one). The robot's own hand at each
  // pose, whatever the approach: on its pads, else as a pinch (table_fit, which sets
  // g.pinch_depth). Without it, HandGeometry's hand from above or level only (g.approach turned
  // down if it points up: from below, the hand would come through the table), at the grasp and
  // at its pregrasp.
  TableFit table_check(Grasp& g) const {
    if (!p_.table_z) return TableFit::Clear;
    if (p_.robot_hand) return table_fit(g, p_.robot_hand, *p_.table_z, p_.table_clearance);
    if (g.approach.z() > 1e-9) g.approach = -g.approach;
    const double floor = *p_.table_z + p_.table_clearance;
    if (hand_lowest_z(g, hand_) < floor || hand_lowest_z(g, hand_, p_.pregrasp_distance) < floor) return TableFit::Table;
    return TableFit::Clear;
  }

  // A candidate is uncertain when a contact or a sample beside one is unresolved; its contacts are
  // when one of them is.
  void mark_uncertain(GraspCandidate& cand) const {
    for (std::size_t i : cand.samples) {
      cand.contacts_uncertain = cand.contacts_uncertain || s_[i].unresolved();
      for (std::size_t j : nb_[i]) cand.uncertain = cand.uncertain || s_[j].unresolved();
    }
    cand.uncertain = cand.uncertain || cand.contacts_uncertain;
  }

  const std::vector<SurfaceSample>& s_;
  const Neighbourhoods& nb_;
  const std::vector<std::size_t>& region_of_;
  const std::vector<double>& boundary_distance_;
  const std::vector<std::size_t>& pool_;
  const Eigen::Vector3d centre_;
  const SynthesisParams& p_;
  const HandGeometry& hand_;
  const double safety_ref_, cos_thumb_, cos_finger_, balance_, sin_plane_, reach_, min_spread2_, max_spread2_;
  const Eigen::Vector3d preferred_;
  const double weights_;
};

// Every thumb's candidates, the thumbs searched at once with a parallel_for and their candidates
// joined in the thumbs' order (the same list whatever the threads), best total first; the table's
// leaving-outs counted in result.
std::vector<GraspCandidate> search_candidates(const CandidateSearch& search, const std::vector<std::size_t>& thumbs,
                                              const ParallelFor& parallel_for, SynthesisResult& result) {
  std::vector<ThumbCandidates> per_thumb(thumbs.size());
  for_each_index(parallel_for, thumbs.size(), [&](std::size_t ti) { per_thumb[ti] = search.for_thumb(thumbs[ti]); });
  std::vector<GraspCandidate> all;
  for (ThumbCandidates& c : per_thumb) {
    result.below_table += c.below_table;
    result.hand_unfit += c.hand_unfit;
    std::move(c.candidates.begin(), c.candidates.end(), std::back_inserter(all));
  }
  std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.grasp.scores.total > b.grasp.scores.total; });
  return all;
}

// Distinct candidates: one whose contacts all lie within a finger's width of another's (fingers
// swapped or not) adds nothing to it.
bool same_contacts(const GraspCandidate& a, const GraspCandidate& b, double finger_width) {
  auto near = [&](int i, int j) { return (a.grasp.contacts[i].position - b.grasp.contacts[j].position).norm() < finger_width; };
  return near(0, 0) && ((near(1, 1) && near(2, 2)) || (near(1, 2) && near(2, 1)));
}

// Force closure on the model: the contacts where the model puts them, pushing along its normals,
// their friction cones narrowed by normal_error_deg (inscribed_cone_deg).
QualityParams model_quality(const SynthesisParams& p) {
  QualityParams quality;
  quality.friction = p.friction;
  if (p.normal_error_deg > 0) quality.friction = std::tan((inscribed_cone_deg(p.friction) - p.normal_error_deg) * kDeg);
  return quality;
}

// The candidates kept, from `all` (best total first) into result.candidates: taken in order, each
// kept unless it repeats one kept, its S1 is under min_symmetry, the model stands in the hand's way, or it is not force closure
// on the model about the object's centre (torques over the samples' farthest distance from it, as
// the true measure scales them by r_max); at most max_candidates of each kind (see below), after
// at most max_checks force-closure checks. The hulls (the costly part) are computed ahead, a few at once with a
// parallel_for, for the next candidates that repeat none kept so far and the hand can take: the
// same choices as one at a time, a hull now and then computed for nothing.
void select_candidates(std::vector<GraspCandidate>& all, const std::vector<SurfaceSample>& s, const SynthesisParams& p,
                       SynthesisResult& result) {
  const HandGeometry& hand = p.hand;
  const Eigen::Vector3d centre = result.centre;
  const SampleCells cells(s, hand.finger_width);
  double r_max = 0;
  for (const auto& x : s) r_max = std::max(r_max, (x.position - centre).norm());
  const QualityParams quality = model_quality(p);
  auto repeats = [&](const GraspCandidate& c) {
    return std::any_of(result.candidates.begin(), result.candidates.end(),
                       [&](const auto& k) { return same_contacts(c, k, hand.finger_width); });
  };
  auto asymmetric = [&](const GraspCandidate& c) { return c.grasp.scores.symmetry < p.min_symmetry; };
  std::vector<signed char> blocked(all.size(), -1);  // -1: not checked yet
  auto hand_blocked = [&](std::size_t i) {
    if (blocked[i] < 0) blocked[i] = p.path_tolerance > 0 && cells.hand_path_blocked(all[i].grasp, hand, p.path_tolerance);
    return blocked[i] == 1;
  };
  // Up to max_candidates of each kind: on resolved surface, on resolved contacts only, and not
  // resolved. Better-scoring candidates on surface not yet pinned by two views would otherwise
  // crowd the resolved ones out of the list, and with them the grasps selectable now.
  auto kind = [](const GraspCandidate& c) { return !c.uncertain ? 0 : !c.contacts_uncertain ? 1 : 2; };
  std::array<std::size_t, 3> kept{};
  auto full = [&](const GraspCandidate& c) { return kept[kind(c)] >= p.max_candidates; };
  std::vector<std::optional<GraspQuality>> quality_of(all.size());
  auto compute_ahead = [&](std::size_t first, std::size_t budget) {
    const std::size_t ahead = std::min<std::size_t>(p.parallel_for ? 8 : 1, budget);  // one thread: none ahead
    std::vector<std::size_t> next;
    for (std::size_t j = first; j < all.size() && next.size() < ahead; ++j)
      if (!quality_of[j] && !full(all[j]) && !asymmetric(all[j]) && !repeats(all[j]) && !hand_blocked(j)) next.push_back(j);
    auto compute = [&](std::size_t k) {
      GraspQuality q;
      try {
        q = evaluate_grasp(all[next[k]].grasp.contacts, centre, r_max, quality);
      } catch (const GraspQualityError&) {
        q = {};  // degenerate contacts (two coincide): no grasp at all
      }
      quality_of[next[k]] = q;
    };
    for_each_index(p.parallel_for, next.size(), compute);
  };
  std::size_t checks = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    GraspCandidate& c = all[i];
    if (std::all_of(kept.begin(), kept.end(), [&](std::size_t k) { return k >= p.max_candidates; })) break;
    if (full(c) || repeats(c)) continue;
    if (asymmetric(c)) {
      ++result.asymmetric;
      continue;
    }
    // The hand's way first, on every candidate in turn: a few microseconds each. Counting it in
    // max_checks let the blocked best candidates use up the search (the cracker box: 400 of 400
    // blocked from view 3 to view 8; the first free one at view 3 was the 444th).
    if (hand_blocked(i)) {
      ++result.hand_blocked;
      continue;
    }
    if (p.require_force_closure && r_max > 0) {
      if (checks++ >= p.max_checks) break;
      if (!quality_of[i]) compute_ahead(i, p.max_checks - checks + 1);
      const GraspQuality& q = *quality_of[i];
      if (!q.force_closure || q.epsilon < p.min_model_epsilon) {
        ++result.not_force_closure;
        continue;
      }
      c.model_epsilon = q.epsilon;
    }
    ++kept[kind(c)];
    result.candidates.push_back(std::move(c));
  }
}

// Whether a candidate's approach lies within level_tilt_deg of `preferred` and its squeeze axis
// (the thumb to the fingers' midpoint, across the approach) within level_squeeze_deg of
// perpendicular to it; a bound of 0 is no bound.
bool is_level(const Grasp& g, const Eigen::Vector3d& preferred, double level_tilt_deg, double level_squeeze_deg) {
  const Eigen::Vector3d down = preferred.normalized();
  const Eigen::Vector3d a = g.approach.normalized();
  if (level_tilt_deg > 0 && a.dot(down) < std::cos(level_tilt_deg * kDeg)) return false;
  if (level_squeeze_deg <= 0) return true;
  const Eigen::Vector3d across = (g.contacts[1].position + g.contacts[2].position) / 2 - g.contacts[0].position;
  const Eigen::Vector3d squeeze = across - a * a.dot(across);
  return squeeze.norm() < 1e-9 || std::abs(squeeze.normalized().dot(down)) <= std::sin(level_squeeze_deg * kDeg);
}

// The reliable candidates (total at least `reliable`) first, the level ones (is_level) before the
// others and the most stable on the model first within each; the rest in their order, by total.
void rank_reliable_first(std::vector<GraspCandidate>& candidates, double reliable, const SynthesisParams& p) {
  auto level = [&](const GraspCandidate& c) { return is_level(c.grasp, p.preferred_approach, p.level_tilt_deg, p.level_squeeze_deg); };
  std::stable_sort(candidates.begin(), candidates.end(), [&](const auto& a, const auto& b) {
    const bool ra = a.grasp.scores.total >= reliable, rb = b.grasp.scores.total >= reliable;
    if (ra != rb) return ra;
    if (!ra) return false;
    const bool la = level(a), lb = level(b);
    if (la != lb) return la;
    return a.model_epsilon > b.model_epsilon;
  });
}

}  // namespace

SynthesisResult synthesise(std::span<const SurfaceSample> input, const SynthesisParams& p) {
  check_params(p);
  const std::vector<SurfaceSample> s = normalised_input(input);
  const Neighbourhoods nb = NeighbourGrid(s, p.neighbour_radius).neighbourhoods(false, p.parallel_for);
  const double sharp = p.sharp_curvature > 0 ? p.sharp_curvature : 2.0 / p.hand.finger_width;

  SynthesisResult result;
  const std::vector<std::size_t> region_of = grow_regions(s, nb, sharp, p.max_normal_step_deg * kDeg, result.regions);
  result.boundary_distance = boundary_distances(s, nb, region_of, p.neighbour_radius);
  result.uncertain_regions = uncertain_regions(result.regions);

  const std::vector<std::size_t> pool = contact_pool(s, region_of, p, result);
  if (pool.size() < 3) return result;
  const std::vector<std::size_t> thumbs(pool.begin(), pool.begin() + std::min(pool.size(), p.max_thumbs));
  result.centre = object_centre(s, p);

  const CandidateSearch search(s, nb, region_of, result.boundary_distance, pool, result.centre, p);
  std::vector<GraspCandidate> all = search_candidates(search, thumbs, p.parallel_for, result);
  select_candidates(all, s, p, result);
  if (p.rank_total) rank_reliable_first(result.candidates, *p.rank_total, p);
  return result;
}

}  // namespace fba::grasp
