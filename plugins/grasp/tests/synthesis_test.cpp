// Grasp synthesis on shapes whose answer is known, and on the YCB meshes against the independent
// quality measure.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <random>

#include "fba/geometry/mesh_io.hpp"
#include "fba/grasp/angles.hpp"
#include "fba/grasp/grasp_quality.hpp"
#include "fba/grasp/object_surface.hpp"
#include "fba/grasp/robot_hand.hpp"
#include "fba/grasp/synthesis.hpp"
#include "support/data_sets.hpp"

namespace fba::grasp {
namespace {

constexpr double kPi = std::numbers::pi;

// Samples on a regular grid over each surface, spacing about h, with outward normals.
std::vector<SurfaceSample> cylinder(double r, double height, double h) {
  std::vector<SurfaceSample> out;
  const int around = static_cast<int>(std::round(2 * kPi * r / h));
  for (int i = 0; i < around; ++i) {
    const double a = 2 * kPi * i / around;
    const Eigen::Vector3d radial(std::cos(a), std::sin(a), 0);
    for (double z = h / 2; z < height; z += h) out.push_back({r * radial + Eigen::Vector3d(0, 0, z), radial});
  }
  for (double x = -r; x <= r; x += h)
    for (double y = -r; y <= r; y += h) {
      if (std::hypot(x, y) > r - h / 4) continue;
      out.push_back({{x, y, 0}, {0, 0, -1}});
      out.push_back({{x, y, height}, {0, 0, 1}});
    }
  return out;
}

std::vector<SurfaceSample> box(const Eigen::Vector3d& size, double h) {
  std::vector<SurfaceSample> out;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side : {-1, 1})
      for (double a = h / 2; a < size[u]; a += h)
        for (double b = h / 2; b < size[v]; b += h) {
          SurfaceSample s;
          s.position[axis] = side * size[axis] / 2;
          s.position[u] = a - size[u] / 2;
          s.position[v] = b - size[v] / 2;
          s.normal = Eigen::Vector3d::Zero();
          s.normal[axis] = side;
          out.push_back(s);
        }
  }
  return out;
}

std::vector<SurfaceSample> sphere(double r, int count) {
  std::vector<SurfaceSample> out;
  const double golden = kPi * (3 - std::sqrt(5.0));  // Fibonacci sphere: even spacing
  for (int i = 0; i < count; ++i) {
    const double z = 1 - 2 * (i + 0.5) / count;
    const double rho = std::sqrt(1 - z * z);
    const Eigen::Vector3d n(rho * std::cos(golden * i), rho * std::sin(golden * i), z);
    out.push_back({r * n, n});
  }
  return out;
}

SynthesisParams params_for(double spacing) {
  SynthesisParams p;
  p.neighbour_radius = 2.2 * spacing;
  return p;
}

// The samples with their curvature estimated over the neighbourhood params_for(spacing) uses.
std::vector<SurfaceSample> curved(std::vector<SurfaceSample> samples, double spacing) {
  estimate_curvature(samples, params_for(spacing).neighbour_radius);
  return samples;
}

TEST(GraspSynthesis, CylinderBestGraspHasThreeContactsAroundTheAxis) {
  const double h = 0.005;
  auto samples = curved(cylinder(0.035, 0.12, h), h);
  const SynthesisResult r = synthesise(samples, params_for(h));
  ASSERT_FALSE(r.candidates.empty());
  const Grasp& g = r.candidates.front().grasp;
  EXPECT_GT(g.scores.symmetry, 0.9);
  // On the side, pushing radially inward, about 120 degrees apart around the axis.
  for (const auto& c : g.contacts) {
    EXPECT_NEAR(c.normal.z(), 0.0, 1e-9);
    EXPECT_NEAR(std::hypot(c.position.x(), c.position.y()), 0.035, 1e-9);
  }
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d a = g.contacts[k].position, b = g.contacts[(k + 1) % 3].position;
    a.z() = b.z() = 0;
    EXPECT_NEAR(angle_between_deg(a, b), 120.0, 15.0);
  }
  // Approach from above, near the axis: perpendicular to the contacts' plane, which the plane
  // alignment (10 degrees by default) keeps near level on a cylinder's side.
  EXPECT_LT(g.approach.z(), -std::cos(20.0 * kPi / 180));
  // The pregrasp opens wider than the contacts are apart, within the hand's range.
  const Eigen::Vector3d mid = (g.contacts[1].position + g.contacts[2].position) / 2;
  EXPECT_GT(g.aperture, (mid - g.contacts[0].position).norm());
  EXPECT_NEAR(g.spread, (g.contacts[1].position - g.contacts[2].position).norm(), 1e-12);
  // The whole side is one region bounded by the rims; the caps are two more.
  EXPECT_EQ(r.regions.size(), 3u);
  EXPECT_TRUE(r.uncertain_regions.empty());
}

