// The view of an octree model: its occupied leaves as flat arrays of centre and edge (world,
// metres). `occupied` is the model, every occupied leaf once; `refine` and `uncarved` mark some of
// them again, for the page to highlight, as the model picture (plugins/vision/src/model_picture.cpp)
// tells them apart:
//  - refine: the leaves of a node split because a grasp criterion asked (synthesis's regions, a
//    graspable contour): the carver marks that node's interest;
//  - uncarved: what the carving has not resolved: the leaves on the outline (Partial) not split
//    down to the model's depth. Before the first view nothing is carved: every leaf is uncarved,
//    and none is shown as occupied (the root box is not the object).
// A model of more than kMaxModelLeaves occupied leaves is shown at the deepest depth whose nodes
// fit, each node there standing for the leaves under it.
#include <algorithm>
#include <array>
#include <vector>

#include "fba/types/octree.hpp"
#include "view_json.hpp"
#include "views.hpp"

namespace fba::views {

namespace {

enum Array { kOccupied, kUncarved, kRefine };
constexpr const char* kArrayName[3] = {"occupied", "uncarved", "refine"};

struct Classifier {
  const Octree& model;
  std::vector<char> interest;  // by depth, along the walk's current path: the node was split for a grasp criterion

  // The arrays an occupied node shown as a box goes in: a leaf, or a node standing for the leaves under it.
  std::array<bool, 3> arrays(const OctreeCell& c) const {
    if (model.views == 0) return {false, true, false};
    const bool parent_interest = c.depth > 0 && interest[static_cast<std::size_t>(c.depth - 1)];
    const bool refine = parent_interest || (!c.is_leaf() && c.interest() > 0);
    const bool coarse = c.is_leaf() && c.state() == NodeState::Partial && c.depth < model.max_depth;
    return {true, coarse, refine};
  }
  void enter(const OctreeCell& c) {
    const auto d = static_cast<std::size_t>(c.depth);
    if (interest.size() <= d) interest.resize(d + 1);
    interest[d] = c.interest() > 0;
  }
};

struct Census {
  std::size_t leaves[3] = {0, 0, 0};             // occupied leaves by array
  std::vector<std::size_t> leaves_at, inner_at;  // occupied leaves, and occupied nodes with children, by depth
  // Boxes shown when nodes at `depth` stand for the leaves under them.
  std::size_t shown_at(int depth) const {
    std::size_t n = depth < static_cast<int>(inner_at.size()) ? inner_at[static_cast<std::size_t>(depth)] : 0;
    for (int d = 0; d <= depth && d < static_cast<int>(leaves_at.size()); ++d) n += leaves_at[static_cast<std::size_t>(d)];
    return n;
  }
};

Census take_census(const Octree& model) {
  Census c;
  Classifier kinds{model, {}};
  model.for_each_node([&](const OctreeCell& cell) {
    kinds.enter(cell);
    if (!cell.occupied()) return false;
    auto& at = cell.is_leaf() ? c.leaves_at : c.inner_at;
    const auto d = static_cast<std::size_t>(cell.depth);
    if (at.size() <= d) at.resize(d + 1, 0);
    ++at[d];
    if (cell.is_leaf()) {
      const auto in = kinds.arrays(cell);
      for (int a = 0; a < 3; ++a) c.leaves[a] += in[static_cast<std::size_t>(a)];
    }
    return true;
  });
  return c;
}

void append_box(std::string& out, const OctreeCell& c) {
  if (out.back() != '[') out += ',';
  for (int i = 0; i < 3; ++i) {
    append_number(out, c.centre[i], kMetres);
    out += ',';
  }
  append_number(out, 2 * c.half_size, kMetres);
}

void append_bounds(std::string& out, const Eigen::AlignedBox3d& b) {
  out += '[';
  for (int i = 0; i < 6; ++i) {
    if (i > 0) out += ',';
    append_number(out, i < 3 ? b.min()[i] : b.max()[i - 3], kMetres);
  }
  out += ']';
}

}  // namespace

std::string model_view(const Packet& p) {
  try {
    const Octree& model = p.get<Octree>();
    if (model.node_count == 0 || model.bounds.isEmpty()) return {};
    const Census census = take_census(model);
    // Where no node is cut: below the deepest occupied node that has children, and as deep as the deepest leaf.
    const int deepest = static_cast<int>(std::max(census.leaves_at.size(), census.inner_at.size() + 1)) - 1;
    int depth = deepest;
    while (depth > 0 && census.shown_at(depth) > kMaxModelLeaves) --depth;

    // The three arrays, written as JSON text directly: a depth-8 model has some 10^5 numbers.
    std::string arrays[3] = {"[", "[", "["};
    Eigen::AlignedBox3d shown_box;
    Classifier kinds{model, {}};
    model.for_each_node([&](const OctreeCell& c) {
      kinds.enter(c);
      if (!c.occupied()) return false;
      if (!c.is_leaf() && c.depth < depth) return true;
      const auto in = kinds.arrays(c);
      for (int a = 0; a < 3; ++a)
        if (in[static_cast<std::size_t>(a)]) append_box(arrays[a], c);
      shown_box.extend(c.box());
      return false;
    });

    std::string out = R"({"kind":"model")";
    for (int k = 0; k < 3; ++k) out += std::string(",\"") + kArrayName[k] + "\":" + arrays[k] + "]";
    out += R"(,"bounds":)";
    append_bounds(out, shown_box.isEmpty() ? model.bounds : shown_box);
    out += R"(,"root":)";
    append_bounds(out, model.bounds);
    out += R"(,"counts":{)";
    for (int k = 0; k < 3; ++k)
      out += std::string(k ? "," : "") + "\"" + kArrayName[k] + "\":" + std::to_string(census.leaves[k]);
    out += "},\"truncated\":" + std::string(depth < deepest ? "true" : "false");
    out += ",\"shown_depth\":" + std::to_string(depth) + ",\"max_depth\":" + std::to_string(model.max_depth);
    out += ",\"views\":" + std::to_string(model.views) + "}";
    return out;
  } catch (...) {  // a view is shown or not, never thrown from (views.hpp)
    return {};
  }
}

}  // namespace fba::views
