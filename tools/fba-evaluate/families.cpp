// fba-evaluate families: an object set nobody tuned on (issue 31), written as meshes with a manifest
// and a batch list over them at random poses, each object resting as it would (settle.hpp).
#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/object_families.hpp"
#include "options.hpp"
#include "settle.hpp"

namespace fba::evaluate {

namespace {

namespace fs = std::filesystem;
using geometry::FamilyObject;
using geometry::ObjectFamily;

const char* kFamiliesHelp = R"(fba-evaluate families: object meshes by family, and a batch list over them at random poses.

  fba-evaluate families --seed S -o DIR [--per-family 10] [--poses 3] [--families box ring ...]
                        [--with-ycb [--ycb-dir data/ycb]] [--task tasks/grasp.yaml] [--variants-from LIST] [--jobs N]

Writes, for each family chosen (all by default: box, cylinder, sphere, ellipsoid, superquadric, ring,
l_shape, t_shape, tool, holed), --per-family objects drawn from the family's ranges by --seed
(docs/evaluating-grasps.md, "Objects nobody tuned on"): DIR/<family>/<family>-NN.obj, a closed
mesh in metres, z up, centred on its bounding box. Each object is dropped --poses times, from an
orientation drawn from its seed, onto the table in MuJoCo, and stepped until it is still: each rest
it comes to (drops that rest within 2 degrees of one another share one) is written as
DIR/<family>/<family>-NN-restK.obj, the object turned so that it stands as it rests (its lowest point
at z = 0), so that fba-run, which stands a mesh as its file stands (scene.rest upright), places it as
it settled.

DIR/manifest.json gives each object's family, kind, parameters, seed, volume and size, and each
drop's orientations (dropped, settled) and the rest it came to. DIR/families_random.yaml is a list
for fba-evaluate grasp --batch: one run per drop, on the rest it came to, at x and y within 2.5 cm
of the workspace's centre and a yaw drawn by the batch from --seed; with --with-ycb, the shipped
YCB meshes (data/ycb's <name>/model.obj from the current folder, or --ycb-dir's) --poses times
each, standing as their files stand, as in tasks/grasp_poses_random.yaml. Its variants are
--variants-from's (e.g. tasks/grasp_poses_random.yaml's loop, ring and uniform), else one, loop.

  fba-evaluate grasp --batch DIR/families_random.yaml --jobs 2 -o out/families

The same seed writes the same files on any machine (the physics: on the same build of MuJoCo).
DIR must be new or empty.

Options)";