TEST(GraspSynthesis, BoxBestGraspOpposesAThumbOnOneFaceToTwoFingersOnTheOpposite) {
  const double h = 0.005;
  auto samples = curved(box({0.06, 0.10, 0.15}, h), h);
  const SynthesisResult r = synthesise(samples, params_for(h));
  EXPECT_EQ(r.regions.size(), 6u);  // one per face: the edges are sharp
  ASSERT_FALSE(r.candidates.empty());
  const Grasp& g = r.candidates.front().grasp;
  const Eigen::Vector3d thumb = g.contacts[0].normal;
  EXPECT_LT(angle_between_deg(g.contacts[1].normal, -thumb), 1e-6);
  EXPECT_LT(angle_between_deg(g.contacts[2].normal, -thumb), 1e-6);
  EXPECT_NEAR(std::abs(thumb.x()) + std::abs(thumb.y()) + std::abs(thumb.z()), 1.0, 1e-9);  // a face normal
  // The fingers sit apart by at least a finger's width, and each contact well inside its face.
  EXPECT_GE(g.spread, SynthesisParams{}.hand.finger_width);
  EXPECT_GT(g.scores.safety_margin, 0.5);
  EXPECT_NEAR(g.scores.curvature, 0.5, 0.05);  // flat
}

// A low object on a table: with the table known, no candidate puts the fingertips or the palm
// into it; contacts on a cylinder lying on the table sit high enough for the fingertips to clear.
TEST(GraspSynthesis, WithATableNoCandidateReachesIntoIt) {
  const double h = 0.004;
  // A cylinder 3.7 cm across lying along x on the table (z = 0), as a banana lies.
  std::vector<SurfaceSample> lying;
  for (auto s : cylinder(0.0185, 0.12, h)) {
    s.position = Eigen::Vector3d(s.position.z() - 0.06, s.position.y(), s.position.x() + 0.0185);
    s.normal = Eigen::Vector3d(s.normal.z(), s.normal.y(), s.normal.x());
    lying.push_back(s);
  }
  const auto samples = curved(lying, h);
  SynthesisParams p = params_for(h);
  const SynthesisResult free = synthesise(samples, p);
  p.table_z = 0.0;
  const SynthesisResult tabled = synthesise(samples, p);
  EXPECT_GT(tabled.below_table, 0u);
  const auto lowest_without = std::min_element(free.candidates.begin(), free.candidates.end(), [&](const auto& a, const auto& b) {
    return hand_lowest_z(a.grasp, p.hand) < hand_lowest_z(b.grasp, p.hand);
  });
  ASSERT_NE(lowest_without, free.candidates.end());
  EXPECT_LT(hand_lowest_z(lowest_without->grasp, p.hand), 0.0) << "without the table some candidate reaches below it";
  for (const auto& c : tabled.candidates) {
    EXPECT_LE(c.grasp.approach.z(), 0.0);
    EXPECT_GE(hand_lowest_z(c.grasp, p.hand), p.table_clearance);
    EXPECT_GE(hand_lowest_z(c.grasp, p.hand, p.pregrasp_distance), p.table_clearance);
  }
}

TEST(GraspSynthesis, TheHandsLowestPointFollowsItsGeometry) {
  Grasp g;
  g.contacts = {GraspContact{{-0.03, 0, 0.05}, {1, 0, 0}}, GraspContact{{0.03, 0.02, 0.05}, {-1, 0, 0}},
                GraspContact{{0.03, -0.02, 0.05}, {-1, 0, 0}}};
  g.approach = {0, 0, -1};
  HandGeometry hand;
  // From above: the fingertips, tip_length below the contacts.
  EXPECT_NEAR(hand_lowest_z(g, hand), 0.05 - hand.tip_length, 1e-12);
  // Moved back along the approach, they rise with the hand.
  EXPECT_NEAR(hand_lowest_z(g, hand, 0.05), 0.1 - hand.tip_length, 1e-12);
  // From the side (along -x would be the thumb's way: along y here): the palm spans its width
  // (thumb to fingers, along x: level) and its depth (across, along z) about the contacts' height.
  g.approach = {0, 1, 0};
  EXPECT_NEAR(hand_lowest_z(g, hand), 0.05 - hand.palm_half_depth, 1e-12);
}

