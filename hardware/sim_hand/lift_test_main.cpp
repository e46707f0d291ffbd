// fba-lift-test: lift tests from the shell, timed. Without --grasp it executes the ring grasp
// (three contacts 120 degrees apart at mid height, approached from above), so that it doubles as
// the benchmark of one lift test's wall time; with --synthesise N it runs grasp synthesis
// (plugins/grasp) on N samples of the true surface and lift-tests its best candidates.
//
//   fba-lift-test MESH [--grasp summary.json | --synthesise N [--candidates K]] [--x M] [--y M]
//                      [--yaw DEG] [--rest upright|side] [--mass KG] [--force N] [--height F] [--thumb-angle DEG] [--repeat N]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/grasp/grasp_json.hpp"
#include "fba/grasp/object_surface.hpp"
#include "fba/grasp/synthesis.hpp"
#include "lift_test.hpp"
#include "ring_grasp.hpp"

namespace {

constexpr const char* kUsage =
    "usage: fba-lift-test MESH [--grasp FILE.json] [--x M] [--y M] [--yaw DEG] [--rest upright|side] [--mass KG] [--force N]\n"
    "                     [--height F] [--thumb-angle DEG] [--repeat N]\n"
    "  --grasp        a grasp as JSON (a run's summary.json with a \"grasp\" member, or the grasp itself);\n"
    "                 default: the ring grasp at height F of the object (default 0.5) from above\n"
    "  --synthesise   synthesise grasps from N samples of the true surface (seeded) and lift-test the best K\n"
    "                 candidates (--candidates, default 1: the grasp synthesis would select)\n"
    "  --repeat       run the same lift test N times and report the mean wall time\n";

void print(const fba::GraspExecution& r) {
  std::printf("held %s, slip %.4f m, lifted %.3f m, held for %.2f s, %zu contacts%s%s\n", r.held ? "yes" : "no", r.slip_m,
              r.lift_height_m, r.hold_s, r.contacts.size(), r.reason.empty() ? "" : ": ", r.reason.c_str());
}

// Synthesis on the true surface, then the lift test of its best candidates: how often what
// synthesis selects holds in physics.
int synthesised(fba::sim_hand::LiftTest& test, int samples, int candidates) {
  const fba::grasp::ObjectSurface surface(test.object());
  const auto sampling = fba::grasp::sample_for_synthesis(surface, static_cast<std::size_t>(samples), 1);
  fba::grasp::SynthesisParams params;
  params.neighbour_radius = sampling.neighbour_radius;
  params.object_centre = surface.centre_of_mass();
  const auto result = fba::grasp::synthesise(sampling.samples, params);
  if (result.candidates.empty()) {
    std::printf("synthesis found no candidate\n");
    return 1;
  }
  int held = 0, tried = 0;
  for (const auto& c : result.candidates) {
    if (tried == candidates) break;
    ++tried;
    const auto r = test.run(c.grasp);
    held += r.held;
    std::printf("candidate %d (score %.2f, epsilon %.3f): ", tried, c.grasp.scores.total, surface.evaluate(c.grasp.contacts).epsilon);
    print(r);
  }
  std::printf("held %d of %d synthesised grasps\n", held, tried);
  return held == tried ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::cerr << kUsage;
    return argc < 2 ? 2 : 0;
  }
  std::map<std::string, std::string> opt{{"--x", "0"},    {"--y", "0"},      {"--yaw", "0"},         {"--mass", "0.3"},
                                         {"--force", "10"}, {"--height", "0.5"}, {"--thumb-angle", "180"}, {"--repeat", "1"},
                                         {"--grasp", ""}, {"--synthesise", "0"}, {"--candidates", "1"}, {"--rest", "upright"}};
  for (int i = 2; i < argc; i += 2) {
    if (!opt.count(argv[i]) || i + 1 >= argc) {
      std::cerr << "fba-lift-test: unknown option or missing value: " << argv[i] << "\n" << kUsage;
      return 2;
    }
    opt[argv[i]] = argv[i + 1];
  }
  try {
    const auto build_start = std::chrono::steady_clock::now();
    const auto mesh = fba::geometry::load_mesh(argv[1]);
    fba::sim_hand::LiftTestParams params;
    params.mass = std::stod(opt["--mass"]);
    params.finger_force = std::stod(opt["--force"]);
    fba::sim_hand::LiftTest test(
        mesh, {std::stod(opt["--x"]), std::stod(opt["--y"]), std::stod(opt["--yaw"]) * M_PI / 180, opt["--rest"]}, params);
    std::printf("scene built (mesh loaded, MuJoCo model compiled) in %.3f s wall time\n",
                std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count());
    if (const int samples = std::stoi(opt["--synthesise"]); samples > 0) return synthesised(test, samples, std::stoi(opt["--candidates"]));
    fba::Grasp grasp;
    if (!opt["--grasp"].empty()) {
      std::ifstream in(opt["--grasp"]);
      if (!in) throw std::runtime_error("cannot read " + opt["--grasp"]);
      const auto j = nlohmann::json::parse(in);
      grasp = fba::grasp::grasp_from_json(j.contains("grasp") ? j["grasp"] : j, opt["--grasp"]);
    } else {
      double low = INFINITY, high = -INFINITY;
      for (const auto& v : test.object().vertices) low = std::min(low, double(v.z())), high = std::max(high, double(v.z()));
      grasp = fba::sim_hand::ring_grasp(test.object(), low + std::stod(opt["--height"]) * (high - low),
                                        std::stod(opt["--thumb-angle"]) * M_PI / 180);
    }
    const int repeat = std::max(1, std::stoi(opt["--repeat"]));
    fba::GraspExecution r;
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < repeat; ++i) r = test.run(grasp);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / repeat;
    print(r);
    for (const auto& c : r.contacts)
      std::printf("  %-11s at (%.4f, %.4f, %.4f) normal (%.2f, %.2f, %.2f) force %.2f N\n", c.link.c_str(), c.position.x(),
                  c.position.y(), c.position.z(), c.normal.x(), c.normal.y(), c.normal.z(), c.force);
    std::printf("one lift test: %.3f s wall time for %.2f s simulated (%ld steps), mean of %d\n", wall, test.simulated_s(),
                test.steps(), repeat);
    return r.held ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "fba-lift-test: " << e.what() << "\n";
    return 2;
  }
}
