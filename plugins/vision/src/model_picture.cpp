#include "fba/vision/model_picture.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <unordered_map>

#include <opencv2/imgproc.hpp>

#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/vision/caption.hpp"
#include "fba/vision/octree_carver.hpp"

namespace fba::vision {

namespace {

// What the model knows of an occupied leaf; Hidden ones (below the table) are not drawn.
enum class Kind : std::uint8_t { Carved, Coarse, Unseen, Hidden };
constexpr std::array kDrawn{Kind::Carved, Kind::Coarse, Kind::Unseen};
using Kinds = std::unordered_map<const OctreeNode*, Kind>;

// BGR. Light and neutral for what is known, saturated for what a person should look at.
const cv::Vec3b kColour[3] = {{205, 205, 205}, {230, 195, 150}, {170, 70, 160}};
const char* const kLabel[3] = {"carved", "coarse: not refined yet", "seen by under 2 views: not carved"};
const cv::Vec3b kBackground{250, 248, 245};
const cv::Scalar kRegionLine{0, 110, 230};
const cv::Scalar kContact[3] = {{40, 40, 230}, {40, 170, 40}, {230, 120, 30}};  // thumb, finger 1, finger 2
const cv::Scalar kApproach{0, 200, 230};

Kind kind_of(const Octree& model, const OctreeCell& c, const ModelPictureOptions& o) {
  if (o.table_z && c.box().max().z() <= *o.table_z) return Kind::Hidden;
  if (!seen_by_two_views(c, o.views)) return Kind::Unseen;
  if (c.state() == NodeState::Partial && c.depth < model.max_depth) return Kind::Coarse;
  return Kind::Carved;
}

// Every occupied leaf's kind.
Kinds kinds_of(const Octree& model, const ModelPictureOptions& o) {
  Kinds kinds;
  model.for_each_occupied_leaf([&](const OctreeCell& c) { kinds[c.node] = kind_of(model, c, o); });
  return kinds;
}

int count(const Kinds& kinds, Kind k) {
  return static_cast<int>(std::count_if(kinds.begin(), kinds.end(), [k](const auto& e) { return e.second == k; }));
}

// The box a picture frames: the leaves two views saw (unseen space may spread far beyond the
// object, up to the root box's faces), else every drawn leaf, else the root box.
Eigen::AlignedBox3d drawn_box(const Octree& model, const Kinds& kinds) {
  Eigen::AlignedBox3d seen, drawn;
  model.for_each_occupied_leaf([&](const OctreeCell& c) {
    const Kind k = kinds.at(c.node);
    if (k != Kind::Hidden) drawn.extend(c.box());
    if (k != Kind::Hidden && k != Kind::Unseen) seen.extend(c.box());
  });
  return !seen.isEmpty() ? seen : !drawn.isEmpty() ? drawn : model.bounds;
}

// The views' mean "up" (their images' -y in the world), or world z without views.
Eigen::Vector3d up_of(const std::vector<CameraModel>& views) {
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const auto& v : views) up -= v.camera_from_world.linear().transpose() * Eigen::Vector3d::UnitY();
  return up.norm() < 1e-6 ? Eigen::Vector3d::UnitZ() : up.normalized();
}

// A picture camera at `elevation` above the horizontal and `azimuth` around `up` from the first
// view (or an arbitrary side), looking at the box's centre from as near as frames `points`.
CameraModel picture_camera(const Eigen::AlignedBox3d& box, const std::vector<Eigen::Vector3d>& points, const ModelPictureOptions& o,
                           double azimuth_deg, double elevation_deg) {
  const Eigen::Vector3d centre = box.center(), up = up_of(o.views);
  Eigen::Vector3d side = o.views.empty() ? Eigen::Vector3d(1, -1, 0) : Eigen::Vector3d(o.views.front().centre_in_world() - centre);
  side -= side.dot(up) * up;
  if (side.norm() < 1e-9) side = up.unitOrthogonal();
  side = Eigen::AngleAxisd(azimuth_deg * M_PI / 180, up) * side.normalized();
  const double el = elevation_deg * M_PI / 180;
  const Eigen::Vector3d toward = std::cos(el) * side + std::sin(el) * up;
  // As near as the points fill 88% of the picture's half-width or half-height.
  return geometry::framing_camera(points, centre, toward, up, o.size.width, o.size.height, 0.88);
}

// The leaves drawn by kind: the opaque ones z-buffered together, unseen space blended over them
// where it is in front, translucent and hatched.
cv::Mat draw_leaves(const Octree& model, const Kinds& kinds, const CameraModel& camera, bool with_unseen = true) {
  cv::Mat out(camera.height, camera.width, CV_8UC3, kBackground);
  cv::Mat nearest(camera.height, camera.width, CV_32F, cv::Scalar(0));
  geometry::RenderOptions look;
  look.light_towards_world = (camera.camera_from_world.linear().transpose() * Eigen::Vector3d(-0.3, -0.5, -1.0)).normalized();
  look.ambient = 0.35;
  look.diffuse = 0.65;
  for (const Kind k : kDrawn) {
    if (k == Kind::Unseen && !with_unseen) continue;
    const TriangleMesh mesh = surface_mesh(model, [&](const OctreeCell& c) { return kinds.at(c.node) == k; });
    if (mesh.triangles.empty()) continue;
    look.object_colour = kColour[static_cast<int>(k)];
    const geometry::RenderResult r = geometry::render(mesh, camera, look);
    for (int y = 0; y < out.rows; ++y)
      for (int x = 0; x < out.cols; ++x) {
        const float z = r.depth.at<float>(y, x);
        float& front = nearest.at<float>(y, x);
        if (z <= 0 || (front > 0 && z >= front)) continue;
        cv::Vec3b& px = out.at<cv::Vec3b>(y, x);
        if (k != Kind::Unseen) {
          px = r.colour.at<cv::Vec3b>(y, x);
          front = z;
        } else {
          const bool hatch = (x + y) % 12 == 0;
          const cv::Vec3b c = hatch ? kColour[static_cast<int>(Kind::Unseen)] : r.colour.at<cv::Vec3b>(y, x);
          for (int i = 0; i < 3; ++i) px[i] = static_cast<uchar>(hatch ? c[i] : 0.75 * px[i] + 0.25 * c[i]);
        }
      }
  }
  return out;
}

cv::Point pixel(const CameraModel& camera, const Eigen::Vector3d& p) {
  Eigen::Vector2d px;
  if (!geometry::project(camera, p, px)) return {-10000, -10000};
  return {static_cast<int>(std::lround(px.x())), static_cast<int>(std::lround(px.y()))};
}

void draw_box(cv::Mat& picture, const CameraModel& camera, const Eigen::AlignedBox3d& b, const cv::Scalar& colour) {
  for (int i = 0; i < 8; ++i)
    for (int axis = 0; axis < 3; ++axis)
      if (!(i & (1 << axis)))  // each edge once: from the corner with the axis's bit clear
        cv::line(picture, pixel(camera, b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i))),
                 pixel(camera, b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i | (1 << axis)))), colour, 1, cv::LINE_AA);
}