// The robot hand's shapes (robot_hand.hpp): a finger's cylinder reaches lowest on the rim of its
// lower end, a box at its lowest corner.
TEST(GraspSynthesis, AHandShapesLowestPointIsOnItsRimOrCorner) {
  const double tilt = 30 * std::numbers::pi / 180;
  fba::grasp::HandShape finger{"thumb", fba::grasp::HandShape::Kind::Cylinder, {0.01, 0.04, 0}, Eigen::Isometry3d::Identity()};
  finger.world_from_shape = Eigen::Translation3d(0, 0, 0.1) * Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX());
  EXPECT_NEAR(fba::grasp::lowest_z(finger), 0.1 - 0.02 * std::cos(tilt) - 0.01 * std::sin(tilt), 1e-12);
  finger.world_from_shape = Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.1));  // upright: the flat end
  EXPECT_NEAR(fba::grasp::lowest_z(finger), 0.08, 1e-12);
  fba::grasp::HandShape palm{"palm", fba::grasp::HandShape::Kind::Box, {0.11, 0.065, 0.02}, finger.world_from_shape};
  palm.world_from_shape.rotate(Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()));
  EXPECT_NEAR(fba::grasp::lowest_z(palm), 0.1 - 0.065 * std::sin(tilt) - 0.02 * std::cos(tilt), 1e-12);
}

TEST(GraspSynthesis, EstimatingCurvatureRefusesASampleThatIsNotFinite) {
  std::vector<SurfaceSample> samples(3, SurfaceSample{});
  for (auto& s : samples) s.normal = {0, 0, 1};
  samples[1].position.y() = std::numeric_limits<double>::quiet_NaN();  // not x: maxCoeff may pass over it
  EXPECT_THROW(estimate_curvature(samples, 0.01), std::invalid_argument);
}

TEST(GraspSynthesis, CurvatureScoreOrdersConcaveAboveFlatAboveSphere) {
  const double h = 0.005;
  auto flat = curved(box({0.06, 0.10, 0.15}, h), h);
  auto ball = sphere(0.04, 2000);
  estimate_curvature(ball, 0.012);
  auto concave = flat;  // the same box with its faces declared slightly hollow
  for (auto& s : concave) s.curvature = std::min(s.curvature, 0.0) - 10.0;
  SynthesisParams pb = params_for(h), ps;
  ps.neighbour_radius = 0.012;
  const double s4_flat = synthesise(flat, pb).candidates.at(0).grasp.scores.curvature;
  const double s4_concave = synthesise(concave, pb).candidates.at(0).grasp.scores.curvature;
  const auto on_ball = synthesise(ball, ps);
  ASSERT_FALSE(on_ball.candidates.empty());
  const double s4_ball = on_ball.candidates.front().grasp.scores.curvature;
  EXPECT_GT(s4_concave, s4_flat);
  EXPECT_GT(s4_flat, s4_ball);
  // A sphere of radius 4 cm has mean curvature 25 /m.
  for (std::size_t i = 0; i < ball.size(); i += 97) EXPECT_NEAR(ball[i].curvature, 25.0, 2.5);
}

