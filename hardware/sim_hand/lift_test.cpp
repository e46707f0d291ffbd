#include "lift_test.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <sstream>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <mujoco/mujoco.h>

#include <Eigen/Geometry>

#include "fba/geometry/decimate.hpp"
#include "hand_model.hpp"

namespace fba::sim_hand {

namespace {

// MuJoCo's default error handler ends the process; a scene that overflows its memory must be a
// failed test, not a dead task. libmujoco is built with unwind tables (amd64), so an exception
// passes through it.
[[noreturn]] void throw_mujoco_error(const char* message) { throw LiftTestError(std::string("MuJoCo: ") + message); }
// Warnings (an unstable simulation) are read from mjData after each step instead of printed.
void ignore_mujoco_warning(const char*) {}

void install_mujoco_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    mju_user_error = throw_mujoco_error;
    mju_user_warning = ignore_mujoco_warning;
  });
}

// A binary STL: what MuJoCo 2.2 reads as a mesh asset (it has no mesh API; the file goes in its
// virtual file system).
std::string binary_stl(const TriangleMesh& mesh, const Eigen::Vector3d& origin) {
  std::string out(80, '\0');
  auto put = [&out](const void* p, std::size_t n) { out.append(static_cast<const char*>(p), n); };
  const auto count = static_cast<std::uint32_t>(mesh.triangles.size());
  put(&count, 4);
  for (const auto& t : mesh.triangles) {
    float v[12] = {};
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f p = mesh.vertices[static_cast<std::size_t>(t[k])] - origin.cast<float>();
      for (int j = 0; j < 3; ++j) v[3 + 3 * k + j] = p[j];
    }
    put(v, sizeof v);
    const std::uint16_t attributes = 0;
    put(&attributes, 2);
  }
  return out;
}

struct VfsDeleter {
  void operator()(mjVFS* v) const {
    mj_deleteVFS(v);
    delete v;
  }
};

void add_file(mjVFS& vfs, const std::string& name, const std::string& data) {
  if (mj_makeEmptyFileVFS(&vfs, name.c_str(), static_cast<int>(data.size())) != 0)
    throw LiftTestError("lift test: cannot add " + name + " to MuJoCo's virtual file system");
  const int i = mj_findFileVFS(&vfs, name.c_str());
  std::memcpy(vfs.filedata[i], data.data(), data.size());
}

double smoothstep(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * (3 - 2 * s);
}

std::string format_m(double v) { return fmt::format("{:.3f} m", v); }

}  // namespace

const std::string& LiftTest::hand_model() {
  static const std::string text(kHandModel);
  return text;
}

struct LiftTest::Impl {
  LiftTestParams params;
  TriangleMesh object;
  std::string physics_note;
  mjModel* m = nullptr;
  mjData* d = nullptr;

  // Indices in the model, looked up once by name.
  int palm_body = -1, palm_joint = -1, mocap = -1, object_body = -1, table_geom = -1;
  struct Finger {
    std::string name;
    int close_joint = -1, close_actuator = -1;  // the closing slide, force driven
    std::vector<int> phalanx_actuators;         // the phalanges' position servos
    int spread_actuator = -1;          // -1 for the thumb
    int spread_joint = -1;
  };
  std::array<Finger, 3> fingers;  // thumb, finger_a (+y), finger_b (-y)
  // The hand's geometry, read from the model: the fully open fingers' distance from the palm's
  // centre along x, the pad's distance from the palm's frame along z, the pad's radius, the spread range,
  // the closing slides' travel.
  // pad_to_end: from the pad to the end of the distal phalanx's straight part.
  double base_x = 0, pad_distance = 0, pad_radius = 0, pad_to_end = 0, spread_min = 0, spread_max = 0, travel = 0;
  long steps = 0;
  std::atomic<bool> stop{false};
  struct Stopped {};  // thrown out of a step once stop is set

  ~Impl() {
    if (d) mj_deleteData(d);
    if (m) mj_deleteModel(m);
  }

  int id(mjtObj type, const std::string& name) const {
    const int i = mj_name2id(m, type, name.c_str());
    if (i < 0) throw LiftTestError("lift test: the hand model has no " + std::string(mju_type2Str(type)) + " named '" + name + "'");
    return i;
  }

  std::string geom_name(int g) const {
    const char* n = mj_id2name(m, mjOBJ_GEOM, g);
    return n ? n : "geom " + std::to_string(g);
  }

