// The view of an octree model (libs/types/src/model_view.cpp) on the carved dino and on models
// built by hand, against docs/live-view.md: flat arrays of centre and edge, as many occupied boxes
// as the model has occupied leaves, the refined and uncarved ones marked as the model says; a model
// too big to send whole shown coarser, and saying so.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <memory>
#include <set>
#include <vector>

#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/image_set.hpp"
#include "fba/vision/octree_carver.hpp"
#include "support/data_sets.hpp"
#include "view_checks.hpp"

using fba::test::json;
using fba::test::numbers;
using fba::test::view_of;

namespace {

const Eigen::AlignedBox3d kDinoBox(Eigen::Vector3d(-0.061897, -0.018874, -0.057845), Eigen::Vector3d(0.010897, 0.068227, 0.015495));

// The dino carved from its 16 views; generic detail everywhere (occupancy threshold 0), or with
// `regions` only where a grasp criterion asks (threshold 0.7, as the carver's tests do).
std::shared_ptr<const fba::Octree> carved_dino(int depth, const fba::RegionsOfInterest& regions = {}) {
  const auto set = fba::vision::ImageSet::load(fba::test::kDinoPar);
  fba::vision::CarverParams p;
  p.max_depth = depth;
  if (!regions.boxes.empty()) p.occupancy_threshold = 0.7;
  fba::vision::OctreeCarver carver(p);
  carver.set_bounds(kDinoBox);
  carver.set_regions_of_interest(regions);
  for (std::size_t i = 0; i < set.size(); ++i) {
    const auto r = fba::vision::extract_silhouette(std::make_shared<const fba::Frame>(set.load_frame(i)));
    if (!r.ok()) throw std::runtime_error(r.error);
    carver.add_view(*r.silhouette);
  }
  return carver.snapshot();
}

json view_of_model(const std::shared_ptr<const fba::Octree>& m) { return view_of(fba::Packet::make(m)); }

std::size_t occupied_leaves(const fba::Octree& m) {
  std::size_t n = 0;
  m.for_each_occupied_leaf([&](const fba::OctreeCell&) { ++n; });
  return n;
}

// Every box of every kind: inside the root box, an edge of the model's lattice, within `bounds`.
void expect_boxes_in_the_model(const json& v, const fba::Octree& m) {
  const double root_edge = m.bounds.sizes().x();
  const Eigen::AlignedBox3d bounds(Eigen::Vector3d(v["bounds"][0], v["bounds"][1], v["bounds"][2]),
                                   Eigen::Vector3d(v["bounds"][3], v["bounds"][4], v["bounds"][5]));
  for (const char* kind : {"occupied", "uncarved", "refine"}) {
    const json& a = v[kind];
    ASSERT_TRUE(numbers(a, -1)) << kind;
    ASSERT_EQ(a.size() % 4, 0u) << kind;
    for (std::size_t i = 0; i < a.size(); i += 4) {
      const Eigen::Vector3d c(a[i], a[i + 1], a[i + 2]);
      const double edge = a[i + 3];
      const double lattice_edge = root_edge / std::exp2(std::round(std::log2(root_edge / edge)));
      ASSERT_NEAR(edge, lattice_edge, 1e-5) << kind << " box " << i / 4;
      const Eigen::AlignedBox3d box(c.array() - edge / 2 + 2e-5, c.array() + edge / 2 - 2e-5);
      ASSERT_TRUE(m.bounds.contains(box)) << kind << " box " << i / 4;
      ASSERT_TRUE(bounds.contains(box)) << kind << " box " << i / 4;
    }
  }
}

std::size_t boxes(const json& v, const char* kind) { return v[kind].size() / 4; }

// The boxes of `kind` that are not among the occupied ones (centre and edge alike).
std::size_t outside_the_occupied(const json& v, const char* kind) {
  const auto box = [&](const char* k, std::size_t i) {
    return std::vector<double>{v[k][i].get<double>(), v[k][i + 1].get<double>(), v[k][i + 2].get<double>(), v[k][i + 3].get<double>()};
  };
  std::set<std::vector<double>> occupied;
  for (std::size_t i = 0; i < v["occupied"].size(); i += 4) occupied.insert(box("occupied", i));
  std::size_t n = 0;
  for (std::size_t i = 0; i < v[kind].size(); i += 4) n += !occupied.count(box(kind, i));
  return n;
}

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * double(t.tv_sec) + 1e-6 * double(t.tv_nsec);
}

}  // namespace