TEST(GraspSynthesis, UncertainSamplesNameTheirRegionAndFlagCandidates) {
  const double h = 0.005;
  auto samples = curved(box({0.06, 0.10, 0.15}, h), h);
  for (auto& s : samples)
    if (s.normal.x() > 0.5) s.uncertain = true;  // the +x face is not yet seen well
  const SynthesisParams p = params_for(h);
  const SynthesisResult r = synthesise(samples, p);
  ASSERT_EQ(r.uncertain_regions.size(), 1u);
  const GraspRegion& region = r.regions[r.uncertain_regions[0]];
  EXPECT_NEAR(region.normal.x(), 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(region.uncertain_share, 1.0);
  double face_x = -1;  // the unseen face's plane
  for (const auto& s : samples) face_x = std::max(face_x, s.position.x());
  int flagged = 0, clear = 0;
  for (const auto& c : r.candidates) {
    bool touches = false, near = false;  // a contact on the unseen face; within the neighbourhood of it
    for (const auto& k : c.grasp.contacts) {
      touches = touches || k.normal.x() < -0.5;
      near = near || face_x - k.position.x() <= p.neighbour_radius + h;
    }
    if (touches) EXPECT_TRUE(c.uncertain && c.contacts_uncertain);
    if (!near) EXPECT_FALSE(c.uncertain);
    flagged += c.uncertain;
    clear += !c.uncertain;
  }
  // Both kinds are returned: the unseen face's better candidates do not crowd the others out.
  EXPECT_GT(flagged, 0);
  EXPECT_GT(clear, 0);
}

// max_candidates bounds each kind apart (on resolved surface, on resolved contacts only, neither):
// a grasp selectable now is returned however many better ones wait for views.
TEST(GraspSynthesis, CandidatesOnResolvedSurfaceAreNotCrowdedOutByUnresolvedOnes) {
  const double h = 0.005;
  auto samples = curved(box({0.06, 0.10, 0.15}, h), h);
  for (auto& s : samples)
    if (s.normal.x() > 0.5) s.uncertain = true;
  SynthesisParams p = params_for(h);
  p.max_candidates = 1;
  const SynthesisResult r = synthesise(samples, p);
  int resolved = 0, unresolved = 0;
  for (const auto& c : r.candidates) (c.uncertain ? unresolved : resolved) += 1;
  EXPECT_EQ(resolved, 1);
  EXPECT_GE(unresolved, 1);
  EXPECT_LE(r.candidates.size(), 3u);
}

// Pinning is checked over each contact's neighbourhood; the contacts themselves are flagged apart
// (what grasp.synthesis settles for after its last view).
TEST(GraspSynthesis, UnpinnedSurfaceBesideAContactFlagsTheCandidateButNotItsContacts) {
  const double h = 0.005;
  auto samples = curved(box({0.06, 0.10, 0.15}, h), h);
  const SynthesisResult all = synthesise(samples, params_for(h));
  ASSERT_FALSE(all.candidates.empty());
  const GraspCandidate& best = all.candidates.front();
  ASSERT_FALSE(best.uncertain);
  ASSERT_FALSE(best.contacts_uncertain);
  // Unpin one sample beside the best candidate's thumb, inside its neighbourhood.
  const Eigen::Vector3d thumb = samples[best.samples[0]].position;
  std::size_t beside = samples.size();
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const double d = (samples[i].position - thumb).norm();
    if (d > 0.5 * h && d < 1.5 * h) beside = i;
  }
  ASSERT_LT(beside, samples.size());
  samples[beside].unpinned = true;
  const SynthesisResult r = synthesise(samples, params_for(h));
  bool found = false;
  for (const auto& c : r.candidates)
    if (c.samples == best.samples) {
      found = true;
      EXPECT_TRUE(c.uncertain);
      EXPECT_FALSE(c.contacts_uncertain);
    }
  EXPECT_TRUE(found);
  // The thumb's own sample unpinned: both.
  samples[best.samples[0]].unpinned = true;
  for (const auto& c : synthesise(samples, params_for(h)).candidates)
    if (c.samples == best.samples) {
      EXPECT_TRUE(c.uncertain);
      EXPECT_TRUE(c.contacts_uncertain);
    }
}

TEST(GraspSynthesis, AnObjectTooBigForTheHandGivesNoCandidate) {
  const double h = 0.01;
  auto samples = curved(box({0.4, 0.4, 0.4}, h), h);
  const SynthesisResult r = synthesise(samples, params_for(h));
  EXPECT_TRUE(r.candidates.empty());
  EXPECT_EQ(r.regions.size(), 6u);
}

// The model's own force closure: every candidate kept is force closure on the samples it was
// found on (contacts, the samples' inward normals, torques about their mean over their largest
// distance from it), with the epsilon it reports.
TEST(GraspSynthesis, EveryCandidateIsForceClosureOnTheModel) {
  const double h = 0.005;
  for (const auto& shape : {cylinder(0.035, 0.12, h), box({0.06, 0.10, 0.15}, h), sphere(0.04, 1500)}) {
    const auto samples = curved(shape, h);
    const SynthesisResult r = synthesise(samples, params_for(h));
    ASSERT_FALSE(r.candidates.empty());
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& x : samples) centre += x.position / static_cast<double>(samples.size());
    double r_max = 0;
    for (const auto& x : samples) r_max = std::max(r_max, (x.position - centre).norm());
    for (const auto& c : r.candidates) {
      const GraspQuality q = evaluate_grasp(c.grasp.contacts, centre, r_max);
      EXPECT_TRUE(q.force_closure);
      EXPECT_NEAR(c.model_epsilon, q.epsilon, 1e-12);
      EXPECT_GT(c.model_epsilon, 0.0);
    }
  }
}

// Without friction three point contacts never hold an object (form closure needs seven): the
// check leaves every candidate out and says so.
TEST(GraspSynthesis, FrictionlessThreeContactsAreNeverKept) {
  const double h = 0.005;
  auto samples = curved(cylinder(0.035, 0.12, h), h);
  SynthesisParams p = params_for(h);
  p.friction = 0;
  const SynthesisResult r = synthesise(samples, p);
  EXPECT_TRUE(r.candidates.empty());
  EXPECT_GT(r.not_force_closure, 0u);
  p.require_force_closure = false;
  EXPECT_FALSE(synthesise(samples, p).candidates.empty()) << "the geometric filters alone keep candidates";
}

// The normal turned by `deg` degrees about a random axis perpendicular to it.
Eigen::Vector3d turned(const Eigen::Vector3d& n, double deg, std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  while (axis.norm() < 1e-6) axis = n.cross(Eigen::Vector3d(g(rng), g(rng), g(rng)));
  return Eigen::AngleAxisd(deg * kPi / 180, axis.normalized()) * n;
}

