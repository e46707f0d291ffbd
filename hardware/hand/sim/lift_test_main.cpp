// fba-lift-test: lift tests from the shell, timed, in sim.hand's world: the whole robot (arm, camera,
// hand on the flange) executing reach planning's plan for the grasp, the object as boxes. Without
// --grasp it executes the ring grasp (three contacts 120 degrees apart at mid height, approached
// from above), so that it doubles as the benchmark of one lift test's wall time; with --grasp it
// lift-tests a run's selected grasp (its summary.json) or a grasp given as JSON; with
// --synthesise N it runs grasp synthesis (plugins/grasp) on N samples of the true surface and
// lift-tests its best candidates.
//
//   fba-lift-test MESH [--grasp summary.json | --synthesise N [--candidates K]] [--x M] [--y M]
//                      [--yaw DEG] [--rest upright|side] [--mass KG] [--force N] [--height F] [--thumb-angle DEG] [--repeat N]
//                      [--voxel MM]
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "../robotiq_3f/grip_force.hpp"
#include "fba/geometry/mesh_io.hpp"
#include "fba/grasp/grasp_json.hpp"
#include "fba/grasp/object_surface.hpp"
#include "fba/grasp/synthesis.hpp"
#include "lift_test.hpp"
#include "ring_grasp.hpp"
// How fba-evaluate reads a run's summary.json (header only): the grasp a component reported.
#include "../../tools/fba-evaluate/run_summary.hpp"

namespace {

constexpr const char* kUsage =
    "usage: fba-lift-test MESH [--grasp FILE.json | --synthesise N [--candidates K]] [--x M] [--y M] [--yaw DEG]\n"
    "                     [--rest upright|side] [--mass KG] [--force N] [--height F] [--thumb-angle DEG] [--repeat N]\n"
    "                     [--voxel MM]\n"
    "  --grasp        a run's summary.json (the grasp a component reported, grasp.synthesis' results.grasp, or its\n"
    "                 \"grasp\" member) or a grasp as JSON (\"contacts\", ...), in the table frame: give the run's\n"
    "                 object pose (--x, --y, --yaw, --rest) so that the object stands where the run stood it;\n"
    "                 default: the ring grasp at height F of the object (--height) from above, the thumb at --thumb-angle\n"
    "  --synthesise   synthesise grasps from N samples of the true surface (seeded; 0: off, else 3 to 1000000) and\n"
    "                 lift-test the best K candidates (--candidates, 1 to 1000, default 1: the grasp synthesis would select)\n"
    "  --x, --y       the object's position on the table, metres in [-1, 1] (default 0)\n"
    "  --yaw          its turn about z, degrees in [-360, 360] (default 0)\n"
    "  --mass         kg in [0.001, 10] (default 0.3); --force: newtons at each finger's pad in [15, 60] (default 15)\n"
    "  --height       the ring grasp's height, a fraction of the object's in [0, 1] (default 0.5);\n"
    "  --thumb-angle  the ring grasp's thumb, degrees in [-360, 360] (default 180)\n"
    "  --repeat       run the same lift test N times, 1 to 10000, and report the mean wall time\n"
    "  --voxel        the edge of the voxels whose boxes the object collides as, mm in [0.5, 20] (default 3)\n"
    "Exit status: 0 held, 1 not held, 2 a bad command line, mesh or grasp.\n";

// A command line that asks for nothing sensible: refused with what was expected and what was found.
struct UsageError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

std::string shortest(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// The option's whole text as a finite number in [lo, hi] (std::stod took "1x", passed "nan" on to
// MuJoCo and said only "stod" for "1e999").
double number(const std::string& name, const std::string& text, double lo, double hi) {
  const std::string range = "[" + shortest(lo) + ", " + shortest(hi) + "]";
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0])) || end != text.c_str() + text.size())
    throw UsageError(name + " must be a number in " + range + "; found '" + text + "'");
  if (!std::isfinite(v)) throw UsageError(name + " must be a finite number in " + range + "; found '" + text + "'");
  if (v < lo || v > hi) throw UsageError(name + " must be in " + range + "; found " + text);
  return v;
}

// The option's whole text as an integer in [lo, hi] (std::stoi took "2.5" as 2 and "-1" for
// --repeat, and said only "stoi" for 99999999999).
long long whole(const std::string& name, const std::string& text, long long lo, long long hi, const std::string& note = "") {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]" + note;
  long long v = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (r.ec != std::errc() || r.ptr != text.data() + text.size())
    throw UsageError(name + " must be an integer in " + range + "; found '" + text + "'");
  if (v < lo || v > hi) throw UsageError(name + " must be in " + range + "; found " + text);
  return v;
}

// The grasp in --grasp's file: a run's summary.json, read as fba-evaluate reads it, or a grasp.
fba::Grasp grasp_file(const std::string& path) {
  const nlohmann::json j = fba::evaluate::read_json_file(path, "--grasp");
  if (j.is_object() && j.contains("contacts")) return fba::grasp::grasp_from_json(j, path);
  if (auto g = fba::evaluate::summary_grasp(j, path)) return *g;
  throw UsageError("--grasp: expected a run's summary.json with a grasp (a component's results.grasp, or a \"grasp\" member) or a "
                   "grasp (\"contacts\"); found none in '" + path + "' (did the run select one?)");
}

