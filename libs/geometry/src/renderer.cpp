#include "fba/geometry/renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace fba::geometry {
namespace {

// Sutherland-Hodgman against the single plane z = near: keeps the part of the triangle in front.
// Returns the number of polygon vertices written (0, 3 or 4).
int clip_near(const std::array<Eigen::Vector3d, 3>& in, double near,
              std::array<Eigen::Vector3d, 4>& out) {
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d& a = in[i];
    const Eigen::Vector3d& b = in[(i + 1) % 3];
    const bool a_in = a.z() >= near, b_in = b.z() >= near;
    if (a_in) out[n++] = a;
    if (a_in != b_in) {
      const double t = (near - a.z()) / (b.z() - a.z());
      out[n++] = a + t * (b - a);
    }
  }
  return n;
}

struct Buffers {
  int width, height;
  std::vector<float> depth;  // camera z; +inf where empty
  std::vector<int> face;     // triangle index, -1 where empty
};

// Rasterises one screen triangle (already in front of the near plane) into the z-buffer.
// s: pixel coordinates; inv_z: 1 / camera z per vertex (linear in screen space, which is what
// makes the interpolated depth perspective-correct).
void raster_triangle(const std::array<Eigen::Vector2d, 3>& s, const std::array<double, 3>& inv_z,
                     int face_index, Buffers& buf) {
  const double area = (s[1].x() - s[0].x()) * (s[2].y() - s[0].y()) -
                      (s[1].y() - s[0].y()) * (s[2].x() - s[0].x());
  if (area == 0 || !std::isfinite(area)) return;  // edge-on: covers no area
  const double min_x = std::min({s[0].x(), s[1].x(), s[2].x()});
  const double max_x = std::max({s[0].x(), s[1].x(), s[2].x()});
  const double min_y = std::min({s[0].y(), s[1].y(), s[2].y()});
  const double max_y = std::max({s[0].y(), s[1].y(), s[2].y()});
  const int x0 = std::max(0, static_cast<int>(std::ceil(min_x)));
  const int x1 = std::min(buf.width - 1, static_cast<int>(std::floor(max_x)));
  const int y0 = std::max(0, static_cast<int>(std::ceil(min_y)));
  const int y1 = std::min(buf.height - 1, static_cast<int>(std::floor(max_y)));
  if (x0 > x1 || y0 > y1) return;
  const double inv_area = 1.0 / area;
  // Edge function of edge (a, b) at p, scaled so that the three sum to 1 (barycentrics);
  // dividing by the signed area makes both windings work.
  auto edge = [&](int a, int b, double px, double py) {
    return ((s[b].x() - s[a].x()) * (py - s[a].y()) - (s[b].y() - s[a].y()) * (px - s[a].x())) *
           inv_area;
  };
  // Barycentric weight of vertex 0 is the edge function of the opposite edge (1, 2), etc.
  const double dw0_dx = -(s[2].y() - s[1].y()) * inv_area;
  const double dw1_dx = -(s[0].y() - s[2].y()) * inv_area;
  const double dw2_dx = -(s[1].y() - s[0].y()) * inv_area;
  for (int y = y0; y <= y1; ++y) {
    double w0 = edge(1, 2, x0, y), w1 = edge(2, 0, x0, y), w2 = edge(0, 1, x0, y);
    float* drow = &buf.depth[static_cast<std::size_t>(y) * buf.width];
    int* frow = &buf.face[static_cast<std::size_t>(y) * buf.width];
    for (int x = x0; x <= x1; ++x, w0 += dw0_dx, w1 += dw1_dx, w2 += dw2_dx) {
      if (w0 < 0 || w1 < 0 || w2 < 0) continue;
      const double iz = w0 * inv_z[0] + w1 * inv_z[1] + w2 * inv_z[2];
      if (iz <= 0) continue;
      const float z = static_cast<float>(1.0 / iz);
      if (z < drow[x]) {
        drow[x] = z;
        frow[x] = face_index;
      }
    }
  }
}

cv::Vec3b scale_colour(const cv::Vec3b& c, double k) {
  return cv::Vec3b(cv::saturate_cast<uchar>(c[0] * k), cv::saturate_cast<uchar>(c[1] * k),
                   cv::saturate_cast<uchar>(c[2] * k));
}

}  // namespace