// A carved model's normals are off the true surface's. Allowing for it, every candidate stays force
// closure with each of its normals turned that far in any direction; without it, some do not. The
// opposition is loosened (the defaults' margins alone keep these perfect shapes' candidates closed).
TEST(GraspSynthesis, ACandidateAllowingForNormalErrorStaysClosedWithItsNormalsTurnedThatFar) {
  const double h = 0.005, error_deg = 10;
  std::mt19937 rng(7);
  std::size_t plain_opened = 0;
  for (const auto& shape : {cylinder(0.035, 0.12, h), box({0.06, 0.10, 0.15}, h)}) {
    const auto samples = curved(shape, h);
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& x : samples) centre += x.position / static_cast<double>(samples.size());
    double r_max = 0;
    for (const auto& x : samples) r_max = std::max(r_max, (x.position - centre).norm());
    auto stays_closed = [&](const GraspCandidate& c) {
      for (int trial = 0; trial < 20; ++trial) {
        auto contacts = c.grasp.contacts;
        for (auto& k : contacts) k.normal = turned(k.normal, error_deg, rng);
        if (!evaluate_grasp(contacts, centre, r_max).force_closure) return false;
      }
      return true;
    };
    SynthesisParams p = params_for(h);
    p.thumb_alignment_deg = 25;
    p.balance_deg = 25;
    p.plane_alignment_deg = 25;
    for (const auto& c : synthesise(samples, p).candidates)
      if (plain_opened == 0) plain_opened += stays_closed(c) ? 0 : 1;
    p.normal_error_deg = error_deg;
    const SynthesisResult robust = synthesise(samples, p);
    ASSERT_FALSE(robust.candidates.empty());
    for (const auto& c : robust.candidates) EXPECT_TRUE(stays_closed(c)) << c.grasp.contacts[0].position.transpose();
  }
  EXPECT_GT(plain_opened, 0u) << "on these shapes some candidates closed only with exact normals";
}

// A floor on one measure of the candidates (`measure`), set by `set_floor` at its median over the
// candidates on a curved box without it: fewer are kept, none of them under it. The result with
// the floor.
template <class Measure, class SetFloor>
SynthesisResult expect_a_floor_at_the_median_leaves_out_those_under_it(Measure measure, SetFloor set_floor) {
  const double h = 0.005;
  auto samples = curved(box({0.06, 0.10, 0.15}, h), h);
  SynthesisParams p = params_for(h);
  p.max_candidates = 1000;
  const SynthesisResult all = synthesise(samples, p);
  std::vector<double> values;
  for (const auto& c : all.candidates) values.push_back(measure(c));
  EXPECT_GT(values.size(), 4u);
  const double floor = values.empty() ? 0.0 : quantile(values, 0.5);
  set_floor(p, floor);
  SynthesisResult floored = synthesise(samples, p);
  EXPECT_LT(floored.candidates.size(), all.candidates.size());
  EXPECT_FALSE(floored.candidates.empty());
  for (const auto& c : floored.candidates) EXPECT_GE(measure(c), floor);
  return floored;
}

TEST(GraspSynthesis, MinimumModelEpsilonLeavesOutTheLessStable) {
  expect_a_floor_at_the_median_leaves_out_those_under_it([](const GraspCandidate& c) { return c.model_epsilon; },
                                                         [](SynthesisParams& p, double floor) { p.min_model_epsilon = floor; });
}

// S1's floor counts the candidates it leaves out.
TEST(GraspSynthesis, MinimumSymmetryLeavesOutTheLopsided) {
  const SynthesisResult even = expect_a_floor_at_the_median_leaves_out_those_under_it(
      [](const GraspCandidate& c) { return c.grasp.scores.symmetry; }, [](SynthesisParams& p, double floor) { p.min_symmetry = floor; });
  EXPECT_GT(even.asymmetric, 0u);
  SynthesisParams beyond;
  beyond.min_symmetry = 1.5;
  EXPECT_THROW(synthesise(curved(box({0.06, 0.10, 0.15}, 0.005), 0.005), beyond), std::invalid_argument);
}

