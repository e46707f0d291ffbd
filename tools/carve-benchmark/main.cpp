// Reference vs fast octree carving on the Middlebury dino (the 15 good views, silhouettes by the
// providers' recipe), at depths 6, 7 and 8: times (the fast carver with 1 thread and with
// --threads), speed-up, nodes visited, model size, leaf classification mismatches (exit code 1 if
// any); then the incremental carve view by view (nodes visited against the batch, what
// publishing a snapshot after each view costs); and the re-projection IoU of the model on every
// silhouette: the carved ones (self-consistency) and, as accuracy against masks the carve never
// saw, silhouettes made another way (Otsu's threshold instead of the fixed 0.19, same clean-up).
//
//   fba-carve-benchmark [data-dir] [--repeat N] [--threads N] [--depths 6,7,8] [--tolerance PX] [--detail VIEWS,DEPTH]
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/image_set.hpp"
#include "fba/vision/octree_carver.hpp"
#include "fba/vision/reference_carve.hpp"
#include "support/build_paths.hpp"

using namespace fba::vision;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// The whole process's CPU time (every thread's), printed beside wall time: a multi-threaded carve's
// wall speed-up is worth what its extra CPU costs.
double cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// A number option's value, whole and within [lo, hi]; anything else ends the program with the
// option, what was expected and what was found (atoi took "x" for 0 and "-1" for all cores).
double option_value(const std::string& name, const std::string& text, double lo, double hi, bool integer) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno == ERANGE || !(v >= lo && v <= hi) || (integer && v != std::floor(v))) {
    std::fprintf(stderr, "fba-carve-benchmark: %s must be %s in [%g, %g]; found '%s'\n", name.c_str(),
                 integer ? "a whole number" : "a number", lo, hi, text.c_str());
    std::exit(2);
  }
  return v;
}

// Comma-separated whole numbers, each in [lo, hi], as option_value checks one.
std::vector<int> option_list(const std::string& name, const std::string& text, double lo, double hi) {
  std::vector<int> out;
  std::size_t start = 0;
  do {
    const std::size_t comma = text.find(',', start);
    out.push_back(int(option_value(name, text.substr(start, comma - start), lo, hi, true)));
    start = comma == std::string::npos ? comma : comma + 1;
  } while (start != std::string::npos);
  return out;
}

struct Options {
  std::string data = fba::test::data_dir();
  int repeat = 5, threads = 0;
  std::vector<int> depths{6, 7, 8};
  double tolerance = CarverParams{}.silhouette_tolerance;
  int detail_after_views = CarverParams{}.detail_after_views, detail_depth = CarverParams{}.detail_depth;
};

// The command line into `o`; the exit status when the program should stop here (help, an error).
std::optional<int> parse_options(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeat" && i + 1 < argc) o.repeat = int(option_value(a, argv[++i], 1, 1000, true));
    else if (a == "--threads" && i + 1 < argc) o.threads = int(option_value(a, argv[++i], 0, 256, true));
    else if (a == "--tolerance" && i + 1 < argc) o.tolerance = option_value(a, argv[++i], 0, 100, false);
    else if (a == "--detail" && i + 1 < argc) {
      const std::vector<int> d = option_list(a, argv[++i], 0, 1000);  // the carver checks the depth against its own limits
      if (d.size() != 2) {
        std::fprintf(stderr, "fba-carve-benchmark: --detail takes VIEWS,DEPTH; found '%s'\n", argv[i]);
        return 2;
      }
      o.detail_after_views = d[0];
      o.detail_depth = d[1];
    }
    else if (a == "--depths" && i + 1 < argc) o.depths = option_list(a, argv[++i], 1, 10);
    else if (a.rfind("-", 0) == 0) {
      const bool help = a == "--help" || a == "-h";
      std::fprintf(help ? stdout : stderr, "usage: fba-carve-benchmark [data-dir] [--repeat N] [--threads N] [--depths 6,7,8] [--tolerance PX] [--detail VIEWS,DEPTH]\n");
      if (!help) std::fprintf(stderr, "unknown or incomplete option '%s'\n", a.c_str());
      return help ? 0 : 2;
    } else {
      o.data = a;
    }
  }
  return std::nullopt;
}

// The carver's parameters at `depth` with the options' tolerance and detail (threads left as they are).
CarverParams carver_params(const Options& o, int depth) {
  CarverParams p;
  p.max_depth = depth;
  p.silhouette_tolerance = o.tolerance;
  p.detail_after_views = o.detail_after_views;
  p.detail_depth = o.detail_depth;
  return p;
}

// Each view's silhouette by the README recipe (`sils`) and by Otsu's threshold (`otsu_sils`).
struct Silhouettes {
  std::vector<fba::Silhouette> sils, otsu_sils;
};

