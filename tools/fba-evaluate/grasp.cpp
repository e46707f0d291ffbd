// fba-evaluate grasp: the quality of a grasp on the true object surface (force closure and the
// Ferrari-Canny epsilon), compared with random contact sets and with synthesis on perfect samples.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "grasp_evaluation.hpp"
#include "options.hpp"
#include "fba/grasp/grasp_json.hpp"
#include "fba/grasp/object_surface.hpp"
#include "fba/grasp/synthesis.hpp"

namespace fba::evaluate {
namespace {

const char* kGraspHelp = R"(fba-evaluate grasp: grasp quality on the true object surface.

  fba-evaluate grasp --mesh M.obj --summary run/summary.json [--random 1000]
      Places the three contacts of summary.json's "grasp" on the mesh two ways, with the mesh's
      inward normals: along each contact's normal line (else the closest point), and at each
      contact's closest point. Prints for each how far each contact moved and how far its normal
      is off the mesh's, force closure and the Ferrari-Canny epsilon, and the grasp's as the worse
      of the two (a contact on an edge lands on different faces); then the same figures for random
      contact sets.
  fba-evaluate grasp --mesh M.obj [M2.obj ...] --random 1000
      Random three-contact sets drawn uniformly by area: share force closure, 99th percentile
      of epsilon (all sets, 0 when not force closure), median epsilon of the force-closure ones.
  fba-evaluate grasp --mesh M.obj [M2.obj ...] --synthesise [--samples 3000] [--random 1000]
      Synthesis on samples of the mesh (a perfect model): the best candidate's and the top
      candidates' force closure and epsilon, beside the random figures (one row per mesh).
  fba-evaluate grasp --batch LIST.yaml [--jobs N] [-o DIR]
      Runs a task over a list of objects and poses with fba-run and prints the table of the grasp
      issue's targets (see fba-evaluate grasp --batch LIST --help and docs/evaluating-grasps.md).

The measure: Coulomb friction mu (--friction, 0.5), each cone as --cone-edges (8) edges with a
unit normal component, torques divided by r_max (largest distance from the volume centre of
mass to the surface), the hull of the wrenches by qhull. The mesh must be closed.

summary.json's "grasp" object (world frame, metres; the mesh is in world frame too unless
--mesh-pose says where it stands):
  "grasp": {
    "contacts": [ {"position": [x, y, z], "normal": [x, y, z]},    thumb first, 3 in all,
                  {...}, {...} ],                                  normals pointing inward
    "approach": [x, y, z], "spread": m, "aperture": m,            optional
    "scores": {"symmetry": s1, "safety_margin": s3, "curvature": s4, "total": t},   optional
    "views": [i, ...]                                              optional
  }

A run's summary.json from fba-run is read too: the grasp is then the one a component reported
(grasp.synthesis's results.grasp, this JSON). --summary must be a regular file (a FIFO is refused,
as reading one waits for a writer); a mesh that is not closed is refused with its boundary edges.

Exit status: 0 when evaluated (with --summary: the grasp is force closure by both placements), 1
when it is not, 2 for bad input (a mesh that does not load, a malformed summary).

Options)";

struct Options {
  std::vector<std::string> meshes;
  std::string summary;
  std::size_t random = 1000;
  std::uint64_t seed = 1;
  bool synthesise = false;
  std::size_t samples = 3000;
  std::vector<double> mesh_pose;
  grasp::QualityParams quality;
};

Eigen::Isometry3d parse_pose(const std::vector<double>& v) {
  if (v.empty()) return Eigen::Isometry3d::Identity();
  check_finite_numbers("mesh-pose", v, 6, "x y z roll pitch yaw, metres and radians");
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << v[0], v[1], v[2];
  t.linear() = (Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return t;
}

}  // namespace

TriangleMesh load_posed(const std::string& path, const Eigen::Isometry3d& pose) {
  TriangleMesh m = load_closed_mesh(path);
  for (auto& v : m.vertices) v = (pose * v.cast<double>()).cast<float>();
  return m;
}

