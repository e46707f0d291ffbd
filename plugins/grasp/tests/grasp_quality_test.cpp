// The grasp-quality measure against cases whose answer is known by hand.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

#include "fba/geometry/qhull.hpp"
#include "fba/grasp/grasp_quality.hpp"

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace fba::grasp {
namespace {

// Contacts around a cylinder of radius r about z at height 0, with inward (radial) normals.
std::vector<GraspContact> around_cylinder(double r, std::initializer_list<double> degrees) {
  std::vector<GraspContact> c;
  for (double d : degrees) {
    const double a = d * std::numbers::pi / 180.0;
    const Eigen::Vector3d radial(std::cos(a), std::sin(a), 0.0);
    c.push_back({r * radial, -radial});
  }
  return c;
}

// Support of the wrench set in direction u: the hull reaches max_i u.w_i there, and the inscribed
// ball cannot reach further, so epsilon <= support(u) for every unit u.
double support(const Eigen::Matrix<double, 6, Eigen::Dynamic>& w, const Eigen::Matrix<double, 6, 1>& u) {
  return (u.transpose() * w).maxCoeff();
}

TEST(GraspQuality, ThreeContactsAt120DegreesAroundACylinderAreForceClosure) {
  const double r = 0.04;
  const auto contacts = around_cylinder(r, {0, 120, 240});
  const GraspQuality q = evaluate_grasp(contacts, Eigen::Vector3d::Zero(), r);
  ASSERT_TRUE(q.force_closure);
  // Upper bound by hand: a pure force along the axis is resisted only by friction, whose largest
  // axial component on a cone edge is mu (unit normal component), so epsilon <= mu = 0.5. So is a
  // pure torque about the axis: r * mu / r_max = mu with r_max = r.
  EXPECT_GT(q.epsilon, 0.0);
  EXPECT_LE(q.epsilon, 0.5 + 1e-12);
  // The same bound in every sampled direction (the hull's support), tight within the sampling.
  const auto w = contact_wrenches(contacts, Eigen::Vector3d::Zero(), r);
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  double tightest = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 20000; ++i) {
    Eigen::Matrix<double, 6, 1> u;
    for (int k = 0; k < 6; ++k) u(k) = g(rng);
    tightest = std::min(tightest, support(w, u.normalized()));
  }
  EXPECT_LE(q.epsilon, tightest + 1e-12);
}

// A case computed by hand: a contact at the centre of each face of a cube of half-side s, normals
// inward, centre of mass at the centre, torque scale r_max = s. Contact e (a signed axis) sits at
// s e with normal -e; its pyramid's first tangent is axis-aligned (the contacts' centroid is the
// centre, so the measure takes n.unitOrthogonal()), so each cone edge is f = -e + mu t with
// torque (s e / s) x f = mu (e x t).
//  - 4 edges: t runs over the 4 axes orthogonal to e; the 24 wrenches are (-e + mu t, mu e x t).
//    The weakest direction is a pure torque about the diagonal, u = (0, (1, 1, 1) / sqrt 3): every
//    e x t is a signed axis, so the wrenches reach at most mu / sqrt 3 along u, and twelve of them
//    reach it (those with e x t = +x, +y or +z), spanning the facet there. Along any pure torque b
//    the hull reaches at least mu |b|_inf >= mu / sqrt 3: the 4 edges with e x t = c average to the
//    pure torque (0, mu c), so the diagonal is the weakest torque. Force directions are
//    stronger: the 4 edges of contact -e average to the unit force (e, 0), so the hull reaches at
//    least |a|_inf >= 1/sqrt 3 > mu/sqrt 3 along any pure force a. Epsilon = mu / sqrt 3 (by hand:
//    the bound along u and along the pure forces and torques; that no mixed direction is weaker is
//    what this test checks of the hull).
//  - 8 edges: the diagonal tangents t = (p - q) / sqrt 2 (p, q the other two axes) add
//    e x t = (e x p - e x q) / sqrt 2, whose component along the diagonal reaches 2 / sqrt 6:
//    epsilon = mu sqrt(2/3) about the same diagonal.
TEST(GraspQuality, ContactsAtTheFaceCentresOfACubeHaveTheHandComputedEpsilon) {
  const double s = 0.05;
  std::vector<GraspContact> contacts;
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {-1.0, 1.0}) {
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[axis] = sign;
      contacts.push_back({s * e, -e});
    }
  for (double mu : {0.3, 0.5, 1.0}) {
    const GraspQuality four = evaluate_grasp(contacts, Eigen::Vector3d::Zero(), s, {mu, 4});
    ASSERT_TRUE(four.force_closure);
    EXPECT_NEAR(four.epsilon, mu / std::sqrt(3.0), 1e-9) << "mu " << mu;
    const GraspQuality eight = evaluate_grasp(contacts, Eigen::Vector3d::Zero(), s, {mu, 8});
    ASSERT_TRUE(eight.force_closure);
    EXPECT_NEAR(eight.epsilon, mu * std::sqrt(2.0 / 3.0), 1e-9) << "mu " << mu;
  }
}

