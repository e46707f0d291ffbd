// fba-evaluate: how accurate is a carved model?
//
//   fba-evaluate synthetic --mesh A.obj [B.obj ...] [--views 8] [--depth 6]
//       Renders each mesh from views spread over the upper hemisphere (f = 600 px, 640x480),
//       carves with the exact masks, prints voxel IoU against the true voxelisation and the
//       number of truly occupied voxels carved away (table plane clipped).
//   fba-evaluate model --model carved.ply [--mesh truth.obj] [--images set] [--task T.yaml] --depth 6
//       (a) with --mesh: voxel IoU and carved-away count of the model against the mesh;
//       (b) with --images or --task: re-projection IoU of the model onto each silhouette of the
//       image set. With --task, the silhouettes come from the task's own vision.contour_extraction
//       component, run with the task's parameters (and --set overrides), on the task's image set
//       unless --images names another; without it, the set's own masks when every view has one
//       (fba YAML 'mask'), else fba's default extraction.
//   fba-evaluate grasp --mesh M.obj --summary run/summary.json | --random 1000 | --synthesise
//       Grasp quality on the true surface (grasp.cpp; see its --help).
//   fba-evaluate grasp --batch LIST.yaml [--jobs N] [-o DIR]
//       The grasp loop over objects and poses, run by fba-run, and the targets' table (grasp_batch.cpp).
//   fba-evaluate families --seed S -o DIR [--per-family 10] [--poses 3] [--families ...] [--with-ycb]
//       Object meshes by family, each resting as it settles in MuJoCo, and a batch list over them
//       at random poses (families.cpp).

#include <cmath>
#include <cstdio>
#include <iostream>
#include <numeric>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

#include "evaluate.hpp"
#include "options.hpp"
#include "fba/geometry/mesh_io.hpp"
#include "fba/log.hpp"
#include "fba/registry.hpp"
#include "fba/task_config.hpp"
#include "fba/testing.hpp"
#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/image_set.hpp"

namespace po = boost::program_options;
using namespace fba;
using fba::evaluate::ArgumentError;
using fba::evaluate::check_range;
using fba::evaluate::number;
using fba::evaluate::parse;
using fba::evaluate::ranged;