// With a reliability threshold, the candidates reaching it come first, the most stable on the
// model first; the others follow by total.
TEST(GraspSynthesis, ReliableCandidatesComeMostStableFirst) {
  const double h = 0.005;
  auto samples = curved(cylinder(0.035, 0.12, h), h);
  SynthesisParams p = params_for(h);
  const SynthesisResult by_total = synthesise(samples, p);
  ASSERT_GT(by_total.candidates.size(), 2u);
  p.rank_total = by_total.candidates[by_total.candidates.size() / 2].grasp.scores.total;
  const SynthesisResult ranked = synthesise(samples, p);
  ASSERT_EQ(ranked.candidates.size(), by_total.candidates.size());
  bool reliable = true;
  for (std::size_t i = 0; i < ranked.candidates.size(); ++i) {
    const auto& c = ranked.candidates[i];
    const bool here = c.grasp.scores.total >= *p.rank_total;
    EXPECT_FALSE(here && !reliable) << "a reliable candidate after an unreliable one at " << i;
    reliable = here;
    if (i == 0) continue;
    const auto& before = ranked.candidates[i - 1];
    if (here) EXPECT_LE(c.model_epsilon, before.model_epsilon) << i;
    else if (before.grasp.scores.total < *p.rank_total) EXPECT_LE(c.grasp.scores.total, before.grasp.scores.total) << i;
  }
  double best_reliable_epsilon = 0;
  for (const auto& c : by_total.candidates)
    if (c.grasp.scores.total >= *p.rank_total) best_reliable_epsilon = std::max(best_reliable_epsilon, c.model_epsilon);
  EXPECT_EQ(ranked.candidates.front().model_epsilon, best_reliable_epsilon);
}

// On a ball, where every tilt of the hand has candidates and every one counts as reliable (the
// ranking alone is checked): the most stable candidate is not `level`; with the preference that
// `prefer` sets, the level ones come before every other, the most stable first within each group.
template <class Level, class Prefer>
void expect_level_first_on_a_ball(Level level, Prefer prefer) {
  auto samples = sphere(0.04, 1500);
  estimate_curvature(samples, 0.006);
  SynthesisParams p = params_for(0.003);
  p.rank_total = 0;
  const SynthesisResult any = synthesise(samples, p);
  ASSERT_GT(any.candidates.size(), 2u);
  ASSERT_FALSE(level(any.candidates.front())) << "the most stable is level already: the preference has nothing to change";
  prefer(p);
  const std::vector<GraspCandidate> ranked = synthesise(samples, p).candidates;
  ASSERT_EQ(ranked.size(), any.candidates.size());
  bool before = true;
  for (std::size_t i = 0; i < ranked.size(); ++i) {
    const bool here = level(ranked[i]);
    EXPECT_FALSE(here && !before) << "a level candidate after one that is not, at " << i;
    if (i > 0 && here == before) EXPECT_LE(ranked[i].model_epsilon, ranked[i - 1].model_epsilon) << i;
    before = here;
  }
  EXPECT_TRUE(level(ranked.front()));
}

// The most stable candidate on a ball comes in steep: with level_tilt_deg the reliable ones whose
// approach is within that angle of straight down come first.
TEST(GraspSynthesis, LevelApproachesRankBeforeSteepOnesAmongTheReliable) {
  expect_level_first_on_a_ball(
      [](const GraspCandidate& c) { return std::acos(std::clamp(-c.grasp.approach.normalized().z(), -1.0, 1.0)) * 180 / kPi <= 30; },
      [](SynthesisParams& p) { p.level_tilt_deg = 30; });
}

// The most stable candidate on a ball squeezes on a slope: with level_squeeze_deg the reliable ones
// whose squeeze axis (the thumb to the fingers' midpoint, across the approach) lies within that
// angle of level come first.
TEST(GraspSynthesis, LevelSqueezesRankBeforeSlopingOnesAmongTheReliable) {
  expect_level_first_on_a_ball(
      [](const GraspCandidate& c) {
        const Grasp& g = c.grasp;
        const Eigen::Vector3d a = g.approach.normalized();
        const Eigen::Vector3d across = (g.contacts[1].position + g.contacts[2].position) / 2 - g.contacts[0].position;
        return std::asin(std::min(1.0, std::abs((across - a * a.dot(across)).normalized().z()))) * 180 / kPi <= 10;
      },
      [](SynthesisParams& p) { p.level_squeeze_deg = 10; });
}

// The thumb at x = -0.03, the fingers at x = +0.03 (y = +-0.02), 5 cm above the table, from above.
Grasp grasp_across_x(double z) {
  Grasp g;
  g.contacts = {GraspContact{{-0.03, 0, z}, {1, 0, 0}}, GraspContact{{0.03, 0.02, z}, {-1, 0, 0}},
                GraspContact{{0.03, -0.02, z}, {-1, 0, 0}}};
  g.approach = {0, 0, -1};
  g.aperture = 0.06 + SynthesisParams{}.hand.finger_width;
  return g;
}

std::vector<SurfaceSample> standing_box(const Eigen::Vector3d& size, double h) {
  auto samples = box(size, h);
  for (auto& s : samples) s.position.z() += size.z() / 2;
  return samples;
}