// A drop's seed: the object's seed and the drop's number.
std::uint64_t drop_seed(std::uint64_t object_seed, int k) {
  std::uint64_t x = object_seed + 0x632be59bd9b4e019ULL * static_cast<std::uint64_t>(k + 1);
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Drops whose up directions lie within this angle rest the same way (up to a turn about the
// vertical, which the batch draws anyway).
constexpr double kSameRestDeg = 2.0;

struct Rest {
  std::string file;  // relative to DIR
  std::vector<int> drops;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // the object's direction that points up, in its own frame
  Eigen::Quaterniond tilt = Eigen::Quaterniond::Identity();  // object frame -> the rest file's frame
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
};

struct Drop {
  std::uint64_t seed = 0;
  SettleResult result;
  int rest = -1;
};

struct Written {
  FamilyObject object;
  std::string file;  // relative to DIR
  geometry::SolidProperties solid;
  std::vector<Drop> drops;
  std::vector<Rest> rests;
  double seconds = 0;
};

std::string shortest(float v) {
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

// A Wavefront OBJ: each vertex as the shortest text that reads back as the same float (so that no
// two distinct vertices weld when read), faces numbered from 1.
void write_obj(const TriangleMesh& mesh, const fs::path& path, const std::string& comment) {
  std::ofstream out(path);
  out << "# " << comment << "\n";
  for (const auto& v : mesh.vertices) out << "v " << shortest(v.x()) << ' ' << shortest(v.y()) << ' ' << shortest(v.z()) << '\n';
  for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

Written write_object(ObjectFamily family, std::uint64_t seed, int index, int poses, const fs::path& dir) {
  const auto start = std::chrono::steady_clock::now();
  Written w;
  w.object = geometry::make_family_object(family, seed, index);
  const FamilyObject& o = w.object;
  const std::string family_dir(geometry::family_name(family));
  w.file = family_dir + "/" + o.name + ".obj";
  write_obj(o.mesh, dir / w.file, "fba-evaluate families: " + o.name + " (" + o.kind + "), set seed " + std::to_string(seed));
  w.solid = geometry::solid_properties(o.mesh);
  for (int k = 0; k < poses; ++k) {
    Drop drop;
    drop.seed = drop_seed(o.seed, k);
    drop.result = settle(o.mesh, o.parts, random_orientation(drop.seed));
    const Eigen::Vector3d up = drop.result.settled.conjugate() * Eigen::Vector3d::UnitZ();
    for (std::size_t r = 0; r < w.rests.size() && drop.rest < 0; ++r)
      if (up.dot(w.rests[r].up) > std::cos(kSameRestDeg * std::numbers::pi / 180)) drop.rest = static_cast<int>(r);
    if (drop.rest < 0) {
      Rest rest;
      rest.up = up;
      rest.tilt = tilt_only(drop.result.settled);
      rest.file = family_dir + "/" + o.name + "-rest" + std::to_string(w.rests.size()) + ".obj";
      TriangleMesh rested = o.mesh;
      const Eigen::Matrix3f r = rest.tilt.toRotationMatrix().cast<float>();
      float lowest = INFINITY;
      for (auto& v : rested.vertices) {
        v = r * v;
        lowest = std::min(lowest, v.z());
      }
      for (auto& v : rested.vertices) v.z() -= lowest;
      rest.size = geometry::mesh_bounds(rested).sizes();
      write_obj(rested, dir / rest.file,
                "fba-evaluate families: " + o.name + " (" + o.kind + ") as it rests after drop " + std::to_string(k) + ", set seed " +
                    std::to_string(seed));
      drop.rest = static_cast<int>(w.rests.size());
      w.rests.push_back(std::move(rest));
    }
    w.rests[static_cast<std::size_t>(drop.rest)].drops.push_back(k);
    w.drops.push_back(std::move(drop));
  }
  w.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return w;
}

// The manifest's figures to what they mean: lengths to a micrometre, directions and quaternions to
// 1e-6, volumes to a cubic millimetre (the meshes' vertices are floats: 0.1056 is 0.10559999942779541).
double to(double v, double per_unit) { return std::round(v * per_unit) / per_unit + 0.0; }  // + 0.0: no -0
nlohmann::ordered_json quaternion(const Eigen::Quaterniond& q) { return {to(q.w(), 1e6), to(q.x(), 1e6), to(q.y(), 1e6), to(q.z(), 1e6)}; }
nlohmann::ordered_json vector(const Eigen::Vector3d& v, double per_unit = 1e6) { return {to(v.x(), per_unit), to(v.y(), per_unit), to(v.z(), per_unit)}; }

nlohmann::ordered_json object_json(const Written& w) {
  const FamilyObject& o = w.object;
  nlohmann::ordered_json params = nlohmann::ordered_json::object();
  for (const auto& [k, v] : o.parameters) params[k] = v;
  nlohmann::ordered_json rests = nlohmann::ordered_json::array(), drops = nlohmann::ordered_json::array();
  for (const auto& r : w.rests)
    rests.push_back({{"file", r.file}, {"drops", r.drops}, {"up_in_object", vector(r.up)}, {"tilt_wxyz", quaternion(r.tilt)},
                     {"size_m", vector(r.size)}});
  for (std::size_t k = 0; k < w.drops.size(); ++k) {
    const auto& d = w.drops[k];
    nlohmann::ordered_json j = {{"drop", k},
                                {"seed", d.seed},
                                {"dropped_wxyz", quaternion(d.result.dropped)},
                                {"settled_wxyz", quaternion(d.result.settled)},
                                {"still", d.result.still},
                                {"settle_s", d.result.time},
                                {"rest", d.rest}};
    if (!d.result.warnings.empty()) j["mujoco_warnings"] = d.result.warnings;
    drops.push_back(std::move(j));
  }
  const Eigen::AlignedBox3d box = geometry::mesh_bounds(o.mesh);
  double radius = 0;
  for (const auto& v : o.mesh.vertices) radius = std::max(radius, v.cast<double>().norm());
  return {{"name", o.name},
          {"family", std::string(geometry::family_name(o.family))},
          {"kind", o.kind},
          {"index", o.index},
          {"seed", o.seed},
          {"file", w.file},
          {"parameters", params},
          {"volume_m3", to(w.solid.volume, 1e9)},
          {"size_m", vector(box.sizes())},
          {"radius_m", to(radius, 1e6)},
          {"triangles", o.mesh.triangles.size()},
          {"rests", rests},
          {"drops", drops}};
}

// The path of `p` as the list in `dir` names it: relative to the list when it can be.
std::string from_list(const fs::path& p, const fs::path& dir) {
  std::error_code ec;
  const fs::path r = fs::relative(fs::absolute(p), fs::absolute(dir), ec);
  return ec || r.empty() ? fs::absolute(p).lexically_normal().string() : r.string();
}

std::vector<ObjectFamily> chosen_families(const std::vector<std::string>& words) {
  std::string known;
  for (ObjectFamily f : geometry::all_families()) known += std::string(known.empty() ? "" : ", ") + std::string(geometry::family_name(f));
  std::vector<ObjectFamily> out;
  for (const auto& word : words) {
    std::stringstream ss(word);
    std::string name;
    while (std::getline(ss, name, ',')) {
      if (name.empty()) continue;
      const auto f = geometry::family_from_name(name);
      if (!f) throw ArgumentError("--families: unknown family '" + name + "'; expected some of " + known);
      if (std::find(out.begin(), out.end(), *f) != out.end()) throw ArgumentError("--families: '" + name + "' is given twice");
      out.push_back(*f);
    }
  }
  if (out.empty()) throw ArgumentError("--families: expected at least one of " + known + "; found none");
  return out;
}

// The variants of an existing list, as flow mappings.
std::vector<std::string> variants_from(const std::string& file) {
  if (!fs::is_regular_file(file)) throw ArgumentError("--variants-from: expected a batch list file; found no file '" + file + "'");
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::Exception& e) {
    throw ArgumentError("--variants-from: " + file + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
                        ": not valid YAML: " + e.msg);
  }
  const YAML::Node v = root.IsMap() ? root["variants"] : YAML::Node();
  if (!v || !v.IsSequence() || v.size() == 0)
    throw ArgumentError("--variants-from: expected " + file + " to have a list 'variants'; found " + (v ? "something else" : "none"));
  std::vector<std::string> out;
  for (const auto& item : v) {
    YAML::Node flow = YAML::Clone(item);  // the emitter keeps a node's own (block) style over YAML::Flow
    flow.SetStyle(YAML::EmitterStyle::Flow);
    YAML::Emitter e;
    e << flow;
    out.push_back(e.c_str());
  }
  return out;
}

std::vector<fs::path> ycb_meshes(const fs::path& dir) {
  if (!fs::is_directory(dir))
    throw ArgumentError("--ycb-dir: expected the folder of the shipped YCB meshes (<name>/model.obj); found no folder '" + dir.string() +
                        "' (run from the project's root, or give --ycb-dir)");
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (fs::is_regular_file(e.path() / "model.obj")) out.push_back(e.path() / "model.obj");
  std::sort(out.begin(), out.end());
  if (out.empty()) throw ArgumentError("--ycb-dir: expected <name>/model.obj meshes in '" + dir.string() + "'; found none");
  return out;
}

// Every object written on its own, `jobs` at a time, in any order: the same files whatever --jobs.
std::vector<Written> write_objects(const std::vector<ObjectFamily>& families, int per_family, std::uint64_t seed, int poses,
                                   const fs::path& dir, int jobs) {
  std::vector<std::pair<ObjectFamily, int>> todo;
  for (ObjectFamily f : families)
    for (int i = 0; i < per_family; ++i) todo.emplace_back(f, i);
  std::vector<Written> written(todo.size());
  std::atomic<std::size_t> next{0};
  std::exception_ptr failed;
  std::mutex failed_lock;
  const auto work = [&] {
    for (std::size_t i; (i = next++) < todo.size();) {
      try {
        written[i] = write_object(todo[i].first, seed, todo[i].second, poses, dir);
      } catch (...) {
        const std::lock_guard lock(failed_lock);
        if (!failed) failed = std::current_exception();
        next = todo.size();
      }
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < std::min<int>(jobs, static_cast<int>(todo.size())); ++t) threads.emplace_back(work);
  work();
  for (auto& t : threads) t.join();
  if (failed) std::rethrow_exception(failed);
  return written;
}

// Per family: objects, drops, rests and drops not still, and the settling's seconds; each drop not
// still and MuJoCo's warnings on stderr. Returns how many drops were not still.
std::size_t report_settling(const std::vector<ObjectFamily>& families, const std::vector<Written>& written) {
  std::printf("%-13s %7s %6s %6s %9s %8s\n", "family", "objects", "drops", "rests", "not still", "seconds");
  std::size_t not_still = 0;
  for (ObjectFamily f : families) {
    std::size_t objects = 0, drops = 0, rests = 0, moving = 0;
    double seconds = 0;
    for (const auto& w : written) {
      if (w.object.family != f) continue;
      ++objects;
      drops += w.drops.size();
      rests += w.rests.size();
      seconds += w.seconds;
      for (const auto& d : w.drops) moving += !d.result.still;
    }
    not_still += moving;
    std::printf("%-13s %7zu %6zu %6zu %9zu %8.1f\n", std::string(geometry::family_name(f)).c_str(), objects, drops, rests, moving, seconds);
  }
  for (const auto& w : written)
    for (std::size_t k = 0; k < w.drops.size(); ++k) {
      const auto& d = w.drops[k];
      if (!d.result.still)
        std::fprintf(stderr, "fba-evaluate families: warning: %s's drop %zu was still moving after %g s simulated; its pose then is used\n",
                     w.object.name.c_str(), k, d.result.time);
      for (const auto& m : d.result.warnings)
        std::fprintf(stderr, "fba-evaluate families: warning: %s's drop %zu: MuJoCo: %s\n", w.object.name.c_str(), k, m.c_str());
    }
  return not_still;
}

void write_manifest(const fs::path& dir, std::uint64_t seed, int per_family, int poses, const std::vector<ObjectFamily>& families,
                    const std::vector<Written>& written, const std::vector<fs::path>& ycb) {
  nlohmann::ordered_json manifest = {{"generator", "fba-evaluate families"},
                                     {"seed", seed},
                                     {"per_family", per_family},
                                     {"poses", poses},
                                     {"list", "families_random.yaml"}};
  nlohmann::ordered_json names = nlohmann::ordered_json::array();
  for (ObjectFamily f : families) names.push_back(std::string(geometry::family_name(f)));
  manifest["families"] = names;
  const SettleParams settle_params;
  manifest["settle"] = {{"drop_height_m", settle_params.drop_height}, {"mass_kg", settle_params.mass}, {"friction", settle_params.friction},
                        {"timestep_s", settle_params.timestep},      {"still_tilt_deg", settle_params.still_tilt_deg},
                        {"still_move_m", settle_params.still_move},  {"still_time_s", settle_params.still_time},
                        {"max_time_s", settle_params.max_time},      {"same_rest_deg", kSameRestDeg}};
  nlohmann::ordered_json objects = nlohmann::ordered_json::array();
  for (const auto& w : written) objects.push_back(object_json(w));
  manifest["objects"] = objects;
  nlohmann::ordered_json ycb_json = nlohmann::ordered_json::array();
  for (const auto& m : ycb) ycb_json.push_back(from_list(m, dir));
  manifest["ycb"] = ycb_json;
  std::ofstream(dir / "manifest.json") << manifest.dump(2) << "\n";
}

// The batch list over the written rests (and the YCB meshes); returns its runs.
std::size_t write_list(const fs::path& dir, std::uint64_t seed, int per_family, int poses, const std::vector<ObjectFamily>& families,
                       const std::vector<Written>& written, const std::vector<fs::path>& ycb, const std::string& task,
                       const std::vector<std::string>& variants) {
  std::ostringstream list;
  list << "# Written by fba-evaluate families --seed " << seed << " --per-family " << per_family << " --poses " << poses << " ("
       << families.size() << " families" << (ycb.empty() ? "" : ", with the YCB meshes") << "); manifest.json says what each mesh is.\n"
       << "# Each family mesh is an object in a rest it came to when dropped onto the table in MuJoCo, turned to stand\n"
       << "# as it rested (scene.rest upright); x, y and yaw are drawn by the batch from the seed below.\n"
       << "#\n#   fba-evaluate grasp --batch <this file> --jobs 2 -o out/families\n"
       << "task: " << from_list(task, dir) << "\n"
       << "fba_run_args: [-e, deterministic]\n"
       << "timeout_s: 600\n"
       << "pose_set:\n  - scene.mesh={mesh}\n  - scene.x={x}\n  - scene.y={y}\n  - scene.yaw={yaw}\n"
       << "variants:\n";
  for (const auto& v : variants) list << "  - " << v << "\n";
  list << "random_runs:\n  meshes:\n";
  std::size_t runs = 0;
  for (const auto& w : written)
    for (std::size_t k = 0; k < w.drops.size(); ++k, ++runs) {
      const auto& d = w.drops[k];
      const Eigen::Vector3d up = w.rests[static_cast<std::size_t>(d.rest)].up;
      char note[160];
      std::snprintf(note, sizeof note, "   # %s drop %zu: up is (%.3f, %.3f, %.3f) in the object's frame%s", w.object.name.c_str(), k, up.x(), up.y(),
                    up.z(), d.result.still ? "" : "; still moving when read");
      list << "    - " << w.rests[static_cast<std::size_t>(d.rest)].file << note << "\n";
    }
  for (const auto& m : ycb)
    for (int k = 0; k < poses; ++k, ++runs) list << "    - " << from_list(m, dir) << "   # as shipped, standing as its file stands\n";
  list << "  per_mesh: 1\n  x: [-0.025, 0.025]\n  y: [-0.025, 0.025]\n  yaw: [0, 360]\n  seed: " << seed << "\n";
  std::ofstream(dir / "families_random.yaml") << list.str();
  return runs;
}

}  // namespace

int run_families(const std::vector<std::string>& args) {
  namespace po = boost::program_options;
  po::options_description opts(kFamiliesHelp);
  std::uint64_t seed = 0;
  int per_family = 10, poses = 3, jobs = 1;
  std::vector<std::string> family_words;
  std::string out_dir, task = "tasks/grasp.yaml", ycb_dir = "data/ycb", variants_file;
  opts.add_options()("help,h", "this help")(
      "seed", ranged("seed", &seed, std::uint64_t{0}, std::numeric_limits<std::uint64_t>::max()),
      "the set's seed, required: the objects' parameters, their drops and the batch's poses")(
      "output,o", po::value(&out_dir)->required(), "the folder to write into: new or empty")(
      "per-family", ranged("per-family", &per_family, 1, 1000), "objects per family")(
      "poses", ranged("poses", &poses, 1, 100), "drops per object: runs per object in the list")(
      "families", po::value(&family_words)->multitoken(), "the families (names, or a comma-separated list); default: all")(
      "with-ycb", "add the shipped YCB meshes to the list, --poses runs each")(
      "ycb-dir", po::value(&ycb_dir), "with --with-ycb: the folder of the YCB meshes (default data/ycb)")(
      "task", po::value(&task)->default_value(task), "the task file the list runs")(
      "variants-from", po::value(&variants_file), "copy this batch list's variants (default: one, loop)")(
      "jobs,j", ranged("jobs", &jobs, 1, 64), "objects settled at a time");
  po::variables_map vm = parse(args, opts);
  if (vm.count("help")) {
    std::cout << opts << "\n";
    return 0;
  }
  po::notify(vm);
  // Required, though declared with a default (a ranged option's), which boost takes as given.
  if (vm["seed"].defaulted())
    throw ArgumentError("--seed is required: the set's seed (fix it, and keep the list, before the first run, so that the set cannot have been chosen for its result)");
  const std::vector<ObjectFamily> families =
      vm.count("families") ? chosen_families(family_words) : std::vector<ObjectFamily>(geometry::all_families());
  if (vm.count("ycb-dir") && !vm.count("with-ycb")) throw ArgumentError("--ycb-dir applies with --with-ycb: give --with-ycb as well");
  if (!fs::is_regular_file(task))
    throw ArgumentError("--task: expected the task file the list runs; found no file '" + task + "' (run from the project's root, or give --task)");
  const std::vector<fs::path> ycb = vm.count("with-ycb") ? ycb_meshes(ycb_dir) : std::vector<fs::path>{};
  const std::vector<std::string> variants = variants_file.empty() ? std::vector<std::string>{"{name: loop}"} : variants_from(variants_file);
  const fs::path dir(out_dir);
  if (fs::exists(dir) && !fs::is_directory(dir))
    throw ArgumentError("--output: expected a folder to write the set into; found '" + out_dir + "', which is not one");
  if (fs::exists(dir) && !fs::is_empty(dir))
    throw ArgumentError("--output: expected a new or empty folder (a set is not written over another); found '" + out_dir + "' with " +
                        std::to_string(std::distance(fs::directory_iterator(dir), fs::directory_iterator{})) + " entries");
  for (ObjectFamily f : families) fs::create_directories(dir / std::string(geometry::family_name(f)));

  const auto start = std::chrono::steady_clock::now();
  const std::vector<Written> written = write_objects(families, per_family, seed, poses, dir, jobs);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::size_t not_still = report_settling(families, written);
  write_manifest(dir, seed, per_family, poses, families, written, ycb);
  const std::size_t runs = write_list(dir, seed, per_family, poses, families, written, ycb, task, variants);
  std::printf("%zu objects, %zu runs (%zu x %zu variant(s)) in %s/families_random.yaml, manifest.json beside it; %.1f s%s\n", written.size(), runs,
              runs, variants.size(), out_dir.c_str(), wall, not_still ? " (some drops not still: see above)" : "");
  return 0;
}

}  // namespace fba::evaluate
