#include "plugin_manifest.hpp"

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace fba::detail {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path manifest_path(const fs::path& plugin) {
  fs::path m = plugin;
  m.replace_extension(".manifest.json");
  return m;
}

namespace {

json value_json(const Value& v) {
  return std::visit([](const auto& x) { return json(x); }, v);
}

json port_json(const PortSpec& p, bool input) {
  json j{{"name", p.name}, {"doc", p.doc}};
  if (p.same_as.empty()) j["type"] = p.type->name;
  else j["same_as"] = p.same_as;
  if (input) j["required"] = p.required;
  return j;
}

json spec_object(const Spec& s) {
  json j{{"type", s.type_name()}, {"kind", to_string(s.kind())}, {"doc", s.doc()}};
  j["trigger"] = to_string(s.default_trigger().policy);
  if (s.default_trigger().policy == TriggerPolicy::Periodic) j["period_s"] = s.default_trigger().period_s;
  j["blocking"] = s.is_blocking();
  if (s.kind() == Kind::Actuator) j["concurrent_safe_state"] = s.has_concurrent_safe_state();
  j["inputs"] = json::array();
  for (const auto& p : s.inputs()) j["inputs"].push_back(port_json(p, true));
  j["outputs"] = json::array();
  for (const auto& p : s.outputs()) j["outputs"].push_back(port_json(p, false));
  j["params"] = json::array();
  for (const auto& p : s.params()) {
    json pj{{"name", p.name}, {"type", to_string(p.type)}, {"required", p.required()}, {"doc", p.doc}};
    if (p.default_value) pj["default"] = value_json(*p.default_value);
    if (p.min) pj["min"] = *p.min;
    if (p.max) pj["max"] = *p.max;
    if (!p.choices.empty()) pj["choices"] = p.choices;
    j["params"].push_back(pj);
  }
  j["events"] = json::array();
  for (const auto& e : s.events()) j["events"].push_back({{"name", e.name}, {"doc", e.doc}});
  if (!s.stage_names().empty()) {
    j["stages"] = s.stage_names();
    json tr = json::array();
    for (const auto& [a, b] : s.transitions()) tr.push_back({a, b});
    j["transitions"] = tr;
  }
  return j;
}

// Field access that says which field of which file is wrong.
struct Fields {
  const json& j;
  const std::string& where;
  const json& at(const char* key, json::value_t type, const char* expected) const {
    if (!j.is_object() || !j.contains(key)) throw std::runtime_error(where + ": the field '" + key + "' is missing");
    const json& v = j.at(key);
    const bool ok = v.type() == type || (type == json::value_t::number_unsigned && v.type() == json::value_t::number_integer && v.get<std::int64_t>() >= 0);
    if (!ok) throw std::runtime_error(where + ": the field '" + key + "' must be " + expected + ", found " + v.dump());
    return v;
  }
  std::string str(const char* key) const { return at(key, json::value_t::string, "a string").get<std::string>(); }
  std::uint64_t num(const char* key) const { return at(key, json::value_t::number_unsigned, "a whole number >= 0").get<std::uint64_t>(); }
  const json& arr(const char* key) const { return at(key, json::value_t::array, "a list"); }
};

}  // namespace

std::string spec_json(const Spec& spec) { return spec_object(spec).dump(); }

std::vector<ManifestDataType> data_types_of(const Spec& spec) {
  std::vector<ManifestDataType> out;
  std::set<std::string> seen;
  auto add = [&](const std::vector<PortSpec>& ports) {
    for (const auto& p : ports) {
      if (!p.same_as.empty() || !p.type || p.type == any_type() || !seen.insert(p.type->name).second) continue;
      out.push_back({p.type->name, p.type->doc, p.type->header, p.type->layout});
    }
  };
  add(spec.inputs());
  add(spec.outputs());
  return out;
}

std::string manifest_json(const Manifest& m) {
  json j{{"fba_plugin_manifest", kManifestFormat}, {"magic", m.magic}, {"abi_version", m.abi_version},
         {"fba_version", m.fba_version}, {"build_abi", m.build_abi}, {"name", m.name}, {"build_id", m.build_id}};
  j["types"] = json::array();
  for (const auto& t : m.types) j["types"].push_back(json::parse(t.interface));
  j["data_types"] = json::array();
  for (const auto& d : m.data_types)
    j["data_types"].push_back({{"name", d.name}, {"doc", d.doc}, {"header", d.header}, {"size", d.layout.size},
                               {"align", d.layout.align}, {"version", d.layout.version}});
  return j.dump(2) + "\n";
}

Manifest read_manifest(const fs::path& file) {
  const std::string where = "its manifest " + file.string();
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(where + " cannot be read");
  std::stringstream ss;
  ss << in.rdbuf();
  json j;
  try {
    j = json::parse(ss.str());
  } catch (const json::parse_error& e) {
    throw std::runtime_error(where + " is not valid JSON (" + e.what() + "): rebuild the plugin to rewrite it");
  }
  const Fields f{j, where};
  if (f.num("fba_plugin_manifest") != kManifestFormat)
    throw std::runtime_error(where + " has manifest format " + j["fba_plugin_manifest"].dump() + "; this fba reads format " +
                             std::to_string(kManifestFormat) + ": rebuild the plugin against this fba");
  Manifest m;
  m.magic = static_cast<std::uint32_t>(f.num("magic"));
  m.abi_version = static_cast<std::uint32_t>(f.num("abi_version"));
  m.fba_version = f.str("fba_version");
  m.build_abi = f.str("build_abi");
  m.name = f.str("name");
  m.build_id = f.str("build_id");
  for (const auto& t : f.arr("types")) {
    const Fields tf{t, where + ": a component type"};
    m.types.push_back({tf.str("type"), tf.str("kind"), t.dump()});
  }
  for (const auto& d : f.arr("data_types")) {
    const Fields df{d, where + ": a data type"};
    ManifestDataType dt{df.str("name"), df.str("doc"), df.str("header"), {}};
    dt.layout = TypeLayout{df.num("size"), df.num("align"), static_cast<unsigned>(df.num("version"))};
    m.data_types.push_back(std::move(dt));
  }
  return m;
}

}  // namespace fba::detail