namespace {

// The finest level a dense voxel grid can take: 2^(3*10) voxels is already 1 GiB.
constexpr int kMaxDepth = 10;

// An option of the mesh comparison (a) given without --mesh would be silently ignored.
void check_needs_mesh(const po::variables_map& vm, const std::string& mesh, std::initializer_list<const char*> names) {
  if (!mesh.empty()) return;
  for (const char* n : names)
    if (vm.count(n) && !vm[n].defaulted())
      throw ArgumentError(std::string("--") + n + " applies to the comparison with a mesh: give --mesh as well");
}

void print_summary(const char* what, const std::vector<double>& v) {
  if (v.empty()) return;
  const double mean = std::accumulate(v.begin(), v.end(), 0.0) / v.size();
  std::printf("%s: min %.4f  mean %.4f  over %zu views\n", what,
              *std::min_element(v.begin(), v.end()), mean, v.size());
}

// The silhouettes of the image set's views, and for each view without one why not.
struct Silhouettes {
  std::vector<Silhouette> found;
  std::vector<std::string> missing;
};

// The providers' masks, made independently of fba.
Silhouettes set_masks(const vision::ImageSet& set) {
  Silhouettes out;
  for (std::size_t i = 0; i < set.size(); ++i) {
    Silhouette s;
    s.frame = std::make_shared<Frame>(set.load_frame(i));
    s.mask = set.load_mask(i);
    out.found.push_back(std::move(s));
  }
  return out;
}

Silhouettes default_silhouettes(const vision::ImageSet& set) {
  Silhouettes out;
  for (std::size_t i = 0; i < set.size(); ++i) {
    auto r = vision::extract_silhouette(std::make_shared<Frame>(set.load_frame(i)));
    if (r.ok()) out.found.push_back(*r.silhouette);
    else out.missing.push_back(set[i].name + ": no silhouette (" + r.error + ")");
  }
  return out;
}

const ComponentConfig& only_component_of_type(const TaskConfig& task, const std::string& type) {
  const ComponentConfig* found = nullptr;
  for (const auto& c : task.components) {
    if (c.type->spec.type_name() != type) continue;
    if (found)
      throw ArgumentError("--task: " + task.file.string() + " has two " + type + " components ('" + found->name + "' and '" + c.name +
                          "'); fba-evaluate takes one");
    found = &c;
  }
  if (!found) throw ArgumentError("--task: " + task.file.string() + " has no " + type + " component");
  return *found;
}

// The task's own contour extraction: its vision.contour_extraction component, built from the
// plugin with the task's resolved parameters and fed each view, so the silhouettes are made as
// the task makes them (not by fba's defaults, which would agree with the carver by construction
// only for a task that uses them).
struct TaskExtraction {
  Registry registry;
  TaskConfig task;
  const ComponentConfig* contours = nullptr;
  const ComponentConfig* views = nullptr;  // the task's vision.image_set, if any
};

void load_task_extraction(TaskExtraction& t, const std::string& file, const std::vector<std::string>& sets) {
  for (const auto& e : t.registry.load_path(plugin_search_path()))
    std::fprintf(stderr, "fba-evaluate: warning: plugin %s: %s\n", e.file().c_str(), e.reason().c_str());
  LoadOptions options;
  for (const auto& s : sets) options.overrides.push_back({s});
  try {
    t.task = load_task(file, t.registry, options);
  } catch (const ConfigError& e) {
    std::string all;
    for (const auto& d : e.diagnostics()) all += "\n  " + d.str();
    throw ArgumentError("--task: the task file does not load:" + all);
  }
  t.contours = &only_component_of_type(t.task, "vision.contour_extraction");
  for (const auto& c : t.task.components)
    if (c.type->spec.type_name() == "vision.image_set") t.views = &c;
}

Silhouettes task_silhouettes(const TaskExtraction& t, const vision::ImageSet& set) {
  set_log_level("error");  // a view without a target is reported below, once
  testing::ComponentHarness contours(t.registry, t.contours->type->spec.type_name(), t.contours->params);
  Silhouettes out;
  for (std::size_t i = 0; i < set.size(); ++i) {
    const std::size_t before = contours.packets("silhouette").size();
    const std::size_t events = contours.events().size();
    contours.push<Frame>("frame", set.load_frame(i));
    contours.run();
    if (!contours.failure().empty()) throw std::runtime_error(t.contours->name + " failed on " + set[i].name + ": " + contours.failure());
    const auto& packets = contours.packets("silhouette");
    if (packets.size() > before) {
      out.found.push_back(packets.back().get<Silhouette>());
      continue;
    }
    std::string why = "the component gave none";
    const auto ev = contours.events();
    for (std::size_t k = events; k < ev.size(); ++k)
      if (ev[k].name == "no_target") why = ev[k].payload;
    out.missing.push_back(set[i].name + ": no silhouette (" + why + ")");
  }
  return out;
}

int run_synthetic(const std::vector<std::string>& args) {
  po::options_description opts("fba-evaluate synthetic");
  std::vector<std::string> meshes;
  evaluate::SyntheticParams p;
  std::string save_dir;
  opts.add_options()("help,h", "this help")
      ("mesh", po::value(&meshes)->multitoken()->required(), "mesh file(s) (OBJ, PLY, STL, ...)")
      ("views", ranged("views", &p.views, 1, 1000), "number of views")
      ("depth", ranged("depth", &p.depth, 1, kMaxDepth), "octree max depth (2^depth voxels per axis)")
      ("min-elevation", ranged("min-elevation", &p.min_elevation_deg, -90.0, 90.0), "lowest view elevation, degrees")
      ("max-elevation", ranged("max-elevation", &p.max_elevation_deg, -90.0, 90.0), "highest view elevation, degrees")
      ("margin", ranged("margin", &p.margin, 0.0, 10.0), "root cube margin, fraction of the largest side")
      ("no-table-clip", "do not drop voxels below the mesh's lowest point")
      ("threads", ranged("threads", &p.threads, 0, 256), "carver threads (0 = all cores)")
      ("tolerance", ranged("tolerance", &p.silhouette_tolerance, 0.0, 1000.0), "carver silhouette tolerance, pixels")
      ("save", po::value(&save_dir), "write renders, masks, carved and true models (PLY) here");
  po::variables_map vm = parse(args, opts);
  if (vm.count("help")) {
    std::cout << opts << "\n";
    return 0;
  }
  po::notify(vm);
  check_range("max-elevation", p.max_elevation_deg, p.min_elevation_deg, 90.0);
  p.table_clip = !vm.count("no-table-clip");
  p.save_dir = save_dir;

  std::printf("views %d over elevations %.1f..%.1f deg, depth %d (%d^3), table clip %s\n", p.views,
              p.min_elevation_deg, p.max_elevation_deg, p.depth, 1 << p.depth,
              p.table_clip ? "on" : "off");
  std::printf("%-40s %8s %8s %8s %7s %7s %9s %9s\n", "mesh", "truth", "model", "carved", "IoU",
              "reprojIoU", "render_ms", "carve_ms");
  int worst = 0;
  for (const auto& m : meshes) {
    const evaluate::SyntheticResult r = evaluate::evaluate_synthetic(m, p);
    const double reproj = r.reprojection_iou.empty() ? 0.0
        : *std::min_element(r.reprojection_iou.begin(), r.reprojection_iou.end());
    std::printf("%-40s %8zu %8zu %8zu %7.4f %9.4f %9.2f %9.1f\n",
                std::filesystem::path(m).parent_path().filename().string().c_str(),
                r.voxels.truth_voxels, r.voxels.model_voxels, r.voxels.carved_away, r.voxels.iou,
                reproj, r.render_ms_mean, r.carve_ms);
    if (r.voxels.carved_away > 0) worst = 1;
  }
  // Exit status 1 when a conservative carve removed a truly occupied voxel.
  return worst;
}

int run_model(const std::vector<std::string>& args) {
  po::options_description opts("fba-evaluate model");
  std::string model_path, mesh_path, images, task_file;
  std::vector<std::string> sets;
  std::vector<double> bounds;
  int depth = 6;
  double margin = 0.05;
  opts.add_options()("help,h", "this help")
      ("model", po::value(&model_path)->required(), "the model as a mesh (carved octree PLY)")
      ("depth", ranged("depth", &depth, 1, kMaxDepth), "resolution 2^depth of the model's octree")
      ("mesh", po::value(&mesh_path), "(a) the true object mesh")
      ("bounds", po::value(&bounds)->multitoken(),
       "the carver's root box: xmin ymin zmin xmax ymax zmax (made a cube); default: the mesh's "
       "bounding box made a cube with --margin")
      ("margin", ranged("margin", &margin, 0.0, 10.0), "see --bounds")
      ("no-table-clip", "do not drop voxels below the mesh's lowest point")
      ("images", po::value(&images), "(b) an image set (Middlebury *_par.txt or fba YAML)")
      ("task", po::value(&task_file),
       "(b) make the silhouettes with this task's vision.contour_extraction and its parameters; the image set is the "
       "task's vision.image_set unless --images is given")
      ("set", po::value(&sets)->composing(), "with --task: override a task parameter, component.param=value (repeatable)");
  po::variables_map vm = parse(args, opts);
  if (vm.count("help")) {
    std::cout << opts << "\n";
    return 0;
  }
  po::notify(vm);
  if (!bounds.empty()) {
    evaluate::check_finite_numbers("bounds", bounds, 6, "xmin ymin zmin xmax ymax zmax");
    for (int i = 0; i < 3; ++i) {
      const char axis = static_cast<char>('x' + i);
      if (!(bounds[i] < bounds[i + 3]))
        throw ArgumentError(std::string("--bounds: ") + axis + "min must be below " + axis + "max; found " + number(bounds[i]) +
                            " and " + number(bounds[i + 3]));
    }
  }
  check_needs_mesh(vm, mesh_path, {"depth", "bounds", "margin", "no-table-clip"});
  if (!sets.empty() && task_file.empty()) throw ArgumentError("--set applies to the task given with --task: give --task as well");
  // The task is read before any work, so that a bad task file is refused at once.
  TaskExtraction extraction;
  bool good_only = true;
  std::size_t limit = 0;
  if (!task_file.empty()) {
    load_task_extraction(extraction, task_file, sets);
    if (images.empty()) {
      if (!extraction.views)
        throw ArgumentError("--task: " + task_file + " has no vision.image_set component: give the images with --images");
      const auto& p = extraction.views->params;
      images = std::get<std::string>(p.at("file"));
      good_only = std::get<bool>(p.at("good_only"));
      limit = static_cast<std::size_t>(std::get<std::int64_t>(p.at("limit")));
    }
  }
  const TriangleMesh model = geometry::load_mesh(model_path);
  std::printf("model %s: %zu triangles\n", model_path.c_str(), model.triangles.size());

  if (!mesh_path.empty()) {
    const TriangleMesh truth_mesh = evaluate::load_closed_mesh(mesh_path);
    const auto box = geometry::mesh_bounds(truth_mesh);
    Eigen::AlignedBox3d cube;
    if (!bounds.empty()) {
      cube = geometry::cube_around(Eigen::AlignedBox3d(Eigen::Vector3d(bounds[0], bounds[1], bounds[2]),
                                                       Eigen::Vector3d(bounds[3], bounds[4], bounds[5])),
                                   0.0);
    } else {
      cube = geometry::cube_around(box, margin);
    }
    std::optional<double> z_min;
    if (!vm.count("no-table-clip")) z_min = box.min().z();
    const auto c = evaluate::compare_voxels(geometry::voxelize(truth_mesh, cube, depth),
                                            evaluate::model_mesh_to_grid(model, cube, depth), z_min);
    std::printf("(a) vs %s at %d^3: truth %zu voxels, model %zu, carved away %zu, IoU %.4f\n",
                mesh_path.c_str(), 1 << depth, c.truth_voxels, c.model_voxels, c.carved_away, c.iou);
  }
  if (!images.empty()) {
    auto set = vision::ImageSet::load(images, good_only);
    if (limit > 0 && limit < set.size())
      set = vision::ImageSet(std::vector<vision::ViewDescriptor>(set.views().begin(), set.views().begin() + static_cast<std::ptrdiff_t>(limit)));
    const std::string by = extraction.contours ? "the task's component '" + extraction.contours->name + "' (" + task_file + ")"
                           : set.has_masks()   ? std::string("the set's own masks")
                                               : std::string("fba's default extraction (give --task to use a task's settings)");
    std::printf("silhouettes of %s by %s\n", images.c_str(), by.c_str());
    const Silhouettes made = extraction.contours ? task_silhouettes(extraction, set)
                             : set.has_masks()   ? set_masks(set)
                                                 : default_silhouettes(set);
    for (const auto& m : made.missing) std::printf("  view %s\n", m.c_str());
    const std::vector<Silhouette>& silhouettes = made.found;
    const auto ious = evaluate::reprojection_ious(model, silhouettes);
    for (std::size_t i = 0; i < ious.size(); ++i)
      std::printf("  %-24s reprojection IoU %.4f\n", silhouettes[i].frame->source.c_str(), ious[i]);
    print_summary("(b) reprojection IoU", ious);
  }
  if (mesh_path.empty() && images.empty()) std::printf("nothing to compare: give --mesh and/or --images or --task\n");
  return 0;
}

}  // namespace

