#include "fba/vision/octree_carver.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <opencv2/core/optim.hpp>
#include <opencv2/imgproc.hpp>

#include "carve_common.hpp"
#include "fba/geometry/mesh_io.hpp"

namespace fba::vision {

using namespace detail;

namespace detail {

ViewData make_view(const fba::Silhouette& s, const CarverParams& p) {
  const double curvature_threshold = p.curvature_threshold;
  if (!s.frame) throw std::invalid_argument("carving: the silhouette has no frame (camera)");
  if (s.mask.empty() || s.mask.type() != CV_8UC1)
    throw std::invalid_argument("carving: expected an 8-bit single-channel silhouette mask");
  const fba::CameraModel& cam = s.frame->camera;
  if (cam.width > 0 && (cam.width != s.mask.cols || cam.height != s.mask.rows))
    throw std::invalid_argument("carving: mask " + std::to_string(s.mask.cols) + "x" + std::to_string(s.mask.rows) +
                                " does not match the camera's " + std::to_string(cam.width) + "x" +
                                std::to_string(cam.height));
  if (!cam.distortion.empty() && cv::countNonZero(cam.distortion != 0) > 0)
    throw std::invalid_argument("carving: the camera has lens distortion; undistort the silhouette first "
                                "(extract_silhouette does)");
  ViewData v;
  v.P = cam.projection();
  v.width = s.mask.cols;
  v.height = s.mask.rows;
  v.mask = s.mask;
  v.outside_empty = p.carve_outside_view && !s.touches_border;
  cv::Mat ones = s.mask > 0;
  ones /= 255;  // integral of 0/1: pixel counts
  cv::integral(ones, v.integral, CV_32S);
  if (std::isfinite(curvature_threshold)) {
    // Every boundary of the object is outline that fingers may hold: the outer contour and each
    // hole's (the rim of a handle's hole). Their curvature has one sign convention (convex > 0,
    // a hole's normal pointing into the hole), so a round hole's rim is concave and graspable.
    cv::Mat graspable = cv::Mat::zeros(s.mask.size(), CV_8UC1);
    auto mark = [&](const fba::Outline& o) {
      for (std::size_t i = 0; i < o.contour.size() && i < o.curvature.size(); ++i) {
        const cv::Point q = o.contour[i];
        if (o.curvature[i] < curvature_threshold && q.x >= 0 && q.y >= 0 && q.x < v.width && q.y < v.height)
          graspable.at<std::uint8_t>(q) = 1;
      }
    };
    mark(s);
    for (const auto& h : s.holes) mark(h);
    cv::integral(graspable, v.graspable_integral, CV_32S);
  }
  return v;
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
// The fast carver works on the published representation itself: 8-byte nodes in blocks of an
// arena shared with the snapshots. A block that a snapshot may reach (index below `frozen`) is
// never written: the update copies it and relinks its parent (whose own block was made writable
// the same way on the way down), so a snapshot is O(1) and an update copies only what it visits.
//
// Compared with the reference it saves work in ways that leave every decision the same:
//  * a node whose ancestor is wholly inside a view is not tested against it (a child's corners
//    are inside the parent's cube, so its rectangle is inside the parent's);
//  * a new view that sees a node wholly inside cannot change anything below it (no carving, no
//    lower share, no contour point), so the node's subtree is not visited at all;
//  * the view that gave the parent its lowest occupancy is tested first, and testing stops at the
//    first view that carves the node; the leaf test of an existing leaf needs only the new views.

namespace {

// The producer flags of a node (fba::OctreeNode::flag).
constexpr int kCurvatureHit = 0;  // a view where it is not wholly inside has a graspable contour point in its rectangle
constexpr int kAbove = 1;         // in a view where it lies on the outline, its share (hull_share) is above occupancy_threshold

constexpr float kBelowOne = 0.99999994f;  // the largest float below 1: a partial node's occupancy

struct Task {
  fba::OctreeNode* node;
  NodeKey key;
  int from_view;
  int hint;
  std::uint64_t full_mask;
};

std::uint64_t low_bits(int n) { return n >= 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << n) - 1; }

}  // namespace

void run_on_threads(unsigned threads, std::size_t n, const std::function<void(std::size_t)>& f) {
  const unsigned t = static_cast<unsigned>(std::max<std::size_t>(1, std::min<std::size_t>(threads, n)));
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    try {
      for (std::size_t i; (i = next.fetch_add(1)) < n;) f(i);
    } catch (...) {
      std::lock_guard lock(error_mutex);
      if (!error) error = std::current_exception();
      next = n;  // the others stop at their next task
    }
  };
  std::vector<std::thread> pool;
  try {
    for (unsigned i = 1; i < t; ++i) pool.emplace_back(work);
  } catch (...) {  // could not start a thread: the ones started and this one do the work
  }
  work();
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
}

std::size_t worst_case_bytes(int max_depth) {
  // Every node of levels 0..max_depth, and as much again for the blocks that older versions
  // still hold before the storage is compacted.
  double nodes = 0;
  for (int d = 0; d <= max_depth; ++d) nodes += std::pow(8.0, d);
  const double bytes = 2 * nodes * sizeof(fba::OctreeNode);
  return bytes >= 1.8e19 ? std::numeric_limits<std::size_t>::max() : static_cast<std::size_t>(bytes);
}

struct OctreeCarver::Impl {
  CarverParams params;
  std::vector<ViewData> views;
  fba::RegionsOfInterest roi;
  bool has_bounds = false;
  Eigen::AlignedBox3d cube;
  Lattice lattice;
  fba::OctreeNode root;
  std::shared_ptr<fba::OctreeArena> arena;
  std::uint32_t frozen = 0;          // blocks below this index may be held by a snapshot
  std::atomic<std::int64_t> live_blocks{0};  // blocks reachable from the root
  CarveStats stats;
  std::shared_ptr<const fba::Octree> cached;