  bool is_hand(int geom) const { return m->body_rootid[m->geom_bodyid[geom]] == palm_body; }
  bool is_object(int geom) const { return m->geom_bodyid[geom] == object_body; }

  bool hand_touches_table() const {
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      if (c.dist <= 0 && ((is_hand(c.geom1) && c.geom2 == table_geom) || (is_hand(c.geom2) && c.geom1 == table_geom))) return true;
    }
    return false;
  }

  // The first contact between the hand and anything, as "<hand part> touches <other>"; empty if none.
  std::string hand_collision() const {
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      if (c.dist > 0) continue;  // within the margin, not touching
      for (auto [h, o] : {std::pair{c.geom1, c.geom2}, std::pair{c.geom2, c.geom1}})
        if (is_hand(h) && !is_hand(o)) return geom_name(h) + " touches " + (is_object(o) ? "the object" : geom_name(o));
    }
    return {};
  }

  std::vector<ExecutedContact> object_contacts() const {
    std::vector<ExecutedContact> out;
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      const bool object_second = is_hand(c.geom1) && is_object(c.geom2);
      if (!object_second && !(is_hand(c.geom2) && is_object(c.geom1))) continue;
      mjtNum f[6];
      mj_contactForce(m, d, i, f);
      if (f[0] <= 0) continue;
      ExecutedContact e;
      e.link = geom_name(object_second ? c.geom1 : c.geom2);
      e.position = Eigen::Vector3d(c.pos[0], c.pos[1], c.pos[2]);
      // The contact frame's normal points from geom1 to geom2.
      e.normal = Eigen::Vector3d(c.frame[0], c.frame[1], c.frame[2]) * (object_second ? 1.0 : -1.0);
      e.force = f[0];
      out.push_back(std::move(e));
    }
    return out;
  }

  Eigen::Vector3d object_centre() const {
    const mjtNum* p = d->xipos + 3 * object_body;
    return {p[0], p[1], p[2]};
  }
  Eigen::Vector3d palm_position() const {
    const mjtNum* p = d->xpos + 3 * palm_body;
    return {p[0], p[1], p[2]};
  }
  Eigen::Vector3d wrist_position() const { return {d->mocap_pos[3 * mocap], d->mocap_pos[3 * mocap + 1], d->mocap_pos[3 * mocap + 2]}; }

  bool unstable() const { return d->warning[mjWARN_BADQACC].number > 0; }
};