TEST(GraspSynthesis, AHandWithRoomAroundItsContactsIsNotBlocked) {
  const HandGeometry hand;
  const double tolerance = SynthesisParams{}.path_tolerance;
  // A box 6 cm across and 12 cm tall, taken 5 cm up: its top is 7 cm behind the contacts, nearer
  // than the palm's face.
  EXPECT_FALSE(hand_path_blocked(grasp_across_x(0.05), hand, standing_box({0.06, 0.10, 0.12}, 0.004), tolerance));
}

TEST(GraspSynthesis, AnObjectReachingBehindThePalmBlocksTheHand) {
  const HandGeometry hand;
  const double tolerance = SynthesisParams{}.path_tolerance;
  // 30 cm tall, taken 5 cm up from above: the palm would have to go through its upper part.
  const auto samples = standing_box({0.06, 0.10, 0.30}, 0.004);
  const auto blocking = hand_path_blocked(grasp_across_x(0.05), hand, samples, tolerance);
  ASSERT_TRUE(blocking);
  EXPECT_GT(samples[*blocking].position.z(), 0.05 + hand.palm_distance);
}

TEST(GraspSynthesis, ALedgeBetweenTheOpenThumbAndItsContactBlocksTheHand) {
  const HandGeometry hand;
  const double tolerance = SynthesisParams{}.path_tolerance;
  // The box 6 cm across up to 8 cm, then a cap 12 cm across (x) and 2 cm high on top: closing
  // on the narrow part 5 cm up, the thumb (and the fingers) would meet the cap's rim 3 cm out.
  auto samples = standing_box({0.06, 0.10, 0.08}, 0.004);
  for (auto s : box({0.12, 0.10, 0.02}, 0.004)) {
    s.position.z() += 0.09;
    samples.push_back(s);
  }
  const auto blocking = hand_path_blocked(grasp_across_x(0.05), hand, samples, tolerance);
  ASSERT_TRUE(blocking);
  EXPECT_GT(samples[*blocking].position.z(), 0.079);
  EXPECT_GT(std::abs(samples[*blocking].position.x()), 0.03 + tolerance);
  // Taken on the cap itself, nothing stands in the way.
  Grasp on_cap = grasp_across_x(0.09);
  for (int k = 0; k < 3; ++k) on_cap.contacts[k].position.x() *= 2;
  on_cap.aperture = 0.12 + hand.finger_width;
  EXPECT_FALSE(hand_path_blocked(on_cap, hand, samples, tolerance));
}

// The check passes over whole cells of samples whose ball cannot reach the hand; a sample checked
// alone is the rule itself. Small clouds of samples around the hand's way (beside a box's sides,
// x beyond +-0.03, and about the palm's face, z 0.205), several to a cell: blocked exactly when
// one of their samples alone blocks.
TEST(GraspSynthesis, TheHandsWayCheckFindsWhatEverySampleCheckedAloneFinds) {
  const HandGeometry hand;
  const double tolerance = SynthesisParams{}.path_tolerance;
  const Grasp g = grasp_across_x(0.05);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(0.03, 0.09), y(-0.05, 0.05), z(0.0, 0.26), near(-0.015, 0.015);
  std::bernoulli_distribution thumb_side(0.5);
  int blocked = 0, free = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Eigen::Vector3d at(thumb_side(rng) ? -x(rng) : x(rng), y(rng), z(rng));
    std::vector<SurfaceSample> cloud(8, SurfaceSample{});
    for (auto& s : cloud) {
      s.position = at + Eigen::Vector3d(near(rng), near(rng), near(rng));
      s.normal = {0, 0, 1};
    }
    const bool alone = std::any_of(cloud.begin(), cloud.end(), [&](const SurfaceSample& s) {
      return hand_path_blocked(g, hand, std::span(&s, 1), tolerance).has_value();
    });
    ASSERT_EQ(hand_path_blocked(g, hand, cloud, tolerance).has_value(), alone) << "cloud about " << at.transpose();
    (alone ? blocked : free) += 1;
  }
  EXPECT_GT(blocked, 100);
  EXPECT_GT(free, 100);

  std::vector<SurfaceSample> bad(2, SurfaceSample{});
  bad[1].position.y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(hand_path_blocked(g, hand, bad, tolerance), std::invalid_argument);
  HandGeometry no_width = hand;
  no_width.finger_width = 0;
  EXPECT_THROW(hand_path_blocked(g, no_width, std::span(bad.data(), 1), tolerance), std::invalid_argument);
}