// The smallest distance from the origin to a facet of the merged, triangulated hull of `w` ("qhull
// Qt", qhull's robust default in 6-D), and whether qhull builds `w`'s hull without merging.
struct Hulls {
  double merged = 0;
  bool unmerged_built = false;
};
Hulls hulls(const Eigen::Matrix<double, 6, Eigen::Dynamic>& w) {
  Hulls h;
  auto run = [&](const char* options, double* distance) {
    std::vector<double> coords(w.data(), w.data() + w.size());
    return geometry::run_qhull(6, coords, options, [&](qhT* qh) {
      facetT* facet;
      double d = std::numeric_limits<double>::infinity();
      FORALLfacets { d = std::min(d, -facet->offset); }
      if (distance) *distance = d;
    });
  };
  EXPECT_EQ(run("qhull Qt", &h.merged).code, 0);
  h.unmerged_built = run("qhull Q0", nullptr).code == 0;
  return h;
}

// Quality hulls the wrenches without merging first and falls back to the merged hull where qhull
// reports round-off. Contacts on a box's faces at grid points, normals exactly along the axes, are
// the degenerate input where that happens: every decision and epsilon must be the merged hull's.
TEST(GraspQuality, TheUnmergedHullGivesTheMergedHullsEpsilon) {
  std::vector<GraspContact> points;  // on each face of a 8 cm cube, at 3 x 3 grid points
  for (int axis = 0; axis < 3; ++axis)
    for (double side : {-1.0, 1.0})
      for (double u : {-0.02, 0.0, 0.02})
        for (double v : {-0.02, 0.0, 0.02}) {
          Eigen::Vector3d p;
          p[axis] = side * 0.04, p[(axis + 1) % 3] = u, p[(axis + 2) % 3] = v;
          points.push_back({p, -side * Eigen::Vector3d::Unit(axis)});
        }
  int grasps = 0, force_closure = 0, fell_back = 0;
  for (std::size_t i = 0; i < points.size(); i += 5)
    for (std::size_t j = i + 1; j < points.size(); j += 3)
      for (std::size_t k = j + 1; k < points.size(); k += 7) {
        const std::vector<GraspContact> c{points[i], points[j], points[k]};
        const auto w = contact_wrenches(c, Eigen::Vector3d::Zero(), 0.07);
        const Eigen::MatrixXd centred = w.colwise() - w.rowwise().mean();
        if (Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues()(5) <= 1e-9) continue;  // flat: no hull
        const Hulls h = hulls(w);
        const GraspQuality q = evaluate_grasp(c, Eigen::Vector3d::Zero(), 0.07);
        const std::string which = "contacts " + std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k);
        ++grasps;
        fell_back += !h.unmerged_built;
        ASSERT_EQ(q.force_closure, h.merged > 1e-12) << which << ": merged hull's distance " << h.merged;
        if (!q.force_closure) continue;
        ++force_closure;
        EXPECT_NEAR(q.epsilon, h.merged, 1e-9 * h.merged) << which;
      }
  EXPECT_GT(force_closure, 10) << "of " << grasps;
  EXPECT_GT(fell_back, 0) << "of " << grasps << ": no grasp here takes the merged hull's path";
}

TEST(GraspQuality, EpsilonGrowsWithFriction) {
  const auto contacts = around_cylinder(0.04, {0, 120, 240});
  const double low = evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.04, {0.3, 8}).epsilon;
  const double high = evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.04, {0.8, 8}).epsilon;
  EXPECT_GT(low, 0.0);
  EXPECT_GT(high, low);
}

TEST(GraspQuality, WithoutFrictionThreePointContactsAreNotForceClosure) {
  // Frictionless point contacts need at least 7 in 3-D; three cannot resist an axial force.
  const auto contacts = around_cylinder(0.04, {0, 120, 240});
  EXPECT_FALSE(evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.04, {0.0, 8}).force_closure);
}