TEST(ModelView, HoldsEveryOccupiedLeafOfTheCarvedDinoOnce) {
  const auto model = carved_dino(6);
  const json v = view_of_model(model);
  ASSERT_EQ(v["kind"], "model");
  EXPECT_EQ(v["truncated"], false);
  EXPECT_EQ(v["views"], model->views);
  EXPECT_EQ(boxes(v, "occupied"), occupied_leaves(*model));
  EXPECT_EQ(v["counts"]["occupied"], boxes(v, "occupied"));
  EXPECT_EQ(v["counts"]["uncarved"], boxes(v, "uncarved"));
  EXPECT_EQ(v["counts"]["refine"], boxes(v, "refine"));
  EXPECT_GT(boxes(v, "occupied"), 1000u);
  EXPECT_EQ(boxes(v, "refine"), 0u) << "no grasp criterion asked for detail";
  EXPECT_EQ(boxes(v, "uncarved"), 0u) << "occupancy threshold 0: every leaf on the outline is split to the model's depth";
  ASSERT_TRUE(numbers(v["bounds"], 6));
  ASSERT_TRUE(numbers(v["root"], 6));
  expect_boxes_in_the_model(v, *model);
}

TEST(ModelView, MarksTheLeavesRefinedWhereSynthesisAsked) {
  fba::RegionsOfInterest regions;
  regions.boxes.emplace_back(Eigen::Vector3d(-0.03, 0.0, -0.03), Eigen::Vector3d(0.0, 0.03, 0.0));
  const auto model = carved_dino(6, regions);
  const json v = view_of_model(model);
  EXPECT_EQ(boxes(v, "occupied"), occupied_leaves(*model));
  ASSERT_GT(boxes(v, "refine"), 0u);
  EXPECT_GT(boxes(v, "uncarved"), 0u) << "threshold 0.7 leaves some of the outline coarse";
  const json& refine = v["refine"];
  for (std::size_t i = 0; i < refine.size(); i += 4) {
    const Eigen::Vector3d c(refine[i], refine[i + 1], refine[i + 2]);
    const double h = refine[i + 3].get<double>() / 2;
    // A refined leaf's parent met the region: the leaf is within a parent's edge of it.
    const Eigen::AlignedBox3d near(regions.boxes[0].min().array() - 4 * h, regions.boxes[0].max().array() + 4 * h);
    ASSERT_TRUE(near.contains(c)) << "refine box " << i / 4 << " far from the region: " << c.transpose();
  }
  expect_boxes_in_the_model(v, *model);
}

// What the page marks as refined is model: every refine box is an occupied one, as every uncarved
// box is, on a carved model; and it follows the regions of the moment: once synthesis asks for
// another region, no leaf is marked refined where only the first one was.
TEST(ModelView, RefinedLeavesAreOccupiedOnesWhereTheRegionsOfTheMomentAsked) {
  const auto set = fba::vision::ImageSet::load(fba::test::kDinoPar);
  fba::vision::CarverParams p;
  p.max_depth = 6;
  p.occupancy_threshold = 0.7;
  fba::vision::OctreeCarver carver(p);
  carver.set_bounds(kDinoBox);
  fba::RegionsOfInterest first, second;
  first.boxes.emplace_back(Eigen::Vector3d(-0.03, 0.0, -0.03), Eigen::Vector3d(0.0, 0.03, 0.0));
  second.boxes.emplace_back(Eigen::Vector3d(-0.06, 0.03, -0.03), Eigen::Vector3d(-0.035, 0.068, 0.0));
  carver.set_regions_of_interest(first);
  for (std::size_t i = 0; i < set.size(); ++i) {
    const auto r = fba::vision::extract_silhouette(std::make_shared<const fba::Frame>(set.load_frame(i)));
    ASSERT_TRUE(r.ok()) << r.error;
    carver.add_view(*r.silhouette);
  }
  const json before = view_of_model(carver.snapshot());
  carver.set_regions_of_interest(second);
  const json after = view_of_model(carver.snapshot());
  for (const json* v : {&before, &after}) {
    ASSERT_GT(boxes(*v, "refine"), 0u);
    EXPECT_EQ(outside_the_occupied(*v, "refine"), 0u);
    EXPECT_EQ(outside_the_occupied(*v, "uncarved"), 0u);
  }
  // A refined leaf's parent met a region: the leaf lies within a parent's edge of it.
  const auto near = [](const json& v, std::size_t i, const Eigen::AlignedBox3d& region) {
    const double h = v["refine"][i + 3].get<double>() / 2;
    return Eigen::AlignedBox3d(region.min().array() - 4 * h, region.max().array() + 4 * h)
        .contains(Eigen::Vector3d(v["refine"][i], v["refine"][i + 1], v["refine"][i + 2]));
  };
  for (std::size_t i = 0; i < after["refine"].size(); i += 4)
    ASSERT_TRUE(near(after, i, second.boxes[0])) << "refine box " << i / 4 << " left from the first region";
}

