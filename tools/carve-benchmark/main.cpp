// Reference vs fast octree carving on the Middlebury dino (the 15 good views, silhouettes by the
// providers' recipe), at depths 6, 7 and 8: times, speed-up, nodes visited, leaf classification
// mismatches (exit code 1 if any), and the re-projection IoU of the model on every silhouette.
//
//   fba-carve-benchmark [shared-data-dir] [--repeat N] [--threads N] [--depths 6,7,8] [--tolerance PX]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/image_set.hpp"
#include "fba/vision/octree_carver.hpp"
#include "fba/vision/reference_carve.hpp"

using namespace fba::vision;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = FBA_SHARED_DATA_DIR;
  int repeat = 5, threads = 0;
  std::vector<int> depths{6, 7, 8};
  double tolerance = CarverParams{}.silhouette_tolerance;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeat" && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
    else if (a == "--threads" && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (a == "--tolerance" && i + 1 < argc) tolerance = std::atof(argv[++i]);
    else if (a == "--depths" && i + 1 < argc) {
      depths.clear();
      for (const char* p = argv[++i]; *p;) {
        char* end = nullptr;
        depths.push_back(static_cast<int>(std::strtol(p, &end, 10)));
        p = *end ? end + 1 : end;
      }
    }
    else if (a.rfind("-", 0) == 0) {
      const bool help = a == "--help" || a == "-h";
      std::fprintf(help ? stdout : stderr, "usage: fba-carve-benchmark [shared-data-dir] [--repeat N] [--threads N] [--depths 6,7,8] [--tolerance PX]\n");
      if (!help) std::fprintf(stderr, "unknown or incomplete option '%s'\n", a.c_str());
      return help ? 0 : 2;
    } else {
      data = a;
    }
  }
  const std::string dir = data + "/middlebury-dino";
  try {
    const ImageSet set = ImageSet::load_middlebury(dir + "/dinoSR_par.txt", dir + "/dinoSR_good_silhouette_images.txt");
    std::vector<fba::Silhouette> sils;
    for (std::size_t i = 0; i < set.size(); ++i) {
      auto frame = std::make_shared<const fba::Frame>(set.load_frame(i));
      const ExtractionResult r = extract_silhouette(frame);  // defaults = the README recipe
      if (!r.ok()) {
        std::fprintf(stderr, "%s: %s\n", set[i].name.c_str(), r.error.c_str());
        return 2;
      }
      sils.push_back(*r.silhouette);
    }
    // The providers' tight bounding box of the dino.
    const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.061897, -0.018874, -0.057845),
                                  Eigen::Vector3d(0.010897, 0.068227, 0.015495));
    const Eigen::AlignedBox3d est = OctreeCarver::estimate_bounds(sils);
    std::printf("dino: %zu views; bounds from the README; estimate_bounds gives (%.4f %.4f %.4f)-(%.4f %.4f %.4f)\n",
                sils.size(), est.min().x(), est.min().y(), est.min().z(), est.max().x(), est.max().y(), est.max().z());
    std::printf("median of %d runs, fast carver threads=%d (0 = all cores), silhouette tolerance %.4f px\n\n", repeat,
                threads, tolerance);
    std::printf("depth  reference_ms  fast_ms  speedup  ref_nodes  fast_nodes_visited  all_leaves  mismatches\n");

    std::size_t total_mismatches = 0;
    std::vector<std::pair<int, std::shared_ptr<const fba::Octree>>> models;
    for (int depth : depths) {
      CarverParams p;
      p.max_depth = depth;
      p.threads = threads;
      p.silhouette_tolerance = tolerance;
      std::vector<double> tr, tf;
      fba::Octree ref;
      CarveStats rs;
      std::shared_ptr<const fba::Octree> fast;
      CarveStats fs;
      for (int r = 0; r < repeat; ++r) {
        double t0 = now();
        ref = reference_carve(sils, box, p, {}, &rs);
        tr.push_back(now() - t0);
        t0 = now();
        OctreeCarver carver(p);
        carver.set_bounds(box);
        carver.add_views(sils);
        fast = carver.snapshot();
        tf.push_back(now() - t0);
        fs = carver.stats();
      }
      const std::size_t mism = count_leaf_mismatches(ref, *fast) + count_leaf_mismatches(*fast, ref);
      total_mismatches += mism;
      const std::size_t leaves = std::count_if(fast->nodes.begin(), fast->nodes.end(), [](const fba::OctreeNode& n) { return n.is_leaf(); });
      std::printf("%5d  %12.1f  %7.1f  %6.2fx  %9zu  %18zu  %10zu  %10zu\n", depth, 1e3 * median(tr), 1e3 * median(tf),
                  median(tr) / median(tf), rs.nodes_visited, fs.nodes_visited, leaves, mism);
      models.emplace_back(depth, fast);
    }

    std::printf("\nre-projection IoU of the carved model on each silhouette\nview          ");
    for (const auto& m : models) std::printf("  depth %d", m.first);
    std::printf("\n");
    std::vector<double> sum(models.size(), 0), lo(models.size(), 1);
    for (std::size_t v = 0; v < sils.size(); ++v) {
      std::printf("%-14s", set[v].name.c_str());
      for (std::size_t m = 0; m < models.size(); ++m) {
        const double iou = mask_iou(reproject_mask(*models[m].second, sils[v].frame->camera), sils[v].mask);
        sum[m] += iou, lo[m] = std::min(lo[m], iou);
        std::printf("  %7.4f", iou);
      }
      std::printf("\n");
    }
    std::printf("%-14s", "mean");
    for (std::size_t m = 0; m < models.size(); ++m) std::printf("  %7.4f", sum[m] / sils.size());
    std::printf("\n%-14s", "min");
    for (std::size_t m = 0; m < models.size(); ++m) std::printf("  %7.4f", lo[m]);
    std::printf("\n");
    for (std::size_t m = 0; m < models.size(); ++m)
      std::printf("depth %d: IoU target (mean >= 0.98, min >= 0.95) %s\n", models[m].first,
                  sum[m] / sils.size() >= 0.98 && lo[m] >= 0.95 ? "met" : "NOT met");
    std::printf("\nleaf classification mismatches, reference vs fast: %zu\n", total_mismatches);
    return total_mismatches == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
}