// The silhouettes of every view; false (after saying which view failed) when one cannot be made.
bool extract_all(const ImageSet& set, Silhouettes& out) {
  ExtractionParams otsu;
  otsu.binarise.method = BinariseParams::Method::Otsu;
  for (std::size_t i = 0; i < set.size(); ++i) {
    auto frame = std::make_shared<const fba::Frame>(set.load_frame(i));
    const ExtractionResult r = extract_silhouette(frame);  // defaults = the README recipe
    const ExtractionResult o = extract_silhouette(frame, otsu);
    if (!r.ok() || !o.ok()) {
      std::fprintf(stderr, "%s: %s\n", set[i].name.c_str(), (r.ok() ? o : r).error.c_str());
      return false;
    }
    out.sils.push_back(*r.silhouette);
    out.otsu_sils.push_back(*o.silhouette);
  }
  return true;
}

// A fast carve's model at one depth, with the nodes its batch carve visited.
struct Model {
  int depth;
  std::shared_ptr<const fba::Octree> octree;
  std::size_t batch_visited;
};

// One row of the batch table: the reference and the fast carver (1 thread and `threads`) at
// `depth`, `repeat` times each. Adds the leaf mismatches to `mismatches`.
Model batch_row(const Options& o, const std::vector<fba::Silhouette>& sils, const Eigen::AlignedBox3d& box, int depth,
                std::size_t& mismatches) {
  CarverParams p = carver_params(o, depth);
  std::vector<double> tr, t1, tn, cr, c1, cn;
  fba::Octree ref;
  CarveStats rs;
  std::shared_ptr<const fba::Octree> fast;
  CarveStats fs;
  for (int r = 0; r < o.repeat; ++r) {
    double t0 = now(), c0 = cpu_now();
    ref = reference_carve(sils, box, p, {}, &rs);
    tr.push_back(now() - t0);
    cr.push_back(cpu_now() - c0);
    for (int n : {1, o.threads}) {
      p.threads = n;
      t0 = now();
      c0 = cpu_now();
      OctreeCarver carver(p);
      carver.set_bounds(box);
      carver.add_views(sils);
      fast = carver.snapshot();
      (n == 1 ? t1 : tn).push_back(now() - t0);
      (n == 1 ? c1 : cn).push_back(cpu_now() - c0);
      fs = carver.stats();
    }
  }
  const std::size_t mism = count_leaf_mismatches(ref, *fast) + count_leaf_mismatches(*fast, ref);
  mismatches += mism;
  std::size_t leaves = 0;
  fast->for_each_leaf([&](const fba::OctreeCell&) { ++leaves; });
  std::printf("%5d  %12.1f  %10.1f  %8.1f  %12.1f  %8.1f  %12.1f  %7.2fx  %7.2fx  %9zu  %12zu  %10zu  %11zu  %8.1f  %6zu  %10zu\n",
              depth, 1e3 * median(tr), 1e3 * median(cr), 1e3 * median(t1), 1e3 * median(c1), 1e3 * median(tn),
              1e3 * median(cn), median(tr) / median(t1), median(tr) / median(tn),
              rs.nodes_visited, fs.nodes_visited, leaves, fast->node_count, fast->bytes() / 1048576.0,
              fast->bytes() / fast->node_count, mism);
  return {depth, fast, fs.nodes_visited};
}

// Incremental: the views one by one (threads as given), once without publishing and once with a
// snapshot after every view (as the task does); the difference in carving time is what publishing
// costs (the blocks the next update must copy), plus snapshot() itself. Adds the mismatches
// against the batch model to `mismatches`.
void incremental(const Options& o, const std::vector<fba::Silhouette>& sils, const Eigen::AlignedBox3d& box,
                 const Model& model, std::size_t& mismatches) {
  CarverParams p = carver_params(o, model.depth);
  p.threads = o.threads;
  std::printf("\nincremental, depth %d: per view\nview  visited  carve_ms  carve_ms_publishing  snapshot_ms  "
              "blocks_copied  model_MB  storage_MB\n", p.max_depth);
  OctreeCarver quiet(p), published(p);
  quiet.set_bounds(box);
  published.set_bounds(box);
  std::shared_ptr<const fba::Octree> last;
  for (const auto& s : sils) {
    quiet.add_view(s);
    published.add_view(s);
    last = published.snapshot();
  }
  const auto q = quiet.stats(), pb = published.stats();
  double quiet_total = 0, published_total = 0, snapshot_total = 0;
  for (std::size_t v = 1; v < q.updates.size(); ++v) {  // updates[0] is set_bounds
    const ViewStats& a = q.updates[v];
    const ViewStats& b = pb.updates[v];
    quiet_total += a.carve_seconds, published_total += b.carve_seconds, snapshot_total += b.snapshot_seconds;
    std::printf("%4zu  %7zu  %8.1f  %19.1f  %11.3f  %13zu  %8.1f  %10.1f\n", v, a.nodes_visited, 1e3 * a.carve_seconds,
                1e3 * b.carve_seconds, 1e3 * b.snapshot_seconds, b.blocks_copied, b.model_bytes / 1048576.0,
                b.storage_bytes / 1048576.0);
  }
  const double cost = (published_total - quiet_total + snapshot_total) / quiet_total;
  const std::size_t inc_mism = count_leaf_mismatches(*last, *model.octree) + count_leaf_mismatches(*model.octree, *last);
  mismatches += inc_mism;
  std::printf("depth %d: incremental visits %zu nodes, batch %zu (%.2fx; target <= 2x); publishing after every "
              "view adds %.1f%% to the carving time (%.0f ms against %.0f ms; target < 10%%); incremental vs batch "
              "mismatches %zu\n",
              p.max_depth, q.nodes_visited, model.batch_visited, double(q.nodes_visited) / double(model.batch_visited),
              100 * cost, 1e3 * (published_total + snapshot_total), 1e3 * quiet_total, inc_mism);
}