  struct Context {
    std::size_t visited = 0, refined = 0, copied = 0;
    std::vector<Task>* defer = nullptr;  // when set, nodes at defer_depth are queued, not updated
    int defer_depth = 0;
  };

  static void fresh(fba::OctreeNode& n) {  // a node no view has tested: lowest occupancy 1 so far
    n = fba::OctreeNode{};
    n.set_occupancy(1);
  }

  std::int64_t blocks_under(const fba::OctreeNode& n) const {
    if (n.is_leaf()) return 0;
    std::int64_t s = 1;
    for (const auto& c : (*arena)[n.children()].child) s += blocks_under(c);
    return s;
  }

  void drop_children(fba::OctreeNode& n) {
    if (n.is_leaf()) return;
    live_blocks -= blocks_under(n);
    n.clear_children();
  }

  // Tests n against views [from_view, n_views) (first `hint`; views in full_mask are known to see
  // it wholly inside), then makes Algorithm 2's decision and recurses. Existing children are
  // updated with the same new views; new children with all. n must be writable.
  void update(fba::OctreeNode& n, const NodeKey& k, int from_view, int hint, std::uint64_t full_mask, Context& ctx) {
    if (n.state() == fba::NodeState::Empty) return;  // carved stays carved
    if (ctx.defer && k.depth == ctx.defer_depth) {
      ctx.defer->push_back({&n, k, from_view, hint, full_mask});
      return;
    }
    ++ctx.visited;
    const int nv = static_cast<int>(views.size());
    // A node wholly inside every view so far (lowest occupancy 1) is wholly inside the old views.
    std::uint64_t mask = full_mask | (n.occupancy() >= 1 ? low_bits(from_view) : 0);
    float min_occ = n.occupancy();
    // The generic criterion: some view where the node lies on the outline has its share above
    // the threshold. The hull's share costs a scan of its rows, so it is computed only while it
    // can decide (a Partial node's share is in (0, 1): threshold 0 or 1 decides without it).
    const double t = params.occupancy_threshold;
    bool above = n.flag(kAbove);
    bool curvature_hit = n.flag(kCurvatureHit), all_full = true;
    int argmin = hint;
    double lowest = 2;
    Rect rects[64];  // rectangles computed here, reused by the leaf test
    std::uint64_t have_rect = 0;
    auto carves = [&](int v) {
      if (v < 64 && ((mask >> v) & 1u)) return false;  // wholly inside: not on the outline
      const ViewData& view = views[static_cast<std::size_t>(v)];
      double cu[8], cw[8];
      Rect r;
      if (project_corners_uv(view, lattice, k, cu, cw)) r = rect_of(cu, cw, params.silhouette_tolerance);
      else r.behind = true;
      if (v < 64) rects[v] = r, have_rect |= std::uint64_t(1) << v;
      const Occupancy o = occupancy(view, r);
      if (o.empty()) return true;
      const double val = o.value();
      if (!above && !o.full()) above = t == 0 || (t < 1 && hull_share(view, cu, cw, o) > t);
      if (o.full()) {
        if (v < 64) mask |= std::uint64_t(1) << v;
        return false;
      }
      all_full = false;
      min_occ = std::min(min_occ, std::min(static_cast<float>(val), kBelowOne));
      if (val < lowest) lowest = val, argmin = v;
      curvature_hit = curvature_hit || graspable_contour_in(view, r);
      return false;
    };
    bool carved = hint >= from_view && hint < nv && carves(hint);
    for (int v = from_view; v < nv && !carved; ++v)
      if (v != hint) carved = carves(v);
    if (carved) {
      set_empty(n);
      return;
    }
    n.set_occupancy(min_occ);
    n.set_flag(kAbove, above);
    n.set_flag(kCurvatureHit, curvature_hit);
    // Nothing below can change (see the top of this section), unless detail held back until now
    // is due.
    const bool detail_due = from_view < params.detail_after_views && nv >= params.detail_after_views;
    if (from_view < nv && all_full && !n.is_leaf() && !detail_due) return;

    const bool full = min_occ >= 1;
    Split split = Split::No;
    if (!full && !at_resolution_limit(params, lattice, k.depth)) {
      if (above && k.depth < params.generic_depth) split = Split::Generic;
      else if (curvature_hit || intersects_roi(roi, lattice, k)) split = Split::Grasp;
      if (nv < params.detail_after_views && k.depth >= params.detail_depth) split = Split::No;
    }
    // The leaf test: earlier views were tested when the node became a leaf at the limit, or saw
    // it wholly inside, so only the new views can carve it now.
    if (split == Split::No && wants_leaf_test(params, lattice, k.depth, min_occ))
      for (int v = from_view; v < nv; ++v) {
        if (v < 64 && ((mask >> v) & 1u)) continue;
        const ViewData& view = views[static_cast<std::size_t>(v)];
        const Rect r = v < 64 && ((have_rect >> v) & 1u) ? rects[v] : node_rect(view, lattice, k, params.silhouette_tolerance);
        double u = 0, w = 0;
        if (project_centre(view, lattice, k, u, w) && leaf_carved_by(view, r, u, w, params.silhouette_tolerance)) {
          set_empty(n);
          return;
        }
      }
    if (split == Split::No) {
      drop_children(n);  // no longer wanted (fewer regions of interest, or occupancy fell)
      n.set_state(full ? fba::NodeState::Full : fba::NodeState::Partial);
      n.set_interest(false);
      return;
    }
    n.set_state(fba::NodeState::Partial);
    n.set_interest(split == Split::Grasp);
    int child_from = from_view;
    if (n.is_leaf()) {
      const std::uint32_t b = arena->allocate();
      for (auto& c : (*arena)[b].child) fresh(c);
      n.set_children(b);
      ++live_blocks;
      child_from = 0;
      ++ctx.refined;
    } else if (n.children() < frozen) {  // held by a snapshot: write a copy
      const std::uint32_t b = arena->allocate();
      (*arena)[b] = (*arena)[n.children()];
      n.set_children(b);
      ++ctx.copied;
    }
    fba::OctreeNode* c = (*arena)[n.children()].child;
    for (int i = 0; i < 8; ++i) update(c[i], k.child(i), child_from, argmin, mask, ctx);
  }

