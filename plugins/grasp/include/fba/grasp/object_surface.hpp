// A closed object mesh as the grasp measure needs it: its centre of mass, r_max, contacts placed
// on the true surface with inward normals, and uniform random contacts for the random baseline.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fba/grasp/grasp_quality.hpp"
#include "fba/grasp/synthesis.hpp"
#include "fba/types/grasp.hpp"
#include "fba/types/mesh.hpp"

namespace fba::grasp {

class ObjectSurface {
 public:
  // Throws std::invalid_argument for a mesh without triangles, with an index out of range, or
  // enclosing no volume (an open or flat mesh has no centre of mass).
  explicit ObjectSurface(const TriangleMesh& mesh);

  // Centre of mass of the solid, uniform density (volume integral over signed tetrahedra).
  const Eigen::Vector3d& centre_of_mass() const { return com_; }
  // Largest distance from the centre of mass to the surface (reached at a vertex): the torque scale.
  double r_max() const { return r_max_; }
  double volume() const { return volume_; }
  double area() const { return area_total_; }

  struct Placement {
    GraspContact contact;      // on the surface, with the triangle's inward normal
    double displacement = 0;   // distance from the given position to the placed one, metres
    bool along_normal = true;  // false when the line along the normal missed and the closest point was used
    // Degrees between the given normal and the surface's there: the model's error a grasp on it
    // must absorb. None when the given normal is zero or not finite.
    std::optional<double> normal_error_deg;
  };
  // Puts an approximate contact on the surface: the hit of the line through its position along its
  // normal that is nearest to the position; if that line misses the mesh, the closest surface point.
  Placement place(const GraspContact& approximate) const;
  // Puts an approximate contact on the surface point closest to its position (along_normal false).
  Placement place_closest(const GraspContact& approximate) const;
  // The surface point closest to p, with the inward normal of its triangle.
  GraspContact closest_point(const Eigen::Vector3d& p) const;

  // A point drawn uniformly by area over the surface, with its triangle's inward normal.
  template <class Rng>
  GraspContact sample(Rng& rng) const;

  GraspQuality evaluate(std::span<const GraspContact> contacts, const QualityParams& params = {}) const {
    return evaluate_grasp(contacts, com_, r_max_, params);
  }

 private:
  GraspContact on_triangle(std::size_t t, double u, double v) const;

  std::vector<std::array<Eigen::Vector3d, 3>> triangles_;
  std::vector<Eigen::Vector3d> inward_;  // unit inward normal per triangle
  std::vector<double> cumulative_area_;
  double area_total_ = 0;
  double volume_ = 0;
  double r_max_ = 0;
  Eigen::Vector3d com_ = Eigen::Vector3d::Zero();
};

// A grasp's three contacts put on the true surface one way, and the grasp's quality there.
struct PlacedGrasp {
  std::array<ObjectSurface::Placement, 3> contacts;
  GraspQuality quality;
  std::string degenerate;  // why the measure is undefined here (two contacts landed on one point), else ""
};

// A grasp placed on the true surface both ways: each contact along its normal line (place) and
// each at its closest surface point (place_closest). Near an edge the two land on different faces
// with different normals; the grasp counts as the worse, so that it is not judged by its kinder
// placement.
struct GraspOnSurface {
  PlacedGrasp along_normal, closest;
  // Not force closure before force closure, then the lower epsilon (along_normal on a tie).
  const PlacedGrasp& worse() const;
};
GraspOnSurface place_grasp(const ObjectSurface& surface, const std::array<GraspContact, 3>& contacts,
                           const QualityParams& params = {});

struct RandomBaseline {
  std::size_t sets = 0;
  double force_closure_share = 0;  // share of the random sets that are force closure
  double epsilon_p99 = 0;          // 99th percentile of epsilon over all sets (0 when not force closure)
  double epsilon_median_fc = 0;    // median epsilon of the force-closure sets (0 if none)
};

// `sets` random three-contact sets drawn uniformly by area, seeded: the baseline a synthesised
// grasp should beat (the grasp issue's "random contact sets").
RandomBaseline random_baseline(const ObjectSurface& surface, std::size_t sets, std::uint64_t seed,
                               const QualityParams& params = {});

// What synthesis would see of this object if its model were perfect: `count` samples drawn
// uniformly by area (seeded) with outward normals and curvature estimated over neighbour_radius,
// which is 2.5 times the mean sample spacing: pass it on as SynthesisParams::neighbour_radius.
struct SurfaceSampling {
  std::vector<SurfaceSample> samples;
  double neighbour_radius = 0;
};
SurfaceSampling sample_for_synthesis(const ObjectSurface& surface, std::size_t count, std::uint64_t seed);

// The q-quantile (0..1) of values by linear interpolation between order statistics; 0 when empty.
double quantile(std::vector<double> values, double q);

template <class Rng>
GraspContact ObjectSurface::sample(Rng& rng) const {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double a = uniform(rng) * area_total_;
  auto it = std::upper_bound(cumulative_area_.begin(), cumulative_area_.end(), a);
  const std::size_t t = std::min<std::size_t>(it - cumulative_area_.begin(), triangles_.size() - 1);
  double u = uniform(rng), v = uniform(rng);
  if (u + v > 1) {  // fold the parallelogram onto the triangle: uniform over it
    u = 1 - u;
    v = 1 - v;
  }
  return on_triangle(t, u, v);
}

}  // namespace fba::grasp