void draw_grasp(cv::Mat& picture, const CameraModel& camera, const Grasp& g) {
  for (std::size_t i = 0; i < 3; ++i) {
    const auto& c = g.contacts[i];
    cv::arrowedLine(picture, pixel(camera, c.position - g.approach.normalized() * 0.05), pixel(camera, c.position), kApproach, 2,
                    cv::LINE_AA, 0, 0.2);
    cv::arrowedLine(picture, pixel(camera, c.position - c.normal.normalized() * 0.03), pixel(camera, c.position), kContact[i], 2,
                    cv::LINE_AA, 0, 0.3);
    cv::circle(picture, pixel(camera, c.position), 6, kContact[i], cv::FILLED, cv::LINE_AA);
  }
}

std::string fixed(double v, const char* format = "%.3f") {
  char s[32];
  std::snprintf(s, sizeof s, format, v);
  return s;
}

// The legend of the leaves' kinds present (carved always), the regions and the grasp.
std::vector<LegendEntry> model_legend(const Kinds& kinds, const ModelPictureOptions& o, bool with_unseen = true) {
  std::vector<LegendEntry> legend;
  for (const Kind k : kDrawn)
    if (k == Kind::Carved || (count(kinds, k) > 0 && (k != Kind::Unseen || with_unseen))) {
      const cv::Vec3b c = kColour[static_cast<int>(k)];
      legend.push_back({cv::Scalar(c[0], c[1], c[2]), kLabel[static_cast<int>(k)], k == Kind::Unseen ? LegendMark::Hatch : LegendMark::Swatch});
    }
  if (!o.regions.empty()) legend.push_back({kRegionLine, "region synthesis asked to refine", LegendMark::Line});
  if (o.grasp) {
    legend.push_back({kContact[0], "thumb", LegendMark::Dot});
    legend.push_back({kContact[1], "finger 1", LegendMark::Dot});
    legend.push_back({kContact[2], "finger 2", LegendMark::Dot});
    legend.push_back({kApproach, "approach", LegendMark::Line});
  }
  return legend;
}