  void set_empty(fba::OctreeNode& n) {
    drop_children(n);
    n = fba::OctreeNode{};
    n.set_state(fba::NodeState::Empty);
  }

  void parallel_for(std::size_t n, const std::function<void(std::size_t)>& f) const {
    if (params.parallel_for) return params.parallel_for(n, f);
    const unsigned threads = params.threads > 0 ? static_cast<unsigned>(params.threads) : std::thread::hardware_concurrency();
    run_on_threads(threads, n, f);
  }

  // Copies the live tree into a new arena when old blocks (dropped, or copied for a snapshot)
  // outnumber the live ones: O(live) at most once per as many blocks written, and versions still
  // read keep the old arena alive.
  void compact_if_wasteful() {
    const std::int64_t live = live_blocks.load(), total = arena->size();
    if (total - live <= live + 4096) return;
    auto fresh_arena = std::make_shared<fba::OctreeArena>(arena->max_blocks());
    std::function<void(fba::OctreeNode&)> copy = [&](fba::OctreeNode& n) {
      if (n.is_leaf()) return;
      const std::uint32_t b = fresh_arena->allocate();
      (*fresh_arena)[b] = (*arena)[n.children()];
      n.set_children(b);
      for (auto& c : (*fresh_arena)[b].child) copy(c);
    };
    copy(root);
    arena = std::move(fresh_arena);
    frozen = 0;
  }

