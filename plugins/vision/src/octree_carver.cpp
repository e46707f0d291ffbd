#include "fba/vision/octree_carver.hpp"

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

#include <opencv2/core/optim.hpp>
#include <opencv2/imgproc.hpp>

#include "carve_common.hpp"
#include "fba/geometry/mesh_io.hpp"

namespace fba::vision {

using namespace detail;

namespace detail {

ViewData make_view(const fba::Silhouette& s, double curvature_threshold) {
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
  cv::Mat ones = s.mask > 0;
  ones /= 255;  // integral of 0/1: pixel counts
  cv::integral(ones, v.integral, CV_32S);
  if (std::isfinite(curvature_threshold) && !s.contour.empty()) {
    cv::Mat graspable = cv::Mat::zeros(s.mask.size(), CV_8UC1);
    for (std::size_t i = 0; i < s.contour.size() && i < s.curvature.size(); ++i) {
      const cv::Point q = s.contour[i];
      if (s.curvature[i] < curvature_threshold && q.x >= 0 && q.y >= 0 && q.x < v.width && q.y < v.height)
        graspable.at<std::uint8_t>(q) = 1;
    }
    cv::integral(graspable, v.graspable_integral, CV_32S);
  }
  return v;
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
// The fast carver: a pointer octree whose eight children are allocated together, updated
// depth-first so a node's data is hot when its children are tested, subtrees shared out to
// threads. Compared with the reference it saves work three ways that leave every decision the
// same: views in which an ancestor was wholly inside are not tested (a child's corners are inside
// the parent's cube, so its rectangle is inside the parent's), the view that gave the parent its
// lowest occupancy is tested first, and testing stops at the first view that carves the node.

namespace {

struct FastNode {
  double min_occ = 1;              // lowest occupancy over the views tested
  double max_occ = 0;              // highest occupancy (1 when wholly inside some view)
  std::uint64_t full_views = 0;    // bit v: wholly inside silhouette v (views 0..63)
  bool empty = false;
  bool curvature_hit = false;
  Split split = Split::No;
  std::unique_ptr<FastNode[]> children;  // 8, or none
};

struct Task {
  FastNode* node;
  NodeKey key;
  int from_view;
  int hint;
};

}  // namespace

struct OctreeCarver::Impl {
  CarverParams params;
  std::vector<ViewData> views;
  fba::RegionsOfInterest roi;
  bool has_bounds = false;
  Eigen::AlignedBox3d cube;
  Lattice lattice;
  FastNode root;
  CarveStats stats;
  std::shared_ptr<const fba::Octree> cached;

  struct Context {
    std::size_t visited = 0, refined = 0;
    std::vector<Task>* defer = nullptr;  // when set, nodes at defer_depth are queued, not updated
    int defer_depth = 0;
  };

  // Tests n against views [from_view, n_views) (first `hint`), then makes Algorithm 2's decision
  // and recurses. Existing children are updated with the same new views; new children with all.
  void update(FastNode& n, const NodeKey& k, int from_view, int hint, Context& ctx) const {
    if (n.empty) return;  // carved stays carved
    if (ctx.defer && k.depth == ctx.defer_depth) {
      ctx.defer->push_back({&n, k, from_view, hint});
      return;
    }
    ++ctx.visited;
    const int nv = static_cast<int>(views.size());
    int argmin = hint;
    double lowest = 2;
    Rect rects[64];               // rectangles computed here, reused by the leaf test
    std::uint64_t have_rect = 0;
    auto test = [&](int v) {  // false when the view carves the node
      if (v < 64 && ((n.full_views >> v) & 1u)) return true;
      const Rect r = node_rect(views[static_cast<std::size_t>(v)], lattice, k, params.silhouette_tolerance);
      if (v < 64) rects[v] = r, have_rect |= std::uint64_t(1) << v;
      const Occupancy o = occupancy(views[static_cast<std::size_t>(v)], r);
      if (o.empty()) return false;
      const double val = o.value();
      n.min_occ = std::min(n.min_occ, val);
      n.max_occ = std::max(n.max_occ, val);
      if (val < lowest) lowest = val, argmin = v;
      if (o.full()) {
        if (v < 64) n.full_views |= std::uint64_t(1) << v;
      } else if (!n.curvature_hit && graspable_contour_in(views[static_cast<std::size_t>(v)], r)) {
        n.curvature_hit = true;
      }
      return true;
    };
    bool carved = hint >= from_view && hint < nv && !test(hint);
    for (int v = from_view; v < nv && !carved; ++v)
      if (v != hint) carved = !test(v);
    if (carved) {
      n.empty = true;
      n.min_occ = 0;
      n.children.reset();
      return;
    }
    n.split = split_decision(params, lattice, k.depth, n.min_occ, n.max_occ, intersects_roi(roi, lattice, k), n.curvature_hit);
    // Views in which the node is wholly inside cannot carve it by the leaf test either.
    bool leaf_carved = false;
    if (n.split == Split::No && wants_leaf_test(params, lattice, k.depth, n.min_occ))
      for (int v = 0; v < nv && !leaf_carved; ++v) {
        if (v < 64 && ((n.full_views >> v) & 1u)) continue;
        const ViewData& view = views[static_cast<std::size_t>(v)];
        const Rect r = v < 64 && ((have_rect >> v) & 1u) ? rects[v] : node_rect(view, lattice, k, params.silhouette_tolerance);
        double u = 0, w = 0;
        leaf_carved = project_centre(view, lattice, k, u, w) && leaf_carved_by(view, r, u, w, params.silhouette_tolerance);
      }
    if (leaf_carved) {
      n.empty = true;
      n.min_occ = 0;
      n.children.reset();
      return;
    }
    if (n.split == Split::No) {
      n.children.reset();  // no longer wanted (fewer regions of interest, or occupancy fell)
      return;
    }
    int child_from = from_view;
    if (!n.children) {
      n.children = std::make_unique<FastNode[]>(8);
      for (int c = 0; c < 8; ++c) {
        n.children[c].full_views = n.full_views;  // those views are skipped: occupancy 1 there
        n.children[c].max_occ = n.full_views ? 1 : 0;
      }
      child_from = 0;
      ++ctx.refined;
    }
    for (int c = 0; c < 8; ++c) update(n.children[c], k.child(c), child_from, argmin, ctx);
  }

  // Updates the whole tree with views [from_view, n_views).
  void run(int from_view) {
    if (!has_bounds) return;
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<Task> tasks;
    Context top;
    top.defer = &tasks;
    top.defer_depth = 3;  // up to 512 subtrees, enough to balance two to a few dozen threads
    update(root, NodeKey{}, from_view, from_view, top);

    unsigned n_threads = params.threads > 0 ? static_cast<unsigned>(params.threads) : std::thread::hardware_concurrency();
    n_threads = std::max(1u, std::min<unsigned>(n_threads, static_cast<unsigned>(tasks.size())));
    std::vector<Context> ctx(n_threads);
    std::atomic<std::size_t> next{0};
    auto work = [&](Context& c) {
      for (std::size_t i; (i = next.fetch_add(1)) < tasks.size();) {
        const Task& t = tasks[i];
        update(*t.node, t.key, t.from_view, t.hint, c);
      }
    };
    if (n_threads <= 1) {
      if (!ctx.empty()) work(ctx[0]);
    } else {
      std::vector<std::thread> pool;
      for (unsigned i = 1; i < n_threads; ++i) pool.emplace_back(work, std::ref(ctx[i]));
      work(ctx[0]);
      for (auto& t : pool) t.join();
    }
    stats.nodes_visited += top.visited;
    stats.nodes_refined += top.refined;
    for (const auto& c : ctx) stats.nodes_visited += c.visited, stats.nodes_refined += c.refined;
    stats.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    cached.reset();
  }

  std::shared_ptr<const fba::Octree> flatten() const {
    auto t = std::make_shared<fba::Octree>();
    t->max_depth = params.max_depth;
    t->views = static_cast<int>(views.size());
    if (!has_bounds) return t;
    t->bounds = cube;
    // Breadth first, like the reference, so the two layouts agree node for node.
    std::vector<std::pair<const FastNode*, NodeKey>> queue{{&root, NodeKey{}}};
    t->nodes.emplace_back();
    for (std::size_t i = 0; i < queue.size(); ++i) {
      const auto [fn, k] = queue[i];
      fba::OctreeNode n;
      set_geometry(n, lattice, k);
      if (fn->empty) {
        n.state = fba::NodeState::Empty;
        n.occupancy = 0;
      } else {
        n.occupancy = static_cast<float>(fn->min_occ);
        if (fn->children) {
          n.state = fba::NodeState::Partial;
          n.interest = fn->split == Split::Grasp ? 1.0f : 0.0f;
          n.first_child = static_cast<std::int32_t>(queue.size());
          for (int c = 0; c < 8; ++c) {
            queue.emplace_back(&fn->children[c], k.child(c));
            t->nodes.emplace_back();
          }
        } else {
          n.state = fn->min_occ >= 1 ? fba::NodeState::Full : fba::NodeState::Partial;
        }
      }
      t->nodes[i] = n;
    }
    return t;
  }
};

OctreeCarver::OctreeCarver(CarverParams p) : params_(p), impl_(std::make_unique<Impl>()) {
  check_params(p);
  impl_->params = p;
}

OctreeCarver::~OctreeCarver() = default;

void OctreeCarver::set_bounds(const Eigen::AlignedBox3d& box) {
  const Eigen::AlignedBox3d cube = geometry::cube_around(box);
  std::lock_guard lock(mutex_);
  impl_->cube = cube;
  impl_->lattice = Lattice{cube.min(), cube.sizes().x()};
  impl_->has_bounds = true;
  impl_->root = FastNode{};
  impl_->run(0);
}

void OctreeCarver::add_view(const fba::Silhouette& s) {
  ViewData v = make_view(s, params_.curvature_threshold);
  std::lock_guard lock(mutex_);
  impl_->views.push_back(std::move(v));
  impl_->stats.views = impl_->views.size();
  impl_->run(static_cast<int>(impl_->views.size()) - 1);
}

void OctreeCarver::add_views(const std::vector<fba::Silhouette>& views) {
  std::vector<ViewData> prepared;
  for (const auto& s : views) prepared.push_back(make_view(s, params_.curvature_threshold));
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
  if (!impl_->cached) impl_->cached = impl_->flatten();
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
