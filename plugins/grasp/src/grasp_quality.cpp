#include "fba/grasp/grasp_quality.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <fba/geometry/qhull.hpp>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace fba::grasp {
namespace {

std::string fmt_vec(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

void check_input(std::span<const GraspContact> contacts, const Eigen::Vector3d& com, double r_max,
                 const QualityParams& params) {
  if (contacts.size() < 2)
    throw GraspQualityError("grasp quality: expected at least 2 contacts, found " +
                            std::to_string(contacts.size()));
  if (!(params.friction >= 0) || !std::isfinite(params.friction))
    throw GraspQualityError("grasp quality: friction must be a finite number >= 0, found " +
                            std::to_string(params.friction));
  if (params.cone_edges < 3)
    throw GraspQualityError("grasp quality: a friction cone needs at least 3 edges, found " +
                            std::to_string(params.cone_edges));
  if (!(r_max > 0) || !std::isfinite(r_max))
    throw GraspQualityError("grasp quality: r_max (largest distance from the centre of mass to the "
                            "surface) must be positive and finite, found " + std::to_string(r_max));
  if (!com.allFinite()) throw GraspQualityError("grasp quality: centre of mass is not finite: " + fmt_vec(com));
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const auto& c = contacts[i];
    if (!c.position.allFinite())
      throw GraspQualityError("grasp quality: contact " + std::to_string(i) + " position is not finite: " +
                              fmt_vec(c.position));
    if (!c.normal.allFinite() || c.normal.norm() < 1e-12)
      throw GraspQualityError("grasp quality: contact " + std::to_string(i) +
                              " needs a non-zero inward normal, found " + fmt_vec(c.normal));
    for (std::size_t j = 0; j < i; ++j) {
      // Two fingers cannot touch the same point; relative to the object's size.
      if ((c.position - contacts[j].position).norm() <= 1e-9 * r_max)
        throw GraspQualityError("grasp quality: contacts " + std::to_string(j) + " and " + std::to_string(i) +
                                " coincide at " + fmt_vec(c.position));
    }
  }
}

// True when a hyperplane through the origin has every wrench strictly on one side: a certificate
// that the origin is outside their hull (not force closure). Gilbert's minimum-norm-point
// iteration, stopped early: most random grasps are separated in a few steps, which spares them the
// 6-D hull (milliseconds each); false means "not shown", and qhull decides.
bool separated_from_origin(const Eigen::Matrix<double, 6, Eigen::Dynamic>& w) {
  Eigen::Matrix<double, 6, 1> x = w.rowwise().mean();
  for (int iteration = 0; iteration < 200; ++iteration) {
    Eigen::Index s = 0;
    const double lowest = (x.transpose() * w).minCoeff(&s);
    if (lowest > 0) return true;
    // Closest point to the origin on the segment from x to w_s.
    const Eigen::Matrix<double, 6, 1> d = w.col(s) - x;
    const double dd = d.squaredNorm();
    if (!(dd > 0)) return false;
    const double t = std::clamp(-x.dot(d) / dd, 0.0, 1.0);
    if (t == 0) return false;
    x += t * d;
  }
  return false;
}

// Runs qhull on the columns of `points` and returns the smallest distance from the origin to a
// facet's hyperplane, negative when the origin lies outside some facet. First without merging
// (Q0): on these few dozen 6-D points several times faster than the merged, triangulated hull
// (fba_grasp_quality_benchmark), and where its round-off shows qhull says so (a precision error,
// with exact box faces or parallel normals) and the merged hull decides; the two agree
// (GraspQuality.TheUnmergedHullGivesTheMergedHullsEpsilon; figures in docs/results.md).
double min_facet_distance(const Eigen::Matrix<double, 6, Eigen::Dynamic>& points) {
  constexpr int dim = 6;
  double min_distance = std::numeric_limits<double>::infinity();
  auto run = [&](const char* options) {
    std::vector<coordT> coords(points.data(), points.data() + points.size());  // column-major = one point per 6
    min_distance = std::numeric_limits<double>::infinity();
    return geometry::run_qhull(dim, coords, options, [&](qhT* qh) {
      facetT* facet;
      FORALLfacets {
        // qhull: a point p is outside a facet when normal . p + offset > 0; the origin gives offset.
        min_distance = std::min(min_distance, -facet->offset);
      }
    });
  };
  if (run("qhull Q0").code == 0) return min_distance;
  // Qt: triangulated facets; every facet then has its own hyperplane.
  const auto status = run("qhull Qt");
  if (status.code != 0)
    throw std::runtime_error("grasp quality: qhull failed (code " + std::to_string(status.code) + "): " + status.message);
  return min_distance;
}

}  // namespace

Eigen::Matrix<double, 6, Eigen::Dynamic> contact_wrenches(std::span<const GraspContact> contacts,
                                                          const Eigen::Vector3d& com, double r_max,
                                                          const QualityParams& params) {
  check_input(contacts, com, r_max, params);
  const int k = params.cone_edges;
  Eigen::Matrix<double, 6, Eigen::Dynamic> w(6, contacts.size() * k);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& c : contacts) centroid += c.position / static_cast<double>(contacts.size());
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const Eigen::Vector3d n = contacts[i].normal.normalized();
    // The pyramid's rotation about n changes epsilon slightly; take it from the grasp's own
    // geometry (towards the contact from the contacts' centroid) so that a rigid motion of the
    // whole grasp does not change the result.
    Eigen::Vector3d t1 = contacts[i].position - centroid;
    t1 -= t1.dot(n) * n;
    t1 = t1.norm() > 1e-9 * r_max ? t1.normalized() : n.unitOrthogonal();
    const Eigen::Vector3d t2 = n.cross(t1);
    const Eigen::Vector3d arm = (contacts[i].position - com) / r_max;
    for (int j = 0; j < k; ++j) {
      const double a = 2.0 * std::numbers::pi * j / k;
      const Eigen::Vector3d f = n + params.friction * (std::cos(a) * t1 + std::sin(a) * t2);
      w.col(i * k + j) << f, arm.cross(f);
    }
  }
  return w;
}

GraspQuality evaluate_grasp(std::span<const GraspContact> contacts, const Eigen::Vector3d& com, double r_max,
                            const QualityParams& params) {
  const auto w = contact_wrenches(contacts, com, r_max, params);
  // Wrenches that span less than 6 dimensions cannot hold the origin in their hull's interior, and
  // qhull cannot build a hull of flat input: not force closure, by definition.
  // Affine span: all points on one hyperplane away from the origin (e.g. every contact pushing
  // along the same normal) is flat too.
  const Eigen::MatrixXd centred = w.colwise() - w.rowwise().mean();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(centred);
  const auto& s = svd.singularValues();
  if (s.size() < 6 || s(5) <= 1e-9 * s(0)) return {};
  if (separated_from_origin(w)) return {};
  const double d = min_facet_distance(w);
  // The origin is strictly inside when it is inside every facet by more than round-off.
  if (!(d > 1e-12)) return {};
  return {true, d};
}

}  // namespace fba::grasp
