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
#include <numeric>
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

SynthesisResult synthesise(std::span<const SurfaceSample> input, const SynthesisParams& p) {
  check_params(p);
  const std::vector<SurfaceSample> s = normalised_input(input);
  const HandGeometry& hand = p.hand;
  const double sharp = p.sharp_curvature > 0 ? p.sharp_curvature : 2.0 / hand.finger_width;
  const double safety_ref = p.safety_reference > 0 ? p.safety_reference : hand.finger_width;
  const std::size_t n = s.size();
  const SampleCells cells(s, hand.finger_width);
  const std::vector<std::vector<std::size_t>> nb = NeighbourGrid(s, p.neighbour_radius).neighbourhoods(false, p.parallel_for);

  // Regions: connected graspable samples whose normals turn gently.
  const double max_step = p.max_normal_step_deg * kDeg;
  std::vector<bool> graspable(n);
  for (std::size_t i = 0; i < n; ++i) graspable[i] = std::abs(s[i].curvature) <= sharp;
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> region_of(n, kNone);
  SynthesisResult result;
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (!graspable[seed] || region_of[seed] != kNone) continue;
    const std::size_t r = result.regions.size();
    GraspRegion region;
    std::vector<std::size_t> stack{seed};
    region_of[seed] = r;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      region.samples.push_back(i);
      for (std::size_t j : nb[i])
        if (graspable[j] && region_of[j] == kNone && angle_between(s[i].normal, s[j].normal) <= max_step) {
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
    result.regions.push_back(std::move(region));
  }

  // Safety margin: distance within the region to its boundary, where a sample borders another
  // region, an ungraspable sample, or no samples at all (its neighbours all lie to one side).
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (std::size_t i = 0; i < n; ++i) {
    if (region_of[i] == kNone) continue;
    bool boundary = nb[i].size() < 3;
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    for (std::size_t j : nb[i]) {
      if (region_of[j] != region_of[i]) boundary = true;
      offset += s[j].position - s[i].position;
    }
    if (!nb[i].empty()) {
      offset /= static_cast<double>(nb[i].size());
      offset -= offset.dot(s[i].normal) * s[i].normal;
      if (offset.norm() > 0.35 * p.neighbour_radius) boundary = true;  // a one-sided neighbourhood
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
  result.boundary_distance.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    result.boundary_distance[i] = region_of[i] == kNone ? 0.0 : std::min(dist[i], 1e3);  // closed region: no boundary

  std::vector<std::size_t> order(result.regions.size());
  std::iota(order.begin(), order.end(), 0);
  for (std::size_t r : order)
    if (result.regions[r].uncertain_share > 0) result.uncertain_regions.push_back(r);
  std::stable_sort(result.uncertain_regions.begin(), result.uncertain_regions.end(), [&](std::size_t a, std::size_t b) {
    const auto& ra = result.regions[a];
    const auto& rb = result.regions[b];
    return ra.uncertain_share * ra.samples.size() > rb.uncertain_share * rb.samples.size();
  });

  // Candidates: a thumb opposing two fingers, within the hand's reach, each contact at least the
  // edge margin inside its region and high enough for a finger to touch above the table.
  std::vector<std::size_t> pool;
  for (std::size_t i = 0; i < n; ++i) {
    if (region_of[i] == kNone) continue;
    const bool near_edge = result.boundary_distance[i] < p.edge_margin;
    const bool too_low = !near_edge && p.table_z && p.robot_hand.finger_radius > 0 &&
                         s[i].position.z() - p.robot_hand.finger_radius * (1 - s[i].normal.z()) < *p.table_z + p.table_clearance;
    result.near_edge += near_edge;
    result.too_low += too_low;
    if (!near_edge && !too_low) pool.push_back(i);
  }
  std::mt19937 rng(0);  // a fixed shuffle: an even, reproducible subset of the surface
  std::shuffle(pool.begin(), pool.end(), rng);
  if (pool.size() < 3) return result;
  const std::vector<std::size_t> thumbs(pool.begin(), pool.begin() + std::min(pool.size(), p.max_thumbs));

  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  if (p.object_centre) {
    centre = *p.object_centre;
  } else {
    for (const auto& x : s) centre += x.position / static_cast<double>(n);
  }
  result.centre = centre;
  const double cos_thumb = std::cos(p.thumb_alignment_deg * kDeg);
  const double cos_finger = std::cos(p.finger_alignment_deg * kDeg);
  const double balance = p.balance_deg * kDeg;
  const double sin_plane = std::sin(p.plane_alignment_deg * kDeg);
  const double reach = std::hypot(hand.aperture_max, hand.spread_max / 2);
  const double min_spread = std::max(hand.spread_min, hand.finger_width);
  const double min_spread2 = min_spread * min_spread, max_spread2 = hand.spread_max * hand.spread_max;
  const Eigen::Vector3d preferred = p.preferred_approach.normalized();
  const double weights = p.weight_symmetry + p.weight_safety + p.weight_curvature;
  auto s4 = [&](std::size_t i) { return std::clamp(0.5 - 0.5 * s[i].curvature / p.curvature_scale, 0.0, 1.0); };
  auto s3 = [&](std::size_t i) { return std::min(1.0, result.boundary_distance[i] / safety_ref); };

  // Each thumb's candidates apart, at once with a parallel_for, then in the thumbs' order: the same
  // list whatever the threads.
  std::vector<std::vector<GraspCandidate>> per_thumb(thumbs.size());
  std::vector<std::size_t> below_table(thumbs.size(), 0), hand_unfit(thumbs.size(), 0);
  auto search = [&](std::size_t ti) {
    const std::size_t t = thumbs[ti];
    std::vector<GraspCandidate>& all = per_thumb[ti];
    const Eigen::Vector3d tp = s[t].position;
    const Eigen::Vector3d tn = -s[t].normal;  // inward: where the thumb pushes
    // Finger positions the thumb can oppose: in reach, facing back towards the thumb.
    std::vector<std::size_t> fingers;
    for (std::size_t f : pool) {
      if (fingers.size() >= p.max_fingers) break;
      const Eigen::Vector3d d = tp - s[f].position;
      const double len = d.norm();
      if (len < hand.aperture_min || len > reach) continue;
      if (-s[f].normal.dot(d / len) < cos_finger) continue;
      if (tn.dot(-d / len) < cos_thumb * 0.5) continue;  // loose: the exact axis needs both fingers
      fingers.push_back(f);
    }
    for (std::size_t a = 0; a < fingers.size(); ++a) {
      for (std::size_t b = a + 1; b < fingers.size(); ++b) {
        const std::size_t f1 = fingers[a], f2 = fingers[b];
        const Eigen::Vector3d p1 = s[f1].position, p2 = s[f2].position;
        const double spread2 = (p1 - p2).squaredNorm();  // no root for the many pairs out of range
        if (spread2 < min_spread2 || spread2 > max_spread2) continue;
        const double spread = std::sqrt(spread2);
        const Eigen::Vector3d mid = (p1 + p2) / 2;
        const double aperture = (mid - tp).norm();
        if (aperture < hand.aperture_min || aperture > hand.aperture_max) continue;
        const Eigen::Vector3d axis = (mid - tp) / aperture;
        if (tn.dot(axis) < cos_thumb) continue;
        if (-s[f1].normal.dot(-axis) < cos_finger || -s[f2].normal.dot(-axis) < cos_finger) continue;
        // The fingers' sideways pushes cancel: their resultant opposes the thumb.
        const Eigen::Vector3d resultant = -s[f1].normal - s[f2].normal;
        if (angle_between(resultant, -axis) > balance) continue;
        if (std::abs((p1 - p2).dot(axis)) > 0.5 * spread) continue;  // side by side, not one behind the other
        const Eigen::Vector3d plane = (p1 - tp).cross(p2 - tp);
        if (plane.norm() < 1e-12) continue;
        const Eigen::Vector3d normal = plane.normalized();
        // Three forces in equilibrium lie in one plane: each contact must be able to push within it.
        if (std::abs(s[t].normal.dot(normal)) > sin_plane || std::abs(s[f1].normal.dot(normal)) > sin_plane ||
            std::abs(s[f2].normal.dot(normal)) > sin_plane)
          continue;

        // S1: angles around the object's centre (projected on the contacts' plane) near 120
        // degrees, and the triangle's centre near the object's.
        const Eigen::Vector3d c = centre - (centre - tp).dot(normal) * normal;
        const std::array<Eigen::Vector3d, 3> v = {tp - c, p1 - c, p2 - c};
        double deviation = 0;
        for (int k = 0; k < 3; ++k)
          deviation = std::max(deviation, std::abs(angle_between(v[k], v[(k + 1) % 3]) / kDeg - 120.0));
        const double radius = (v[0].norm() + v[1].norm() + v[2].norm()) / 3;
        const double off_centre = ((tp + p1 + p2) / 3 - centre).norm();
        const double symmetry =
            std::max(0.0, 1 - deviation / 120.0) * std::max(0.0, 1 - off_centre / std::max(radius, 1e-12));
        const double safety = std::min({s3(t), s3(f1), s3(f2)});
        const double curvature = (s4(t) + s4(f1) + s4(f2)) / 3;

        GraspCandidate cand;
        Grasp& g = cand.grasp;
        g.contacts = {GraspContact{tp, tn}, GraspContact{p1, -s[f1].normal}, GraspContact{p2, -s[f2].normal}};
        g.approach = normal.dot(preferred) >= 0 ? normal : Eigen::Vector3d(-normal);
        g.spread = spread;
        g.aperture = std::min(aperture + hand.finger_width, hand.aperture_max + hand.finger_width);
        if (p.table_z && p.robot_hand) {
          // The robot's own hand at each pose, whatever the approach: on the pads, else as a pinch.
          const TableFit fit = table_fit(g, p.robot_hand, *p.table_z, p.table_clearance);
          if (fit != TableFit::Clear) {
            ++(fit == TableFit::Unfit ? hand_unfit : below_table)[ti];
            continue;
          }
        } else if (p.table_z) {
          // From above or level only: from below, the hand would come through the table.
          if (g.approach.z() > 1e-9) g.approach = -g.approach;
          const double floor = *p.table_z + p.table_clearance;
          if (hand_lowest_z(g, hand) < floor || hand_lowest_z(g, hand, p.pregrasp_distance) < floor) {
            ++below_table[ti];
            continue;
          }
        }
        g.scores = {symmetry, safety, curvature,
                    (p.weight_symmetry * symmetry + p.weight_safety * safety + p.weight_curvature * curvature) / weights};
        cand.samples = {t, f1, f2};
        cand.regions = {region_of[t], region_of[f1], region_of[f2]};
        for (std::size_t i : cand.samples) {
          cand.contacts_uncertain = cand.contacts_uncertain || s[i].unresolved();
          for (std::size_t j : nb[i]) cand.uncertain = cand.uncertain || s[j].unresolved();
        }
        cand.uncertain = cand.uncertain || cand.contacts_uncertain;
        all.push_back(std::move(cand));
      }
    }
  };
  for_each_index(p.parallel_for, thumbs.size(), search);
  std::vector<GraspCandidate> all;
  for (std::size_t ti = 0; ti < thumbs.size(); ++ti) {
    result.below_table += below_table[ti];
    result.hand_unfit += hand_unfit[ti];
    std::move(per_thumb[ti].begin(), per_thumb[ti].end(), std::back_inserter(all));
  }
  std::stable_sort(all.begin(), all.end(),
                   [](const auto& a, const auto& b) { return a.grasp.scores.total > b.grasp.scores.total; });
  // Distinct candidates: one whose contacts all lie within a finger's width of a better one's
  // (fingers swapped or not) adds nothing.
  auto same = [&](const GraspCandidate& a, const GraspCandidate& b) {
    auto near = [&](int i, int j) {
      return (a.grasp.contacts[i].position - b.grasp.contacts[j].position).norm() < hand.finger_width;
    };
    return near(0, 0) && ((near(1, 1) && near(2, 2)) || (near(1, 2) && near(2, 1)));
  };
  // Force closure on the model: the contacts where the model puts them, pushing along its normals,
  // about the object's centre; torques over the samples' farthest distance from it, as the true
  // measure scales them by r_max.
  double r_max = 0;
  for (const auto& x : s) r_max = std::max(r_max, (x.position - centre).norm());
  QualityParams quality;
  quality.friction = p.friction;
  if (p.normal_error_deg > 0) quality.friction = std::tan((inscribed_cone_deg(p.friction) - p.normal_error_deg) * kDeg);
  // The candidates are taken in order, each kept unless it repeats one kept, the hand cannot take
  // it, or it is not force closure. The hulls (the costly part) are computed ahead, a few at once
  // with a parallel_for, for the next candidates that repeat none kept so far and the hand can take:
  // the same choices as one at a time, a hull now and then computed for nothing.
  auto repeats = [&](const GraspCandidate& c) {
    return std::any_of(result.candidates.begin(), result.candidates.end(), [&](const auto& k) { return same(c, k); });
  };
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
      if (!quality_of[j] && !full(all[j]) && !repeats(all[j]) && !hand_blocked(j)) next.push_back(j);
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
  if (p.rank_total) {
    // The reliable candidates first, the most stable on the model first; the rest by total.
    const double reliable = *p.rank_total;
    std::stable_sort(result.candidates.begin(), result.candidates.end(), [&](const auto& a, const auto& b) {
      const bool ra = a.grasp.scores.total >= reliable, rb = b.grasp.scores.total >= reliable;
      if (ra != rb) return ra;
      return ra && a.model_epsilon > b.model_epsilon;
    });
  }
  return result;
}

}  // namespace fba::grasp