LiftTest::LiftTest(const TriangleMesh& mesh, const ObjectPlacement& placement, const LiftTestParams& params,
                   const std::string& hand_mjcf)
    : impl_(std::make_unique<Impl>()) {
  install_mujoco_handlers();
  if (mesh.triangles.empty()) throw LiftTestError("lift test: the object mesh has no triangles");
  if (!(params.mass > 0) || !(params.friction > 0) || !(params.lift_height > 0) || !(params.hold_s >= 0) ||
      !(params.lift_s > 0) || !(params.finger_force > 0) || !(params.drop_distance > 0) || !(params.clearance >= 0) ||
      !(params.contact_tolerance > 0) ||
      !(params.pregrasp_distance >= 0))
    throw std::invalid_argument("lift test: mass, friction, lift height, lift time, finger force, drop distance and contact "
                                "tolerance must be "
                                "positive, hold time, clearance and pregrasp distance not negative");
  auto& s = *impl_;
  s.params = params;
  s.object = place_on_table(mesh, placement);

  // The scene: the hand model with the object added as a free body. The mesh's vertices are
  // given relative to the body, placed at the centre of the mesh's bounds; MuJoCo collides with
  // their convex hull and spreads the mass over the mesh's volume.
  Eigen::AlignedBox3d box;
  for (const auto& v : s.object.vertices) box.extend(v.cast<double>());
  const Eigen::Vector3d centre = box.center();
  std::string scene = hand_mjcf.empty() ? hand_model() : hand_mjcf;
  const auto end = scene.rfind("</mujoco>");
  if (end == std::string::npos) throw LiftTestError("lift test: the hand model is not MJCF: no </mujoco> found");
  scene.insert(end, fmt::format(R"(
  <asset><mesh name="object" file="object.stl"/></asset>
  <worldbody>
    <body name="object" pos="{} {} {}">
      <freejoint name="object"/>
      <geom name="object" type="mesh" mesh="object" mass="{}" contype="1" conaffinity="3" condim="4" rgba="0.8 0.3 0.2 1"/>
    </body>
  </worldbody>
)", centre.x(), centre.y(), centre.z(), params.mass));

  const geometry::Decimated physics = geometry::decimate(s.object, kPhysicsTriangles);
  if (physics.cell > 0)
    s.physics_note = fmt::format("the object's {} triangles were decimated to {} for MuJoCo (at most {}), by vertex clustering on a "
                                 "{:.2f} mm grid",
                                 s.object.triangles.size(), physics.mesh.triangles.size(), kPhysicsTriangles, physics.cell * 1e3);
  std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  add_file(*vfs, "scene.xml", scene);
  add_file(*vfs, "object.stl", binary_stl(physics.mesh, centre));
  char error[1024] = "";
  s.m = mj_loadXML("scene.xml", vfs.get(), error, sizeof error);
  if (!s.m) throw LiftTestError(std::string("lift test: MuJoCo does not compile the scene: ") + error);
  s.d = mj_makeData(s.m);
  if (!s.d) throw LiftTestError("lift test: MuJoCo could not allocate the simulation data");

  for (int g = 0; g < s.m->ngeom; ++g) s.m->geom_friction[3 * g] = params.friction;
  s.palm_body = s.id(mjOBJ_BODY, "palm");
  s.palm_joint = s.id(mjOBJ_JOINT, "palm");
  s.mocap = s.m->body_mocapid[s.id(mjOBJ_BODY, "wrist")];
  if (s.mocap < 0) throw LiftTestError("lift test: the hand model's body 'wrist' is not a mocap body");
  if (s.m->jnt_type[s.palm_joint] != mjJNT_FREE) throw LiftTestError("lift test: the hand model's joint 'palm' is not a free joint");
  s.object_body = s.id(mjOBJ_BODY, "object");
  s.table_geom = s.id(mjOBJ_GEOM, "table");
  const char* names[3] = {"thumb", "finger_a", "finger_b"};
  for (int f = 0; f < 3; ++f) {
    auto& finger = s.fingers[static_cast<std::size_t>(f)];
    finger.name = names[f];
    finger.close_joint = s.id(mjOBJ_JOINT, finger.name + "_close");
    finger.close_actuator = s.id(mjOBJ_ACTUATOR, finger.name + "_close");
    for (const char* k : {"_1", "_2", "_3"}) finger.phalanx_actuators.push_back(s.id(mjOBJ_ACTUATOR, finger.name + k));
    if (f > 0) {
      finger.spread_joint = s.id(mjOBJ_JOINT, finger.name + "_spread");
      finger.spread_actuator = s.id(mjOBJ_ACTUATOR, finger.name + "_spread");
    }
  }
  const int thumb_base = s.id(mjOBJ_BODY, "thumb_base");
  s.base_x = -s.m->body_pos[3 * thumb_base];
  s.pad_distance = s.m->body_pos[3 * thumb_base + 2] + s.m->body_pos[3 * s.id(mjOBJ_BODY, "thumb_2") + 2] +
                   s.m->body_pos[3 * s.id(mjOBJ_BODY, "thumb_3") + 2] + s.m->site_pos[3 * s.id(mjOBJ_SITE, "thumb_pad") + 2];
  s.pad_radius = s.m->geom_size[3 * s.id(mjOBJ_GEOM, "thumb_3")];
  s.pad_to_end = s.m->site_pos[3 * s.id(mjOBJ_SITE, "thumb_pad") + 2];
  const int spread = s.fingers[1].spread_joint;
  s.spread_min = 2 * s.m->jnt_range[2 * spread];
  s.spread_max = 2 * s.m->jnt_range[2 * spread + 1];
  s.travel = s.m->jnt_range[2 * s.fingers[0].close_joint + 1];
}

LiftTest::~LiftTest() = default;

const TriangleMesh& LiftTest::object() const { return impl_->object; }
const std::string& LiftTest::physics_note() const { return impl_->physics_note; }
double LiftTest::simulated_s() const { return static_cast<double>(impl_->steps) * impl_->m->opt.timestep; }
long LiftTest::steps() const { return impl_->steps; }

void LiftTest::stop() { impl_->stop.store(true); }

GraspExecution LiftTest::run(const Grasp& grasp) {
  auto& s = *impl_;
  try {
    if (s.stop.load()) throw Impl::Stopped{};
    return run_steps(grasp);
  } catch (const Impl::Stopped&) {
    // Open the hand: every closing slide back to its stop, and the simulation ends there.
    for (int i = 0; i < static_cast<int>(0.2 / s.m->opt.timestep); ++i) {
      for (const auto& finger : s.fingers) s.d->ctrl[finger.close_actuator] = -s.params.finger_force;
      mj_step(s.m, s.d);
      ++s.steps;
    }
    GraspExecution result;
    result.reason = "stopped (safe state): the hand opened and the simulation ended";
    return result;
  }
}

GraspExecution LiftTest::run_steps(const Grasp& grasp) {
  auto& s = *impl_;
  mjModel* m = s.m;
  mjData* d = s.d;
  const auto& p = s.params;
  const double dt = m->opt.timestep;
  GraspExecution result;
  s.steps = 0;
  mj_resetData(m, d);

  for (const auto& c : grasp.contacts)
    if (!c.position.allFinite() || !c.normal.allFinite())
      throw std::invalid_argument("lift test: a grasp contact has a non-finite position or normal");
  if (!grasp.approach.allFinite() || grasp.approach.norm() < 1e-9)
    throw std::invalid_argument("lift test: the grasp's approach direction is zero or not finite");
  if (!std::isfinite(grasp.aperture)) throw std::invalid_argument("lift test: the grasp's aperture is not finite");

  // The palm's frame: z along the approach, x from the thumb to the fingers, y = z cross x.
  const Eigen::Vector3d a = grasp.approach.normalized();
  const Eigen::Vector3d thumb = grasp.contacts[0].position;
  const Eigen::Vector3d mid = (grasp.contacts[1].position + grasp.contacts[2].position) / 2;
  Eigen::Vector3d u = (mid - thumb) - a * a.dot(mid - thumb);
  const double width = u.norm();  // thumb to fingers, across the approach
  if (width < 1e-4) {
    result.reason = "the thumb and the fingers' contacts are not apart across the approach";
    return result;
  }
  u /= width;
  const Eigen::Vector3d y = a.cross(u);
  Eigen::Matrix3d r;
  r << u, y, a;
  // finger_a is on the palm's +y side.
  std::array<Eigen::Vector3d, 2> finger_contacts = {grasp.contacts[1].position, grasp.contacts[2].position};
  if ((finger_contacts[0] - mid).dot(y) < (finger_contacts[1] - mid).dot(y)) std::swap(finger_contacts[0], finger_contacts[1]);
  const double spread = (finger_contacts[0] - finger_contacts[1]).dot(y);
  if (spread > s.spread_max + 1e-9) {
    result.reason = "the fingers' contacts are " + format_m(spread) + " apart, beyond the hand's spread of " + format_m(s.spread_max);
    return result;
  }
  // Closer than the fingers can come: they close side by side at the smallest spread.
  const double half_spread = std::max(spread, s.spread_min) / 2;

  // The slide travel at which a pad's inner surface is half_opening from the palm's centre.
  auto travel_for = [&](double half_opening) { return s.base_x - s.pad_radius - half_opening; };
  if (travel_for(width / 2) < 0) {
    result.reason = "the contacts are " + format_m(width) + " apart across the approach, beyond the hand's opening of " +
                    format_m(2 * (s.base_x - s.pad_radius));
    return result;
  }
  const double aperture = std::max(grasp.aperture, width + 2 * p.clearance);
  const double initial_travel = std::clamp(travel_for(aperture / 2), 0.0, s.travel);
  const double depth = s.pad_distance;
  double along = 0;
  for (const auto& c : grasp.contacts) along += c.position.dot(a) / 3;
  const Eigen::Vector3d centre = u * (thumb.dot(u) + mid.dot(u)) / 2 + y * mid.dot(y) + a * along;
  Eigen::Vector3d grasp_palm = centre - a * depth;

  // The hand at the pregrasp: palm pose, fingers open, spread set.
  const Eigen::Quaterniond q(r);
  auto set_palm = [&](const Eigen::Vector3d& pos) {
    for (int k = 0; k < 3; ++k) d->mocap_pos[3 * s.mocap + k] = pos[k];
  };
  // The hand posed kinematically (no time passes): palm at pos, every finger open by travel.
  const double quat[4] = {q.w(), q.x(), q.y(), q.z()};
  auto pose_hand = [&](const Eigen::Vector3d& pos, double travel) {
    set_palm(pos);
    mjtNum* palm_qpos = d->qpos + m->jnt_qposadr[s.palm_joint];
    for (int k = 0; k < 4; ++k) d->mocap_quat[4 * s.mocap + k] = palm_qpos[3 + k] = quat[k];
    for (int k = 0; k < 3; ++k) palm_qpos[k] = pos[k];
    for (std::size_t f = 0; f < 3; ++f) {
      const auto& finger = s.fingers[f];
      d->qpos[m->jnt_qposadr[finger.close_joint]] = travel;
      for (int act : finger.phalanx_actuators) d->ctrl[act] = 0;
      if (finger.spread_joint >= 0) {
        const double offset = f == 1 ? half_spread : -half_spread;
        d->qpos[m->jnt_qposadr[finger.spread_joint]] = offset;
        d->ctrl[finger.spread_actuator] = offset;
      }
    }
    mj_forward(m, d);
  };
  // The fingers are straight, so they may touch nearer their tips than the pads: where the pads at
  // the contacts would put a fingertip on the table (a low object, such as a banana lying flat),
  // the hand stays higher, by at most what keeps the contacts on the fingers' straight part. How
  // high depends on the opening: with the approach tilted, a finger opened wider reaches lower.
  constexpr double kStep = 0.001, kMargin = 0.003;
  auto palm_at_grasp = [&](double travel) {
    for (double raise = 0; raise <= s.pad_to_end - kMargin; raise += kStep) {
      pose_hand(centre - a * (depth + raise), travel);
      if (!s.hand_touches_table()) return Eigen::Vector3d(centre - a * (depth + raise));
    }
    return grasp_palm;  // no height clears the table: the way in below names what touches it
  };

  double open_travel = initial_travel;
  // Closing slides: hold the pregrasp opening (proportional; the joints' damping damps it), or push
  // with the finger force once closing.
  bool closing = false;
  constexpr double kHoldGain = 2000;  // newtons per metre
  auto step = [&] {
    for (std::size_t f = 0; f < 3; ++f) {
      const auto& finger = s.fingers[f];
      d->ctrl[finger.close_actuator] =
          closing ? p.finger_force
                  : std::clamp(kHoldGain * (open_travel - d->qpos[m->jnt_qposadr[finger.close_joint]]), -p.finger_force,
                               p.finger_force);
    }
    if (s.stop.load()) throw Impl::Stopped{};
    mj_step(m, d);
    ++s.steps;
  };
  auto time_text = [&] { return fmt::format("t={:.2f} s", d->time); };

  // Let the object settle on the table first, the hand far back along the approach: the way in is
  // checked against the object where it rests. Checked before it settled, a banana that then
  // rolled 3 mm met the thumb on the way in.
  pose_hand(centre - a * (depth + 1.0), open_travel);
  for (int i = 0; i < static_cast<int>(0.2 / dt); ++i) step();

  // The pregrasp opening: the grasp's aperture if the way in is clear, else wider (as far as the
  // hand opens): a finger whose contact normal is far from its closing direction passes the
  // surface closer than its contact. The way in is checked at poses along it.
  std::string hit;
  bool hit_at_pregrasp = false;
  Eigen::Vector3d pregrasp_palm;
  for (;; open_travel = std::max(open_travel - 0.01, 0.0)) {
    const Eigen::Vector3d palm = palm_at_grasp(open_travel);
    pregrasp_palm = palm - a * p.pregrasp_distance;
    hit.clear();
    constexpr int kChecks = 10;
    for (int i = 0; i <= kChecks && hit.empty(); ++i) {
      pose_hand(pregrasp_palm + (palm - pregrasp_palm) * i / kChecks, open_travel);
      hit = s.hand_collision();
      hit_at_pregrasp = i == 0;
    }
    if (hit.empty()) grasp_palm = palm;
    if (hit.empty() || open_travel == 0) break;
  }
  if (!hit.empty()) {
    result.reason = (hit_at_pregrasp ? "collision at the pregrasp, even with the hand fully open: "
                                     : "no collision-free way in along the approach, even with the hand fully open: ") + hit;
    return result;
  }
  pose_hand(pregrasp_palm, open_travel);

  // Move in along the approach.
  const Eigen::Vector3d start = s.object_centre();
  const int approach_steps = static_cast<int>(std::ceil(0.5 / dt));
  for (int i = 1; i <= approach_steps; ++i) {
    set_palm(pregrasp_palm + (grasp_palm - pregrasp_palm) * smoothstep(double(i) / approach_steps));
    step();
    if (const auto hit = s.hand_collision(); !hit.empty()) {
      result.reason = "collision while moving in at " + time_text() + ": " + hit;
      return result;
    }
  }

  // Close under force control until every slide has stopped (on the object or at its limit).
  closing = true;
  const int min_close = static_cast<int>(0.15 / dt), max_close = static_cast<int>(1.5 / dt), still_needed = static_cast<int>(0.05 / dt);
  int still = 0;
  for (int i = 0; i < max_close && still < still_needed; ++i) {
    step();
    bool moving = false;
    for (const auto& finger : s.fingers) moving |= std::abs(d->qvel[m->jnt_dofadr[finger.close_joint]]) > 0.002;
    still = (moving || i < min_close) ? 0 : still + 1;
  }
  if (s.unstable()) {
    result.reason = "the simulation became unstable at " + time_text();
    return result;
  }
  result.contacts = s.object_contacts();
  if (result.contacts.empty()) {
    result.reason = "no contact with the object after closing the fingers (" + time_text() + ")";
    return result;
  }
  // The hand must have taken the planned grasp, not another one (a wide-open hand can close
  // around the whole object). Where along its length a finger touches does not matter, so the
  // distance is measured across the approach.
  const std::array<Eigen::Vector3d, 3> planned = {thumb, finger_contacts[0], finger_contacts[1]};
  for (std::size_t f = 0; f < 3; ++f) {
    double nearest = INFINITY;
    for (const auto& c : result.contacts) {
      if (c.link.rfind(s.fingers[f].name + "_", 0) != 0) continue;
      const Eigen::Vector3d off = c.position - planned[f];
      nearest = std::min(nearest, (off - a * a.dot(off)).norm());
    }
    if (nearest > p.contact_tolerance) {
      result.reason = std::isinf(nearest) ? s.fingers[f].name + " did not touch the object"
                                          : fmt::format("{} touched the object {:.3f} m (across the approach) from its planned "
                                                        "contact, more than the {:.3f} m allowed: not the planned grasp",
                                                        s.fingers[f].name, nearest, p.contact_tolerance);
      return result;
    }
  }

  // Lift straight up, then hold; the object is out of the hand once it moved drop_distance
  // relative to the palm since the fingers closed.
  auto in_palm = [&] {
    const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> palm(d->xmat + 9 * s.palm_body);
    return Eigen::Vector3d(palm.transpose() * (s.object_centre() - s.palm_position()));
  };
  const Eigen::Vector3d grasped = in_palm();
  const Eigen::Vector3d lift_start = s.wrist_position();
  auto dropped = [&](const char* phase) {
    if (s.unstable()) {
      result.reason = "the simulation became unstable at " + time_text();
      return true;
    }
    const double moved = (in_palm() - grasped).norm();
    if (moved <= p.drop_distance) return false;
    result.reason = fmt::format("dropped at {} while {} (moved {:.3f} m in the hand)", time_text(), phase, moved);
    return true;
  };
  const int lift_steps = static_cast<int>(std::ceil(p.lift_s / dt));
  bool lost = false;
  for (int i = 1; i <= lift_steps && !lost; ++i) {
    set_palm(lift_start + Eigen::Vector3d::UnitZ() * p.lift_height * smoothstep(double(i) / lift_steps));
    step();
    lost = dropped("lifting");
  }
  const Eigen::Vector3d hold_start = in_palm();
  const int hold_steps = static_cast<int>(std::llround(p.hold_s / dt));
  int held_steps = 0;
  for (; held_steps < hold_steps && !lost; ++held_steps) {
    step();
    lost = dropped("holding");
  }
  result.hold_s = (lost ? std::max(held_steps - 1, 0) : held_steps) * dt;
  result.slip_m = (in_palm() - hold_start).norm();
  result.lift_height_m = s.object_centre().z() - start.z();
  result.held = !lost && result.lift_height_m >= p.lift_height / 2;
  if (!lost && !result.held)
    result.reason = fmt::format("the object rose only {:.3f} m of the {:.3f} m lift", result.lift_height_m, p.lift_height);
  return result;
}

}  // namespace fba::sim_hand