Eigen::Isometry3d table_pose(double x, double y, double yaw_deg) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << x, y, 0;
  t.linear() = Eigen::AngleAxisd(yaw_deg * std::numbers::pi / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

std::string object_name(const std::string& mesh) {
  const std::filesystem::path p(mesh);
  return p.stem() == "model" && p.has_parent_path() ? p.parent_path().filename().string() : p.filename().string();
}

namespace {

// One contact's placement on the mesh, as a line.
void print_placement(const char* label, const GraspContact& given, const grasp::ObjectSurface::Placement& p) {
  const Eigen::Vector3d& a = given.position;
  std::printf("  %s: (%.4f, %.4f, %.4f) -> (%.4f, %.4f, %.4f), moved %.2f mm %s", label, a.x(), a.y(), a.z(), p.contact.position.x(),
              p.contact.position.y(), p.contact.position.z(), 1000 * p.displacement,
              p.along_normal ? "along its normal" : "to the closest point");
  if (p.normal_error_deg) std::printf("; normal %.1f deg off the surface's", *p.normal_error_deg);
  std::printf("\n");
}

void print_quality(const char* what, const grasp::PlacedGrasp& g) {
  std::printf("%s: force closure %s, epsilon %.4f%s\n", what, g.quality.force_closure ? "yes" : "no", g.quality.epsilon,
              g.degenerate.empty() ? "" : (" (" + g.degenerate + ")").c_str());
}

int evaluate_summary(const Options& o, const Grasp& g, const grasp::ObjectSurface& surface) {
  const grasp::GraspOnSurface on = grasp::place_grasp(surface, g.contacts, o.quality);
  for (int k = 0; k < 3; ++k) {
    const std::string label = "contact " + std::to_string(k) + (k == 0 ? " (thumb)" : "");
    print_placement(label.c_str(), g.contacts[k], on.along_normal.contacts[k]);
    print_placement((std::string(label.size(), ' ') + " closest point").c_str(), g.contacts[k], on.closest.contacts[k]);
  }
  print_quality("placed along the normals", on.along_normal);
  print_quality("placed at the closest points", on.closest);
  const grasp::GraspQuality& q = on.worse().quality;
  std::printf("grasp: force closure %s, epsilon %.4f (the worse placement: %s)\n", q.force_closure ? "yes" : "no", q.epsilon,
              &on.worse() == &on.closest ? "the closest points" : "along the normals");
  if (o.random > 0) {
    const auto b = grasp::random_baseline(surface, o.random, o.seed, o.quality);
    std::printf("random %zu sets: force closure %.1f%%, epsilon p99 %.4f, median FC epsilon %.4f\n", b.sets,
                100 * b.force_closure_share, b.epsilon_p99, b.epsilon_median_fc);
    if (b.epsilon_p99 > 0) std::printf("grasp epsilon / random p99: %.2f\n", q.epsilon / b.epsilon_p99);
  }
  return q.force_closure ? 0 : 1;
}

void table_row(const Options& o, const std::string& mesh, const grasp::ObjectSurface& surface) {
  std::printf("%-22s", object_name(mesh).c_str());
  if (o.random > 0) {
    const auto b = grasp::random_baseline(surface, o.random, o.seed, o.quality);
    std::printf(" %9.1f%% %9.4f", 100 * b.force_closure_share, b.epsilon_p99);
  }
  if (o.synthesise) {
    const auto sampling = grasp::sample_for_synthesis(surface, o.samples, o.seed);
    grasp::SynthesisParams p;
    p.neighbour_radius = sampling.neighbour_radius;
    const auto r = grasp::synthesise(sampling.samples, p);
    std::vector<double> eps;
    std::size_t fc = 0;
    for (const auto& c : r.candidates) {
      const auto q = grasp::place_grasp(surface, c.grasp.contacts, o.quality).worse().quality;
      eps.push_back(q.epsilon);
      fc += q.force_closure;
    }
    if (eps.empty()) {
      std::printf(" %10s", "no candidate");
    } else {
      std::printf(" %8s %9.4f %6.2f %7zu %9.1f%% %9.4f", eps[0] > 0 ? "yes" : "no", eps[0],
                  r.candidates[0].grasp.scores.total, eps.size(), 100.0 * fc / eps.size(), grasp::quantile(eps, 0.5));
    }
  }
  std::printf("\n");
}

}  // namespace

int run_grasp(const std::vector<std::string>& args) {
  if (std::find(args.begin(), args.end(), "--batch") != args.end()) return run_grasp_batch(args);
  Options o;
  po::options_description opts(kGraspHelp);
  opts.add_options()("help,h", "this help")
      ("mesh", po::value(&o.meshes)->multitoken()->required(), "the true object mesh(es), closed (OBJ, PLY, STL, ...)")
      ("summary", po::value(&o.summary), "a run's summary.json holding a \"grasp\" object (one mesh only)")
      ("random", ranged("random", &o.random, std::size_t{0}, kMaxRandomSets), "random three-contact sets (0: none)")
      ("seed", ranged("seed", &o.seed, std::uint64_t{0}, std::numeric_limits<std::uint64_t>::max()),
       "seed of the random sets and of the surface samples")
      ("synthesise", po::bool_switch(&o.synthesise), "synthesise on samples of each mesh and evaluate the candidates")
      ("samples", ranged("samples", &o.samples, std::size_t{3}, kMaxSamples), "surface samples for --synthesise")
      ("mesh-pose", po::value(&o.mesh_pose)->multitoken(),
       "where the mesh stands in the world: x y z roll pitch yaw (metres, radians); default identity")
      ("friction", ranged("friction", &o.quality.friction, 0.0, kMaxFriction), "Coulomb friction coefficient")
      ("cone-edges", ranged("cone-edges", &o.quality.cone_edges, 3, kMaxConeEdges), "edges per friction cone");
  po::variables_map vm = parse(args, opts);
  if (vm.count("help")) {
    std::cout << opts << "\n";
    return 0;
  }
  po::notify(vm);
  if (vm.count("samples") && !vm["samples"].defaulted() && !o.synthesise)
    throw ArgumentError("--samples applies to --synthesise: give --synthesise as well");
  if (!o.summary.empty() && o.meshes.size() != 1)
    throw std::invalid_argument("--summary evaluates one grasp: expected one --mesh, found " + std::to_string(o.meshes.size()));
  if (o.summary.empty() && !o.synthesise && o.random == 0)
    throw std::invalid_argument("nothing to evaluate: give --summary, --random N or --synthesise");
  const Eigen::Isometry3d pose = parse_pose(o.mesh_pose);

  if (!o.summary.empty()) {
    const Grasp g = read_summary_grasp(o.summary, "--summary");
    const grasp::ObjectSurface surface(load_posed(o.meshes[0], pose));
    std::printf("mesh %s: volume %.3g m^3, r_max %.4f m, friction %.2f, %d cone edges\n", o.meshes[0].c_str(),
                surface.volume(), surface.r_max(), o.quality.friction, o.quality.cone_edges);
    return evaluate_summary(o, g, surface);
  }
  // Every mesh loaded and checked before the first line of the table.
  std::vector<grasp::ObjectSurface> surfaces;
  for (const auto& m : o.meshes) surfaces.emplace_back(load_posed(m, pose));
  std::printf("friction %.2f, %d cone edges, seed %llu", o.quality.friction, o.quality.cone_edges,
              static_cast<unsigned long long>(o.seed));
  if (o.random) std::printf(", %zu random sets", o.random);
  if (o.synthesise) std::printf(", %zu surface samples", o.samples);
  std::printf("\n%-22s", "mesh");
  if (o.random) std::printf(" %10s %9s", "random FC", "rand p99");
  if (o.synthesise) std::printf(" %8s %9s %6s %7s %10s %9s", "best FC", "best eps", "score", "top", "top FC", "top med");
  std::printf("\n");
  for (std::size_t i = 0; i < o.meshes.size(); ++i) table_row(o, o.meshes[i], surfaces[i]);
  return 0;
}

}  // namespace fba::evaluate
