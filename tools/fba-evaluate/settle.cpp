#include "settle.hpp"

#include <mujoco/mujoco.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

namespace fba::evaluate {

namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

struct VfsDeleter {
  void operator()(mjVFS* v) const {
    mj_deleteVFS(v);
    delete v;
  }
};
struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};

// MuJoCo's warnings go to the settle running on this thread (MuJoCo's default handler writes
// MUJOCO_LOG.TXT into the current folder); any other to stderr.
thread_local std::vector<std::string>* warnings_here = nullptr;

void take_warning(const char* message) {
  if (warnings_here) warnings_here->push_back(message);
  else std::fprintf(stderr, "MuJoCo: %s\n", message);
}

// Restores the thread's sink however the settle ends.
struct WarningSink {
  explicit WarningSink(std::vector<std::string>* to) : before(warnings_here) {
    static const bool installed = [] {
      mju_user_warning = take_warning;
      return true;
    }();
    (void)installed;
    warnings_here = to;
  }
  ~WarningSink() { warnings_here = before; }
  std::vector<std::string>* before;
};

}  // namespace

Eigen::Quaterniond random_orientation(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const auto unit = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  const double u1 = unit(), u2 = unit(), u3 = unit();
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1), t = 2 * std::numbers::pi;
  return Eigen::Quaterniond(b * std::cos(t * u3), a * std::sin(t * u2), a * std::cos(t * u2), b * std::sin(t * u3)).normalized();
}

Eigen::Quaterniond tilt_only(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d up = q.conjugate() * Eigen::Vector3d::UnitZ();  // +z of the table, in the mesh's frame
  return Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitZ()).normalized();
}