TEST(GraspQuality, TwoCoplanarParallelContactsAreNotForceClosure) {
  // Two contacts on one face of a box, pushing the same way: nothing opposes them.
  const std::vector<GraspContact> contacts = {{{0.05, 0.0, 0.0}, {-1, 0, 0}}, {{0.05, 0.02, 0.01}, {-1, 0, 0}}};
  const GraspQuality q = evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.1);
  EXPECT_FALSE(q.force_closure);
  EXPECT_EQ(q.epsilon, 0.0);
}

TEST(GraspQuality, ThreeContactsOnOneSideAreNotForceClosure) {
  const std::vector<GraspContact> contacts = {
      {{0.05, 0.0, 0.0}, {-1, 0, 0}}, {{0.05, 0.02, 0.01}, {-1, 0, 0}}, {{0.05, -0.02, 0.01}, {-1, 0, 0}}};
  EXPECT_FALSE(evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.1).force_closure);
}

TEST(GraspQuality, TwoOpposedPointContactsCannotResistTorqueAboutTheirAxis) {
  // Point contacts with friction exert no torque about the line through both.
  const auto contacts = around_cylinder(0.04, {0, 180});
  EXPECT_FALSE(evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.04).force_closure);
}

TEST(GraspQuality, ThreeContactsWithinHalfACircleAreNotForceClosure) {
  // All inward normals in one open half-plane: their positive combinations cannot sum to zero
  // once friction is too small to turn them (mu = 0.1 at 0, 60, 120 degrees).
  const auto contacts = around_cylinder(0.04, {0, 60, 120});
  EXPECT_FALSE(evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.04, {0.1, 8}).force_closure);
}

TEST(GraspQuality, EpsilonIsInvariantToARigidMotionOfTheWholeGrasp) {
  auto contacts = around_cylinder(0.04, {0, 110, 250});
  contacts[1].position.z() = 0.01;
  const Eigen::Vector3d com(0.001, -0.002, 0.003);
  const double before = evaluate_grasp(contacts, com, 0.05).epsilon;
  ASSERT_GT(before, 0.0);
  const Eigen::Isometry3d t = Eigen::Translation3d(0.3, -1.2, 0.7) *
                              Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.2, -0.5, 0.8).normalized());
  for (auto& c : contacts) {
    c.position = t * c.position;
    c.normal = t.linear() * c.normal;
  }
  EXPECT_NEAR(evaluate_grasp(contacts, t * com, 0.05).epsilon, before, 1e-9);
}

TEST(GraspQuality, NormalLengthDoesNotMatter) {
  auto contacts = around_cylinder(0.04, {0, 120, 240});
  const double unit = evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.04).epsilon;
  for (auto& c : contacts) c.normal *= 3.0;
  EXPECT_NEAR(evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.04).epsilon, unit, 1e-12);
}

// The GraspQualityError's message for these contacts (centre of mass at the origin, r_max 4 cm);
// contacts it accepts are a test failure.
std::string quality_error(const std::vector<GraspContact>& contacts) {
  try {
    evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.04);
  } catch (const GraspQualityError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected GraspQualityError";
  return {};
}

TEST(GraspQuality, CoincidentContactsAreAClearError) {
  auto contacts = around_cylinder(0.04, {0, 120, 240});
  contacts[2].position = contacts[0].position;
  const std::string what = quality_error(contacts);
  EXPECT_NE(what.find("contacts 0 and 2 coincide"), std::string::npos) << what;
}

TEST(GraspQuality, ZeroNormalIsAClearError) {
  auto contacts = around_cylinder(0.04, {0, 120, 240});
  contacts[1].normal.setZero();
  const std::string what = quality_error(contacts);
  EXPECT_NE(what.find("contact 1 needs a non-zero inward normal"), std::string::npos) << what;
}

TEST(GraspQuality, BadParametersAreClearErrors) {
  const auto contacts = around_cylinder(0.04, {0, 120, 240});
  EXPECT_THROW(evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.0), GraspQualityError);
  EXPECT_THROW(evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.04, {-0.5, 8}), GraspQualityError);
  EXPECT_THROW(evaluate_grasp(contacts, Eigen::Vector3d::Zero(), 0.04, {0.5, 2}), GraspQualityError);
  EXPECT_THROW(evaluate_grasp(std::span(contacts).first(1), Eigen::Vector3d::Zero(), 0.04), GraspQualityError);
  EXPECT_THROW(evaluate_grasp(contacts, Eigen::Vector3d(NAN, 0, 0), 0.04), GraspQualityError);
}

}  // namespace
}  // namespace fba::grasp