// The grasp subcommand lives in grasp.cpp (grasp quality on the true surface), the families one in
// families.cpp.
namespace fba::evaluate {
int run_grasp(const std::vector<std::string>& args);
int run_families(const std::vector<std::string>& args);
}

int main(int argc, char** argv) {
  const std::string usage =
      "usage: fba-evaluate synthetic --mesh M.obj [M2.obj ...] [--views 8] [--depth 6] [options]\n"
      "       fba-evaluate model --model carved.ply [--mesh truth.obj] [--images set] [--task T.yaml [--set c.p=v]] [--depth 6]\n"
      "       fba-evaluate grasp --mesh M.obj (--summary run/summary.json | --random 1000 | --synthesise)\n"
      "       fba-evaluate grasp --batch LIST.yaml [--jobs N] [-o DIR]\n"
      "       fba-evaluate families --seed S -o DIR [--per-family 10] [--poses 3] [--families box ring ...] [--with-ycb]\n"
      "       fba-evaluate <command> --help\n";
  if (argc < 2) {
    std::cerr << usage;
    return 2;
  }
  const std::string command = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  try {
    if (command == "synthetic") return run_synthetic(args);
    if (command == "model") return run_model(args);
    if (command == "grasp") return evaluate::run_grasp(args);
    if (command == "families") return evaluate::run_families(args);
    if (command == "--help" || command == "-h") {
      std::cout << usage;
      return 0;
    }
    std::cerr << "fba-evaluate: unknown command '" << command << "'\n" << usage;
    return 2;
  } catch (const po::error& e) {
    std::cerr << "fba-evaluate " << command << ": " << e.what() << " (see fba-evaluate " << command << " --help)\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "fba-evaluate: " << e.what() << "\n";
    return 2;
  }
}