  // Updates the whole tree with views [from_view, n_views).
  void run(int from_view) {
    ViewStats vs;
    vs.views = views.size();
    if (has_bounds) {
      const auto t0 = std::chrono::steady_clock::now();
      std::vector<Task> tasks;
      Context top;
      top.defer = &tasks;
      top.defer_depth = 3;  // up to 512 subtrees, enough to balance two to a few dozen threads
      update(root, NodeKey{}, from_view, from_view, 0, top);
      std::vector<Context> ctx(tasks.size());
      parallel_for(tasks.size(), [&](std::size_t i) {
        const Task& t = tasks[i];
        update(*t.node, t.key, t.from_view, t.hint, t.full_mask, ctx[i]);
      });
      vs.nodes_visited = top.visited, vs.nodes_refined = top.refined, vs.blocks_copied = top.copied;
      for (const auto& c : ctx) vs.nodes_visited += c.visited, vs.nodes_refined += c.refined, vs.blocks_copied += c.copied;
      compact_if_wasteful();
      vs.carve_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    vs.model_nodes = 1 + 8 * static_cast<std::size_t>(live_blocks.load());
    vs.model_bytes = vs.model_nodes * sizeof(fba::OctreeNode);
    vs.storage_bytes = std::size_t(arena->size()) * sizeof(fba::OctreeBlock);
    stats.nodes_visited += vs.nodes_visited;
    stats.nodes_refined += vs.nodes_refined;
    stats.seconds += vs.carve_seconds;
    stats.updates.push_back(vs);
    cached.reset();
  }

  std::shared_ptr<const fba::Octree> publish() {
    const auto t0 = std::chrono::steady_clock::now();
    auto t = std::make_shared<fba::Octree>();
    t->max_depth = params.max_depth;
    t->views = static_cast<int>(views.size());
    if (has_bounds) {
      t->bounds = cube;
      t->root = root;
      t->arena = arena;
      t->node_count = 1 + 8 * static_cast<std::size_t>(live_blocks.load());
      frozen = arena->size();  // from now on, the next update copies before writing
    } else {
      t->node_count = 0;
    }
    if (!stats.updates.empty())
      stats.updates.back().snapshot_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return t;
  }
};

OctreeCarver::OctreeCarver(CarverParams p) : params_(p), impl_(std::make_unique<Impl>()) {
  check_params(p);
  const std::size_t need = worst_case_bytes(p.max_depth);
  if (need > p.memory_budget)
    throw std::invalid_argument("OctreeCarver: max_depth " + std::to_string(p.max_depth) + " may need up to " +
                                std::to_string(need >> 20) + " MiB, more than the memory budget of " +
                                std::to_string(p.memory_budget >> 20) + " MiB (CarverParams::memory_budget)");
  impl_->params = p;
  impl_->arena = std::make_shared<fba::OctreeArena>(p.memory_budget / sizeof(fba::OctreeBlock));
  Impl::fresh(impl_->root);
}

OctreeCarver::~OctreeCarver() = default;

void OctreeCarver::set_bounds(const Eigen::AlignedBox3d& box) {
  const Eigen::AlignedBox3d cube = geometry::cube_around(box);
  std::lock_guard lock(mutex_);
  impl_->cube = cube;
  impl_->lattice = Lattice{cube.min(), cube.sizes().x()};
  impl_->has_bounds = true;
  Impl::fresh(impl_->root);
  impl_->arena = std::make_shared<fba::OctreeArena>(impl_->arena->max_blocks());
  impl_->frozen = 0;
  impl_->live_blocks = 0;
  impl_->run(0);
}

void OctreeCarver::add_view(const fba::Silhouette& s) {
  ViewData v = make_view(s, params_);
  std::lock_guard lock(mutex_);
  impl_->views.push_back(std::move(v));
  impl_->stats.views = impl_->views.size();
  impl_->run(static_cast<int>(impl_->views.size()) - 1);
}

void OctreeCarver::add_views(const std::vector<fba::Silhouette>& views) {
  std::vector<ViewData> prepared;
  for (const auto& s : views) prepared.push_back(make_view(s, params_));
  std::lock_guard lock(mutex_);
  const int first = static_cast<int>(impl_->views.size());
  for (auto& v : prepared) impl_->views.push_back(std::move(v));
  impl_->stats.views = impl_->views.size();
  if (!prepared.empty()) impl_->run(first);
}

void OctreeCarver::set_regions_of_interest(const fba::RegionsOfInterest& roi) {
  std::lock_guard lock(mutex_);
  impl_->roi = roi;
  impl_->run(static_cast<int>(impl_->views.size()));  // no new views: re-decide refinement only
}

std::shared_ptr<const fba::Octree> OctreeCarver::snapshot() const {
  std::lock_guard lock(mutex_);
  if (!impl_->cached) impl_->cached = impl_->publish();
  return impl_->cached;
}

CarveStats OctreeCarver::stats() const {
  std::lock_guard lock(mutex_);
  return impl_->stats;
}

Eigen::AlignedBox3d OctreeCarver::estimate_bounds(const std::vector<fba::Silhouette>& views, double margin) {
  if (views.size() < 2) throw std::invalid_argument("estimate_bounds: expected >= 2 silhouettes, found " + std::to_string(views.size()));
  // Each view's bounding rectangle gives up to 4 half-spaces a . X <= b (and one for "in front");
  // the box of their intersection comes from 6 linear programmes. solveLP wants x >= 0, so X is
  // shifted by `shift` metres and boxed to [0, 2 shift]; hitting that box means unbounded.
  constexpr double shift = 1000.0;
  std::vector<Eigen::Vector4d> rows;  // (a, b)
  auto add = [&](const Eigen::Vector4d& h) {  // h . (X, 1) >= 0
    rows.emplace_back(-h.x(), -h.y(), -h.z(), h.w());
  };
  for (const auto& s : views) {
    if (!s.frame) throw std::invalid_argument("estimate_bounds: a silhouette has no frame (camera)");
    if (s.mask.empty()) throw std::invalid_argument("estimate_bounds: a silhouette has an empty mask");
    const cv::Rect r = cv::boundingRect(s.mask);
    if (r.area() == 0) throw std::invalid_argument("estimate_bounds: a silhouette mask is all background");
    const Eigen::Matrix<double, 3, 4> P = s.frame->camera.projection();
    const Eigen::Vector4d p0 = P.row(0).transpose(), p1 = P.row(1).transpose(), p2 = P.row(2).transpose();
    add(p2);  // in front of the camera
    const int W = s.mask.cols, H = s.mask.rows;
    if (r.x > 0) add(p0 - (r.x - 0.5) * p2);
    if (r.x + r.width < W) add((r.x + r.width - 0.5) * p2 - p0);
    if (r.y > 0) add(p1 - (r.y - 0.5) * p2);
    if (r.y + r.height < H) add((r.y + r.height - 0.5) * p2 - p1);
  }
  cv::Mat A(static_cast<int>(rows.size()) + 3, 4, CV_64F);
  for (int i = 0; i < static_cast<int>(rows.size()); ++i) {
    const auto& h = rows[static_cast<std::size_t>(i)];
    // a . (Y - shift) <= b  ->  a . Y <= b + shift * sum(a)
    for (int j = 0; j < 3; ++j) A.at<double>(i, j) = h[j];
    A.at<double>(i, 3) = h.w() + shift * (h.x() + h.y() + h.z());
  }
  for (int j = 0; j < 3; ++j) {
    double* row = A.ptr<double>(static_cast<int>(rows.size()) + j);
    row[0] = row[1] = row[2] = 0;
    row[j] = 1;
    row[3] = 2 * shift;
  }
  Eigen::Vector3d lo, hi;
  for (int j = 0; j < 3; ++j) {
    for (int sign : {-1, 1}) {
      cv::Mat f = cv::Mat::zeros(1, 3, CV_64F), z;
      f.at<double>(0, j) = sign;
      const int res = cv::solveLP(f, A, z);
      if (res != cv::SOLVELP_SINGLE && res != cv::SOLVELP_MULTI)
        throw std::invalid_argument("estimate_bounds: the viewing cones have no common region (add or check views)");
      const double x = z.at<double>(j) - shift;
      if (std::abs(x) > 0.99 * shift)
        throw std::invalid_argument("estimate_bounds: the viewing cones do not bound the object (add views from other directions)");
      (sign < 0 ? lo : hi)[j] = x;
    }
  }
  const Eigen::Vector3d grow = margin * (hi - lo);
  return {lo - grow, hi + grow};
}

}  // namespace fba::vision