TEST(ModelView, TellsRefinedUncarvedAndCarvedLeavesApart) {
  auto m = std::make_shared<fba::Octree>();
  m->bounds = Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.16));
  m->max_depth = 2;
  m->views = 3;
  fba::OctreeNode* kids = m->split(m->root, fba::NodeState::Partial);
  kids[0].set_state(fba::NodeState::Empty);                 // carved away
  kids[1].set_state(fba::NodeState::Full);                  // carved: inside every silhouette
  kids[2].set_state(fba::NodeState::Partial);               // uncarved: on the outline, coarser than depth 2
  kids[3].set_interest(true);                               // split for a grasp criterion:
  fba::OctreeNode* refined = m->split(kids[3], fba::NodeState::Partial);  // its 8 leaves are refine
  refined[5].set_state(fba::NodeState::Empty);
  fba::OctreeNode* plain = m->split(kids[4], fba::NodeState::Full);       // split generically: carved
  plain[0].set_state(fba::NodeState::Partial);                            // at the model's depth: carved
  for (int i = 5; i < 8; ++i) kids[i].set_state(fba::NodeState::Empty);

  const json v = view_of_model(m);
  EXPECT_EQ(boxes(v, "occupied"), 1u + 1u + 7u + 8u) << "every occupied leaf";
  EXPECT_EQ(boxes(v, "uncarved"), 1u);
  EXPECT_EQ(boxes(v, "refine"), 7u);
  EXPECT_EQ(v["uncarved"], json::array({0.04, 0.12, 0.04, 0.08})) << "child 2: x low, y high";
  EXPECT_EQ(v["bounds"], json::array({0, 0, 0, 0.16, 0.16, 0.16}));
  EXPECT_EQ(v["counts"], json({{"occupied", 17}, {"uncarved", 1}, {"refine", 7}}));
  expect_boxes_in_the_model(v, *m);

  m->views = 0;  // before the first view nothing is carved
  const json before = view_of_model(m);
  EXPECT_EQ(boxes(before, "uncarved"), 17u);
  EXPECT_EQ(boxes(before, "occupied") + boxes(before, "refine"), 0u);
}

TEST(ModelView, ShowsATooBigModelCoarserAndSaysSo) {
  // Every node split down to depth 6: 262,144 Full leaves, more than a view holds.
  auto m = std::make_shared<fba::Octree>();
  m->bounds = Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-0.32), Eigen::Vector3d::Constant(0.32));
  m->max_depth = 6;
  m->views = 1;
  std::vector<fba::OctreeNode*> level{&m->root};
  for (int d = 0; d < 6; ++d) {
    std::vector<fba::OctreeNode*> next;
    for (fba::OctreeNode* n : level) {
      fba::OctreeNode* k = m->split(*n, fba::NodeState::Full);
      for (int i = 0; i < 8; ++i) next.push_back(k + i);
    }
    level = std::move(next);
  }
  ASSERT_EQ(occupied_leaves(*m), 262144u);
  const json v = view_of_model(m);
  EXPECT_EQ(v["truncated"], true);
  EXPECT_EQ(v["shown_depth"], 5);
  EXPECT_EQ(boxes(v, "occupied"), 32768u);  // 8^5: the deepest depth within the view's limit
  EXPECT_EQ(v["counts"]["occupied"], 262144u);
  expect_boxes_in_the_model(v, *m);
}

TEST(ModelView, ShowsNothingBeforeTheModelHasBounds) {
  auto m = std::make_shared<fba::Octree>();
  m->node_count = 0;
  EXPECT_TRUE(view_of_model(m).is_null());
}

// The view's cost on the depth-6 dino, printed (docs/results.md): a live view updates it 10 times a
// second, so it must stay far below 100 ms. A figure, not a bound: the machine may be loaded.
TEST(ModelView, CostOfTheDepth6DinoModel) {
  const auto model = carved_dino(6);
  const fba::ViewFunction f = fba::find_view(fba::type_of<fba::Octree>());
  ASSERT_NE(f, nullptr);
  const fba::Packet p = fba::Packet::make(model);
  std::vector<double> wall_ms, cpu_ms;
  std::size_t bytes = 0;
  for (int i = 0; i < 7; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = thread_cpu_ms();
    bytes = f(p).size();
    cpu_ms.push_back(thread_cpu_ms() - c0);
    wall_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(wall_ms.begin(), wall_ms.end());
  std::sort(cpu_ms.begin(), cpu_ms.end());
  std::printf("model view of the depth-6 dino: %zu occupied leaves, %zu bytes, median %.2f ms wall, %.2f ms CPU\n",
              occupied_leaves(*model), bytes, wall_ms[wall_ms.size() / 2], cpu_ms[cpu_ms.size() / 2]);
}