SettleResult settle(const TriangleMesh& mesh, const std::vector<geometry::ConvexPart>& given, const Eigen::Quaterniond& dropped,
                    const SettleParams& p) {
  const geometry::SolidProperties solid = geometry::solid_properties(mesh);
  if (!(solid.volume > 0))
    throw std::invalid_argument("settle: expected a closed, outward mesh (positive volume); found a volume of " + num(solid.volume) + " m^3");
  const Eigen::Quaterniond q0 = dropped.normalized();
  const Eigen::Matrix3d r0 = q0.toRotationMatrix();
  double lowest = INFINITY;
  for (const auto& v : mesh.vertices) lowest = std::min(lowest, (r0 * v.cast<double>()).z());

  SettleResult out;
  const WarningSink sink(&out.warnings);
  std::vector<geometry::ConvexPart> parts = given;
  if (parts.empty()) {
    parts.emplace_back();
    parts[0].points = mesh.vertices;
  }
  std::string assets, geoms;
  const auto triple = [](const Eigen::Vector3d& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); };
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const geometry::ConvexPart& part = parts[i];
    using Kind = geometry::ConvexPart::Kind;
    if (part.kind == Kind::hull) {
      std::string points;
      for (const auto& v : part.points) points += triple(v.cast<double>()) + " ";
      assets += "<mesh name=\"hull" + std::to_string(i) + "\" vertex=\"" + points + "\"/>\n";
      geoms += "<geom type=\"mesh\" mesh=\"hull" + std::to_string(i) + "\" condim=\"6\"/>\n";
      continue;
    }
    const Eigen::Quaterniond q(part.axes);
    const std::string at = "pos=\"" + triple(part.centre) + "\" quat=\"" + num(q.w()) + " " + num(q.x()) + " " + num(q.y()) + " " + num(q.z()) + "\"";
    if (part.kind == Kind::box) geoms += "<geom type=\"box\" size=\"" + triple(part.half) + "\" " + at + " condim=\"6\"/>\n";
    if (part.kind == Kind::cylinder)
      geoms += "<geom type=\"cylinder\" size=\"" + num(part.half.x()) + " " + num(part.half.z()) + "\" " + at + " condim=\"6\"/>\n";
    if (part.kind == Kind::ellipsoid) geoms += "<geom type=\"ellipsoid\" size=\"" + triple(part.half) + "\" " + at + " condim=\"6\"/>\n";
  }
  const Eigen::Matrix3d inertia = p.mass * solid.inertia;
  const Eigen::Vector3d& c = solid.centroid;
  // Viscous damping of the free joint, the same coefficient on its turning (N m s) and its moving
  // (N s / m): the largest principal moment of inertia over turn_damping_time, so that a turn decays
  // in that time; a move then in mass / damping, over 500 s for every family: gravity is not held back.
  const double damping = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(inertia).eigenvalues().maxCoeff() / p.turn_damping_time;
  std::string mjcf = "<mujoco model=\"settle\">\n<compiler angle=\"radian\"/>\n";
  mjcf += "<option timestep=\"" + num(p.timestep) + "\" cone=\"elliptic\" impratio=\"10\" gravity=\"0 0 -9.81\"/>\n";
  mjcf += "<default><geom friction=\"" + num(p.friction) + " 0.005 0.0001\"/></default>\n";
  if (!assets.empty()) mjcf += "<asset>\n" + assets + "</asset>\n";
  mjcf += "<worldbody>\n<geom name=\"table\" type=\"plane\" size=\"1 1 0.01\"/>\n";
  mjcf += "<body name=\"object\" pos=\"0 0 " + num(p.drop_height - lowest) + "\" quat=\"" + num(q0.w()) + " " + num(q0.x()) + " " +
          num(q0.y()) + " " + num(q0.z()) + "\">\n<joint type=\"free\" damping=\"" + num(damping) + "\"/>\n";
  // The solid's own mass properties, not the parts' that MuJoCo would compute.
  mjcf += "<inertial pos=\"" + num(c.x()) + " " + num(c.y()) + " " + num(c.z()) + "\" mass=\"" + num(p.mass) + "\" fullinertia=\"" +
          num(inertia(0, 0)) + " " + num(inertia(1, 1)) + " " + num(inertia(2, 2)) + " " + num(inertia(0, 1)) + " " + num(inertia(0, 2)) +
          " " + num(inertia(1, 2)) + "\"/>\n";
  mjcf += geoms + "</body>\n</worldbody>\n</mujoco>\n";

  std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), "settle.xml", static_cast<int>(mjcf.size())) != 0)
    throw std::runtime_error("settle: MuJoCo's virtual file system refused the model");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), "settle.xml")], mjcf.data(), mjcf.size());
  char error[1000] = "";
  std::unique_ptr<mjModel, ModelDeleter> m;
  {
    // MuJoCo's XML loader keeps the last model it parsed in a global (for mj_saveLastXML): one load
    // at a time, when --jobs settles several objects at once. Stepping needs no lock.
    static std::mutex loading;
    const std::lock_guard lock(loading);
    m.reset(mj_loadXML("settle.xml", vfs.get(), error, sizeof error));
  }
  if (!m) throw std::runtime_error(std::string("settle: MuJoCo refused the object's model: ") + error);
  std::unique_ptr<mjData, DataDeleter> d(mj_makeData(m.get()));

  out.dropped = q0;
  const long max_steps = std::lround(p.max_time / p.timestep), window_steps = std::max(1L, std::lround(p.window / p.timestep));
  const int still_windows = std::max(1, static_cast<int>(std::lround(p.still_time / p.window)));
  const auto up = [&] { return Eigen::Quaterniond(d->qpos[3], d->qpos[4], d->qpos[5], d->qpos[6]).normalized().conjugate() * Eigen::Vector3d::UnitZ(); };
  Eigen::Vector3d last_up = up(), last_at(d->qpos[0], d->qpos[1], d->qpos[2]);
  const double cos_tilt = std::cos(p.still_tilt_deg * std::numbers::pi / 180);
  int still_for = 0;
  while (out.steps < max_steps) {
    mj_step(m.get(), d.get());
    if (++out.steps % window_steps) continue;
    const Eigen::Vector3d now_up = up(), now_at(d->qpos[0], d->qpos[1], d->qpos[2]);
    still_for = now_up.dot(last_up) > cos_tilt && (now_at - last_at).norm() < p.still_move ? still_for + 1 : 0;
    last_up = now_up;
    last_at = now_at;
    if (still_for >= still_windows) {
      out.still = true;
      break;
    }
  }
  out.time = static_cast<double>(out.steps) * p.timestep;
  out.position = Eigen::Vector3d(d->qpos[0], d->qpos[1], d->qpos[2]);
  out.settled = Eigen::Quaterniond(d->qpos[3], d->qpos[4], d->qpos[5], d->qpos[6]).normalized();
  const Eigen::Matrix3d r = out.settled.toRotationMatrix();
  out.lowest = INFINITY;
  for (const auto& v : mesh.vertices) out.lowest = std::min(out.lowest, (r * v.cast<double>() + out.position).z());
  return out;
}

}  // namespace fba::evaluate
