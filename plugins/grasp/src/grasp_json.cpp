#include "fba/grasp/grasp_json.hpp"

namespace fba::grasp {
namespace {

using nlohmann::json;

json vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

[[noreturn]] void fail(const std::string& where, const std::string& expected, const json& found) {
  std::string text = found.dump();
  if (text.size() > 80) text = text.substr(0, 77) + "...";
  throw GraspJsonError(where + ": expected " + expected + ", found " + text);
}

Eigen::Vector3d read_vec(const json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) fail(where, "an array of 3 numbers", j);
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) {
    if (!j[k].is_number()) fail(where + "[" + std::to_string(k) + "]", "a number", j[k]);
    v[k] = j[k].get<double>();
  }
  return v;
}

double read_number(const json& obj, const char* key, const std::string& where) {
  if (!obj.contains(key)) return 0.0;
  if (!obj[key].is_number()) fail(where + "." + key, "a number", obj[key]);
  return obj[key].get<double>();
}

}  // namespace

json grasp_to_json(const Grasp& g) {
  json contacts = json::array();
  for (const auto& c : g.contacts) contacts.push_back({{"position", vec(c.position)}, {"normal", vec(c.normal)}});
  return {{"contacts", contacts},
          {"approach", vec(g.approach)},
          {"spread", g.spread},
          {"aperture", g.aperture},
          {"pinch_depth", g.pinch_depth},
          {"scores",
           {{"symmetry", g.scores.symmetry},
            {"safety_margin", g.scores.safety_margin},
            {"curvature", g.scores.curvature},
            {"total", g.scores.total}}},
          {"views", g.views}};
}

Grasp grasp_from_json(const json& j, const std::string& where) {
  if (!j.is_object()) fail(where, "an object with \"contacts\"", j);
  if (!j.contains("contacts")) fail(where, "a member \"contacts\" (3 contacts, thumb first)", j);
  const json& contacts = j["contacts"];
  if (!contacts.is_array() || contacts.size() != 3)
    fail(where + ".contacts", "an array of 3 contacts (thumb first)", contacts);
  Grasp g;
  for (std::size_t i = 0; i < 3; ++i) {
    const std::string at = where + ".contacts[" + std::to_string(i) + "]";
    const json& c = contacts[i];
    if (!c.is_object() || !c.contains("position") || !c.contains("normal"))
      fail(at, "an object with \"position\" and \"normal\"", c);
    g.contacts[i] = {read_vec(c["position"], at + ".position"), read_vec(c["normal"], at + ".normal")};
  }
  if (j.contains("approach")) g.approach = read_vec(j["approach"], where + ".approach");
  g.spread = read_number(j, "spread", where);
  g.aperture = read_number(j, "aperture", where);
  g.pinch_depth = read_number(j, "pinch_depth", where);
  if (j.contains("scores")) {
    const json& s = j["scores"];
    if (!s.is_object()) fail(where + ".scores", "an object", s);
    g.scores = {read_number(s, "symmetry", where + ".scores"), read_number(s, "safety_margin", where + ".scores"),
                read_number(s, "curvature", where + ".scores"), read_number(s, "total", where + ".scores")};
  }
  if (j.contains("views")) {
    const json& v = j["views"];
    if (!v.is_array()) fail(where + ".views", "an array of view indices", v);
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (!v[k].is_number_integer()) fail(where + ".views[" + std::to_string(k) + "]", "an integer", v[k]);
      g.views.push_back(v[k].get<int>());
    }
  }
  return g;
}

}  // namespace fba::grasp