std::string object_of(const ModelPictureOptions& o) { return o.object.empty() ? "the object" : o.object; }


void check_size(const ModelPictureOptions& o) {
  if (o.size.width < 64 || o.size.height < 64)
    throw std::invalid_argument("model picture: the size " + std::to_string(o.size.width) + " x " + std::to_string(o.size.height) +
                                " is under 64 x 64");
}

std::vector<Eigen::Vector3d> corners(const Eigen::AlignedBox3d& b) {
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < 8; ++i) out.push_back(b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i)));
  return out;
}

}  // namespace

cv::Mat model_picture(const Octree& model, const ModelPictureOptions& o) {
  check_size(o);
  const Kinds kinds = kinds_of(model, o);
  const Eigen::AlignedBox3d box = drawn_box(model, kinds);
  const CameraModel camera = picture_camera(box, corners(box), o, 35, 15);
  cv::Mat picture = draw_leaves(model, kinds, camera);
  for (const auto& r : o.regions) draw_box(picture, camera, r, kRegionLine);
  if (o.grasp) draw_grasp(picture, camera, *o.grasp);

  Caption caption;
  caption.title = object_of(o) + ": the carved model after " + std::to_string(model.views) + " views";
  caption.details = "depth " + std::to_string(model.max_depth) + ", " + std::to_string(kinds.size()) + " occupied leaves";
  if (o.grasp) {
    const auto& s = o.grasp->scores;
    caption.details += "; grasp total " + fixed(s.total) + " (S1 symmetry " + fixed(s.symmetry) + ", S3 safety " + fixed(s.safety_margin) +
                       ", S4 curvature " + fixed(s.curvature) + ")";
  }
  caption.legend = model_legend(kinds, o);
  return captioned(picture, caption);
}