RenderResult render(const TriangleMesh& mesh, const CameraModel& camera,
                    const RenderOptions& options) {
  const int W = camera.width, H = camera.height;
  if (W <= 0 || H <= 0) throw std::invalid_argument("render: camera has no image size");
  const Eigen::Matrix3d& K = camera.K;
  const Eigen::Isometry3d& T = camera.camera_from_world;

  // Vertices to camera coordinates once; triangles share them.
  std::vector<Eigen::Vector3d> cam(mesh.vertices.size());
  for (std::size_t i = 0; i < cam.size(); ++i) cam[i] = T * mesh.vertices[i].cast<double>();

  Buffers buf{W, H,
              std::vector<float>(static_cast<std::size_t>(W) * H,
                                 std::numeric_limits<float>::infinity()),
              std::vector<int>(static_cast<std::size_t>(W) * H, -1)};

  // Light direction (towards the light) in camera coordinates; the headlight points back along
  // the viewing axis.
  const Eigen::Vector3d light =
      options.light_towards_world ? (T.linear() * options.light_towards_world->normalized()).eval()
                                  : Eigen::Vector3d(0, 0, -1);
  std::vector<float> shade(mesh.triangles.size(), 0.f);

  auto to_screen = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d h = K * p;
    return Eigen::Vector2d(h.x() / h.z(), h.y() / h.z());
  };

  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    const std::array<Eigen::Vector3d, 3> tri{cam[t[0]], cam[t[1]], cam[t[2]]};
    if (tri[0].z() < options.near_plane && tri[1].z() < options.near_plane &&
        tri[2].z() < options.near_plane)
      continue;
    // Face normal turned towards the camera (two-sided lighting).
    Eigen::Vector3d n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    const double len = n.norm();
    if (len == 0) continue;
    n /= len;
    if (n.dot(tri[0]) > 0) n = -n;  // tri[0] is the vector camera -> surface
    shade[f] = static_cast<float>(options.ambient + options.diffuse * std::max(0.0, n.dot(light)));

    std::array<Eigen::Vector3d, 4> poly;
    const int count = clip_near(tri, options.near_plane, poly);
    for (int k = 1; k + 1 < count; ++k) {  // fan: (0, k, k+1)
      const std::array<Eigen::Vector3d, 3> c{poly[0], poly[k], poly[k + 1]};
      raster_triangle({to_screen(c[0]), to_screen(c[1]), to_screen(c[2])},
                      {1.0 / c[0].z(), 1.0 / c[1].z(), 1.0 / c[2].z()}, static_cast<int>(f), buf);
    }
  }

  RenderResult out;
  out.colour.create(H, W, CV_8UC3);
  out.depth = cv::Mat::zeros(H, W, CV_32FC1);
  out.mask = cv::Mat::zeros(H, W, CV_8UC1);

  // The table: camera centre and ray directions in world coordinates, per pixel.
  const Eigen::Matrix3d Kinv = K.inverse();
  const Eigen::Matrix3d world_from_cam_R = T.linear().transpose();
  const Eigen::Vector3d centre = camera.centre_in_world();
  const Eigen::Vector3d table_normal_cam = T.linear() * Eigen::Vector3d::UnitZ();
  const double table_shade =
      options.ambient + options.diffuse * std::abs(table_normal_cam.dot(light));

  for (int y = 0; y < H; ++y) {
    const double g = H > 1 ? static_cast<double>(y) / (H - 1) : 0.0;
    cv::Vec3b background;
    for (int c = 0; c < 3; ++c)
      background[c] = cv::saturate_cast<uchar>((1 - g) * options.background_top[c] +
                                               g * options.background_bottom[c]);
    auto* crow = out.colour.ptr<cv::Vec3b>(y);
    auto* drow = out.depth.ptr<float>(y);
    auto* mrow = out.mask.ptr<uchar>(y);
    for (int x = 0; x < W; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * W + x;
      double object_z = buf.face[i] >= 0 ? buf.depth[i] : std::numeric_limits<double>::infinity();
      cv::Vec3b colour = background;
      if (options.table) {
        // Ray through the pixel with camera z = 1, so the ray parameter is the camera depth.
        const Eigen::Vector3d d_cam = Kinv * Eigen::Vector3d(x, y, 1.0);
        const Eigen::Vector3d d_world = world_from_cam_R * d_cam;
        if (d_world.z() != 0) {
          const double s = (options.table_z - centre.z()) / d_world.z();
          if (s > options.near_plane) {
            if (s < object_z) object_z = std::numeric_limits<double>::infinity();  // hidden
            const Eigen::Vector3d hit = centre + s * d_world;
            bool dark = false;
            if (options.table_tile > 0) {
              const auto ix = static_cast<long long>(std::floor(hit.x() / options.table_tile));
              const auto iy = static_cast<long long>(std::floor(hit.y() / options.table_tile));
              dark = ((ix + iy) & 1) != 0;
            }
            colour = scale_colour(options.table_colour, table_shade * (dark ? 0.8 : 1.0));
          }
        }
      }
      if (std::isfinite(object_z)) {
        colour = scale_colour(options.object_colour, shade[buf.face[i]]);
        drow[x] = static_cast<float>(object_z);
        mrow[x] = 255;
      }
      crow[x] = colour;
    }
  }

  if (options.noise_sigma > 0) {
    cv::Mat noise(H, W, CV_32FC3);
    cv::RNG rng(options.seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, options.noise_sigma);
    cv::Mat noisy;
    out.colour.convertTo(noisy, CV_32FC3);
    noisy += noise;
    noisy.convertTo(out.colour, CV_8UC3);  // saturating
  }
  return out;
}

void composite(RenderResult& into, const RenderResult& part) {
  const auto shaped = [](const RenderResult& r, cv::Size size) {
    return r.colour.type() == CV_8UC3 && r.depth.type() == CV_32FC1 && r.mask.type() == CV_8UC1 && r.colour.size() == size &&
           r.depth.size() == size && r.mask.size() == size;
  };
  if (!shaped(into, into.colour.size()) || !shaped(part, into.colour.size()))
    throw std::invalid_argument("composite: the two renders differ in size or are not render()'s colour, depth and mask");
  for (int y = 0; y < into.colour.rows; ++y) {
    const float* pz = part.depth.ptr<float>(y);
    const cv::Vec3b* pc = part.colour.ptr<cv::Vec3b>(y);
    float* iz = into.depth.ptr<float>(y);
    cv::Vec3b* ic = into.colour.ptr<cv::Vec3b>(y);
    uchar* im = into.mask.ptr<uchar>(y);
    for (int x = 0; x < into.colour.cols; ++x) {
      if (pz[x] <= 0 || (iz[x] > 0 && iz[x] <= pz[x])) continue;  // no surface of the part, or behind into's
      iz[x] = pz[x];
      ic[x] = pc[x];
      im[x] = 255;
    }
  }
}

}  // namespace fba::geometry