void print(const fba::GraspExecution& r) {
  std::printf("held %s, slip %.4f m, lifted %.3f m, held for %.2f s, %zu contacts%s%s\n", r.held ? "yes" : "no", r.slip_m,
              r.lift_height_m, r.hold_s, r.contacts.size(), r.reason.empty() ? "" : ": ", r.reason.c_str());
}

void print_plan(const fba::sim_hand::LiftTest& test) {
  if (!test.plan_note().empty()) std::printf("reach plan: %s\n", test.plan_note().c_str());
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
    print_plan(test);
  }
  std::printf("held %d of %d synthesised grasps\n", held, tried);
  return held == tried ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    (argc < 2 ? std::cerr : std::cout) << kUsage;
    return argc < 2 ? 2 : 0;
  }
  std::map<std::string, std::string> opt{{"--x", "0"},    {"--y", "0"},      {"--yaw", "0"},         {"--mass", "0.3"},
                                         {"--force", "15"}, {"--height", "0.5"}, {"--thumb-angle", "180"}, {"--repeat", "1"},
                                         {"--grasp", ""}, {"--synthesise", "0"}, {"--candidates", "1"}, {"--rest", "upright"},
                                         {"--voxel", "3"}};
  try {
    const std::string mesh_file = argv[1];
    if (mesh_file.rfind("-", 0) == 0) throw UsageError("expected the mesh file first; found the option '" + mesh_file + "'");
    for (int i = 2; i < argc; i += 2) {
      if (!opt.count(argv[i])) {
        std::string known;
        for (const auto& [name, value] : opt) known += (known.empty() ? "" : ", ") + name;
        throw UsageError(std::string("unknown option '") + argv[i] + "'; expected one of " + known);
      }
      if (i + 1 >= argc) throw UsageError(std::string(argv[i]) + ": expected a value after it; found the end of the line");
      opt[argv[i]] = argv[i + 1];
    }
    // Every value checked before any work, as sim.hand checks its parameters (the same ranges).
    fba::sim_hand::LiftTestParams params;
    params.mass = number("--mass", opt["--mass"], 0.001, 10);
    params.finger_force = number("--force", opt["--force"], fba::robotiq::kMinForce, fba::robotiq::kMaxForce);
    params.voxel_size = number("--voxel", opt["--voxel"], 0.5, 20) * 1e-3;
    const fba::sim_hand::ObjectPlacement placement{number("--x", opt["--x"], -1, 1), number("--y", opt["--y"], -1, 1),
                                                   number("--yaw", opt["--yaw"], -360, 360) * M_PI / 180, opt["--rest"]};
    if (placement.rest != "upright" && placement.rest != "side")
      throw UsageError("--rest must be upright or side; found '" + placement.rest + "'");
    const double height = number("--height", opt["--height"], 0, 1);
    const double thumb_angle = number("--thumb-angle", opt["--thumb-angle"], -360, 360);
    const int repeat = static_cast<int>(whole("--repeat", opt["--repeat"], 1, 10'000));
    int samples = static_cast<int>(whole("--synthesise", opt["--synthesise"], 0, 1'000'000, " (0: off)"));
    if (samples > 0) samples = static_cast<int>(whole("--synthesise", opt["--synthesise"], 3, 1'000'000, " (0: off)"));
    const int candidates = static_cast<int>(whole("--candidates", opt["--candidates"], 1, 1000));
    if (samples > 0 && !opt["--grasp"].empty()) throw UsageError("--grasp and --synthesise: expected one of them; found both");
    std::optional<fba::Grasp> given;
    if (!opt["--grasp"].empty()) given = grasp_file(opt["--grasp"]);

    const auto build_start = std::chrono::steady_clock::now();
    const auto mesh = fba::geometry::load_mesh(mesh_file);
    fba::sim_hand::LiftTest test(mesh, placement, params);
    std::printf("scene built (mesh loaded, voxelised into boxes, MuJoCo model compiled) in %.3f s wall time\n",
                std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count());
    std::printf("object: %s\n", fba::sim_hand::describe(test.pieces()).c_str());
    if (samples > 0) return synthesised(test, samples, candidates);
    fba::Grasp grasp;
    if (given) {
      grasp = *given;
    } else {
      double low = INFINITY, high = -INFINITY;
      for (const auto& v : test.object().vertices) low = std::min(low, double(v.z())), high = std::max(high, double(v.z()));
      grasp = fba::sim_hand::ring_grasp(test.object(), low + height * (high - low), thumb_angle * M_PI / 180);
    }
    fba::GraspExecution r;
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < repeat; ++i) r = test.run(grasp);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / repeat;
    print(r);
    print_plan(test);
    for (const auto& c : r.contacts)
      std::printf("  %-11s at (%.4f, %.4f, %.4f) normal (%.2f, %.2f, %.2f) force %.2f N\n", c.link.c_str(), c.position.x(),
                  c.position.y(), c.position.z(), c.normal.x(), c.normal.y(), c.normal.z(), c.force);
    std::printf("one lift test: %.3f s wall time for %.2f s simulated (%ld steps), mean of %d\n", wall, test.simulated_s(),
                test.steps(), repeat);
    return r.held ? 0 : 1;
  } catch (const UsageError& e) {
    std::cerr << "fba-lift-test: " << e.what() << " (see fba-lift-test --help)\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "fba-lift-test: " << e.what() << "\n";
    return 2;
  }
}