cv::Mat views_picture(const Octree& model, const ModelPictureOptions& o) {
  check_size(o);
  const Kinds kinds = kinds_of(model, o);
  const Eigen::AlignedBox3d box = drawn_box(model, kinds);
  std::vector<Eigen::Vector3d> points = corners(box);
  for (const auto& v : o.views) points.push_back(v.centre_in_world());
  const CameraModel camera = picture_camera(box, points, o, 20, 55);
  // Without the unseen space: from this far and high it would hide the model under it.
  cv::Mat picture = draw_leaves(model, kinds, camera, false);

  const std::size_t n = o.views.size();
  std::vector<cv::Point> path;
  for (const auto& v : o.views) path.push_back(pixel(camera, v.centre_in_world()));
  for (std::size_t i = 1; i < n; ++i) cv::line(picture, path[i - 1], path[i], {90, 90, 90}, 1, cv::LINE_AA);
  for (std::size_t i = 0; i < n; ++i) {
    const CameraModel& v = o.views[i];
    // Early views blue, late ones red; each a pyramid from its centre to its image's corners,
    // a quarter of the way to the model: where it stood and where it looked.
    const double t = n > 1 ? double(i) / double(n - 1) : 0.0;
    const cv::Scalar colour(230 * (1 - t), 60, 230 * t);
    const Eigen::Vector3d c = v.centre_in_world();
    const double depth = 0.25 * (c - box.center()).norm();
    const Eigen::Isometry3d world_from_camera = v.camera_from_world.inverse();
    const Eigen::Matrix3d K_inv = v.K.inverse();
    std::array<cv::Point, 4> at;
    const double us[4] = {0, double(v.width), double(v.width), 0}, vs[4] = {0, 0, double(v.height), double(v.height)};
    for (int k = 0; k < 4; ++k) at[k] = pixel(camera, world_from_camera * (K_inv * Eigen::Vector3d(us[k], vs[k], 1) * depth));
    for (int k = 0; k < 4; ++k) {
      cv::line(picture, path[i], at[k], colour, 1, cv::LINE_AA);
      cv::line(picture, at[k], at[(k + 1) % 4], colour, 2, cv::LINE_AA);
    }
    cv::circle(picture, path[i], 5, colour, cv::FILLED, cv::LINE_AA);
    const std::string label = std::to_string(i + 1);
    cv::putText(picture, label, path[i] + cv::Point(7, -7), cv::FONT_HERSHEY_SIMPLEX, 0.6, {255, 255, 255}, 4, cv::LINE_AA);
    cv::putText(picture, label, path[i] + cv::Point(7, -7), cv::FONT_HERSHEY_SIMPLEX, 0.6, colour, 2, cv::LINE_AA);
  }

  Caption caption;
  caption.title = object_of(o) + ": the " + std::to_string(n) + " views taken, in order";
  if (n > 0) {
    const Eigen::Vector3d a = o.views.front().centre_in_world(), b = o.views.back().centre_in_world();
    caption.details = "view 1 at " + position_text(a.x(), a.y(), a.z()) + ", view " + std::to_string(n) + " at " +
                      position_text(b.x(), b.y(), b.z()) + "; the model after " + std::to_string(model.views) + " views";
  } else {
    caption.details = "no view was taken";
  }
  caption.legend = {{{230, 60, 0}, "first view", LegendMark::Dot},
                    {{0, 60, 230}, "last view (camera: centre, image's corners)", LegendMark::Dot},
                    {{90, 90, 90}, "path, in order", LegendMark::Line}};
  for (auto& e : model_legend(kinds, {}, false)) caption.legend.push_back(std::move(e));
  return captioned(picture, caption);
}

std::string object_name(const std::string& path) {
  const std::filesystem::path p(path);
  std::string name = p.stem().string();
  // A generic file name (a scanned object's model.obj) or a numbered image says less than its folder.
  const bool numbered = !name.empty() && std::isdigit(static_cast<unsigned char>(name.back()));
  if (name == "model" || name == "textured" || numbered) name = p.parent_path().filename().string();
  if (name.rfind("sim_", 0) == 0) name = name.substr(4);
  if (name.rfind("Ycb", 0) == 0) name = name.substr(3);
  std::string out;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    if (c == '_' || c == '-') {
      out += ' ';
      continue;
    }
    if (std::isupper(static_cast<unsigned char>(c)) && i > 0 && std::islower(static_cast<unsigned char>(name[i - 1]))) out += ' ';
    out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return out.empty() ? "the object" : out;
}

}  // namespace fba::vision