// An approach tilted towards the thumb: the open thumb stands beyond its contact, lower than it.
TEST(GraspSynthesis, TheOpenThumbIsLowerThanItsContactWhenTheHandTilts) {
  Grasp g = grasp_across_x(0.05);
  const HandGeometry hand;
  const double tilt = 30 * kPi / 180;
  g.approach = {std::sin(tilt), 0, -std::cos(tilt)};  // leaning down towards +x: the thumb's side (-x) is lower
  // The thumb's axis sits open + radius out along -u, u = (cos, 0, sin) across the approach.
  const Eigen::Vector3d u(std::cos(tilt), 0, std::sin(tilt));
  const double width = 0.06 * std::cos(tilt);
  const double out = (g.aperture - width) / 2 + hand.finger_width / 2;
  const double thumb_axis_z = 0.05 - out * u.z();
  const double radius_below = hand.finger_width / 2 * std::sin(tilt);  // a capsule tilted by 30 degrees
  EXPECT_NEAR(hand_lowest_z(g, hand), thumb_axis_z - hand.tip_length * std::cos(tilt) - radius_below, 1e-12);
}

TEST(GraspSynthesis, BadInputIsAClearError) {
  EXPECT_THROW(synthesise({}), std::invalid_argument);
  std::vector<SurfaceSample> s = {{{0, 0, 0}, {0, 0, 1}}, {{0.01, 0, 0}, {0, 0, 0}}};
  try {
    synthesise(s);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sample 1 has a zero normal"), std::string::npos) << e.what();
  }
  s[1].normal = {0, 0, 1};
  SynthesisParams p;
  p.hand.aperture_max = 0.01;
  try {
    synthesise(s, p);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("aperture range"), std::string::npos) << e.what();
  }
  SynthesisParams wide;
  wide.normal_error_deg = 25;  // wider than the pyramid's inscribed cone for friction 0.5 (24.8 degrees)
  try {
    synthesise(s, wide);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("normal_error_deg must be >= 0 and below the friction cone's half-angle (24.79"),
              std::string::npos)
        << e.what();
  }
  SynthesisParams tiny;
  tiny.neighbour_radius = 1e-12;
  s[1].position = {1.0, 0, 0};
  EXPECT_THROW(synthesise(s, tiny), std::invalid_argument);
}

// The best synthesised grasp on samples of each YCB mesh, put on the true surface, measured by
// the independent quality measure.
struct YcbCase {
  const char* mesh;
  double random_p99;  // independent figure from data/README.md; 0: none published
};

class SynthesisOnYcb : public testing::TestWithParam<YcbCase> {};

TEST_P(SynthesisOnYcb, BestGraspIsForceClosureOnTheTrueSurface) {
  const auto mesh = geometry::load_mesh(fba::test::ycb_mesh(GetParam().mesh));
  const ObjectSurface surface(mesh);
  const SurfaceSampling sampling = sample_for_synthesis(surface, 3000, 11);
  SynthesisParams p;
  p.neighbour_radius = sampling.neighbour_radius;
  const auto& samples = sampling.samples;
  const SynthesisResult r = synthesise(samples, p);
  ASSERT_FALSE(r.candidates.empty()) << GetParam().mesh;
  std::vector<double> eps;
  int fc = 0;
  for (const auto& c : r.candidates) {
    std::array<GraspContact, 3> placed;
    for (int k = 0; k < 3; ++k) placed[k] = surface.place(c.grasp.contacts[k]).contact;
    const GraspQuality q = surface.evaluate(placed);
    fc += q.force_closure;
    eps.push_back(q.epsilon);
  }
  std::printf("%s: best FC %d eps %.4f (S1 %.2f S3 %.2f S4 %.2f); top %zu: FC share %.2f, median eps %.4f\n",
              GetParam().mesh, eps[0] > 0, eps[0], r.candidates[0].grasp.scores.symmetry,
              r.candidates[0].grasp.scores.safety_margin, r.candidates[0].grasp.scores.curvature, eps.size(),
              static_cast<double>(fc) / eps.size(), quantile(eps, 0.5));
  EXPECT_GT(eps[0], 0.0) << GetParam().mesh << ": the best grasp is not force closure";
  // The target for selected grasps: at least 90% force closure on the true mesh.
  EXPECT_GE(static_cast<double>(fc) / eps.size(), 0.9) << GetParam().mesh;
  // ... and their median epsilon above the 99th percentile of random contact sets.
  if (GetParam().random_p99 > 0) EXPECT_GT(quantile(eps, 0.5), GetParam().random_p99) << GetParam().mesh;
}

INSTANTIATE_TEST_SUITE_P(Ycb, SynthesisOnYcb,
                         testing::Values(YcbCase{"YcbMustardBottle", 0.036}, YcbCase{"YcbMasterChefCan", 0.071},
                                         YcbCase{"YcbBanana", 0.020}, YcbCase{"YcbCrackerBox", 0.0}),
                         [](const auto& info) { return std::string(info.param.mesh); });

}  // namespace
}  // namespace fba::grasp