// The models re-projected onto each view against `masks`; returns the mean and min per model.
std::pair<std::vector<double>, std::vector<double>> iou_table(const char* title, const ImageSet& set,
                                                              const std::vector<Model>& models,
                                                              const std::vector<fba::Silhouette>& masks) {
  std::printf("\nre-projection IoU of the carved model on each %s\nview          ", title);
  for (const auto& m : models) std::printf("  depth %d", m.depth);
  std::printf("\n");
  std::vector<double> sum(models.size(), 0), lo(models.size(), 1);
  for (std::size_t v = 0; v < masks.size(); ++v) {
    std::printf("%-14s", set[v].name.c_str());
    for (std::size_t m = 0; m < models.size(); ++m) {
      const double iou = mask_iou(reproject_mask(*models[m].octree, masks[v].frame->camera), masks[v].mask);
      sum[m] += iou, lo[m] = std::min(lo[m], iou);
      std::printf("  %7.4f", iou);
    }
    std::printf("\n");
  }
  for (auto& x : sum) x /= static_cast<double>(masks.size());
  std::printf("%-14s", "mean");
  for (double x : sum) std::printf("  %7.4f", x);
  std::printf("\n%-14s", "min");
  for (double x : lo) std::printf("  %7.4f", x);
  std::printf("\n");
  return std::make_pair(sum, lo);
}

// The whole benchmark on loaded data; the exit status.
int run(const Options& o, const ImageSet& set, const Silhouettes& s) {
  // The providers' tight bounding box of the dino.
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.061897, -0.018874, -0.057845),
                                Eigen::Vector3d(0.010897, 0.068227, 0.015495));
  const Eigen::AlignedBox3d est = OctreeCarver::estimate_bounds(s.sils);
  std::printf("dino: %zu views; bounds from the README; estimate_bounds gives (%.4f %.4f %.4f)-(%.4f %.4f %.4f)\n",
              s.sils.size(), est.min().x(), est.min().y(), est.min().z(), est.max().x(), est.max().y(), est.max().z());
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  std::printf("median of %d runs; fast carver with 1 thread and with %d (0 = all %u cores); silhouette tolerance %.4f px\n\n",
              o.repeat, o.threads, cores, o.tolerance);
  std::printf("wall and CPU (all threads) milliseconds, medians\n");
  std::printf("depth  reference_ms  ref_cpu_ms  fast1_ms  fast1_cpu_ms  fastN_ms  fastN_cpu_ms  speedup1  speedupN  ref_nodes  "
              "fast_visited  all_leaves  model_nodes  model_MB  B/node  mismatches\n");
  std::size_t total_mismatches = 0;
  std::vector<Model> models;
  for (int depth : o.depths) models.push_back(batch_row(o, s.sils, box, depth, total_mismatches));
  for (const Model& m : models) incremental(o, s.sils, box, m, total_mismatches);

  const auto [mean, lo] = iou_table("silhouette it was carved from (self-consistency)", set, models, s.sils);
  for (std::size_t m = 0; m < models.size(); ++m)
    std::printf("depth %d: IoU target (mean >= 0.98, min >= 0.95) %s\n", models[m].depth,
                mean[m] >= 0.98 && lo[m] >= 0.95 ? "met" : "NOT met");
  const auto [otsu_mean, otsu_lo] =
      iou_table("Otsu silhouette (made another way; the carve never saw them)", set, models, s.otsu_sils);
  for (std::size_t m = 0; m < models.size(); ++m)
    std::printf("depth %d: against Otsu silhouettes mean %.4f, min %.4f\n", models[m].depth, otsu_mean[m], otsu_lo[m]);
  std::printf("\nleaf classification mismatches, reference vs fast: %zu\n", total_mismatches);
  return total_mismatches == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (const auto status = parse_options(argc, argv, options)) return *status;
  const std::string dir = options.data + "/middlebury-dino";
  try {
    const ImageSet set = ImageSet::load_middlebury(dir + "/dinoSR_par.txt", dir + "/dinoSR_good_silhouette_images.txt");
    Silhouettes silhouettes;
    if (!extract_all(set, silhouettes)) return 2;
    return run(options, set, silhouettes);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
}
