// The task's and its profile's parameters, and the profile: which profile binds the task's device
// slots (--profile, else the task's `profile:`), the parameters both declare with their values
// (--set, else their defaults) that ${name} stands for in the task and the profile, where each
// is used (what a --set of a component parameter means depends on it), and that the profile binds
// the task's slots and nothing else. Apart from expansion because it runs before it: these values
// are what the task's components are expanded with.
#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "loader.hpp"

namespace fba::loader {

namespace {

// A task's or a profile's parameter: a name, or names joined by dots that group parameters under
// one (`scene.mesh`, `scene.yaw`: set as --set scene.mesh=...).
bool is_valid_param_name(std::string_view name) {
  for (std::size_t begin = 0;;) {
    const std::size_t dot = name.find('.', begin);
    if (!is_valid_name(name.substr(begin, dot == std::string_view::npos ? dot : dot - begin))) return false;
    if (dot == std::string_view::npos) return true;
    begin = dot + 1;
  }
}

}  // namespace

std::vector<std::string> Loader::available_profiles(const fs::path& task_dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(task_dir / "profiles", ec), end; !ec && it != end; it.increment(ec))
    if (it->path().extension() == ".yaml") names.push_back(it->path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::string> Loader::slot_names(const YAML::Node& comps) {
  std::vector<std::string> slots;
  if (comps && comps.IsMap())
    for (auto it = comps.begin(); it != comps.end(); ++it)
      if (it->first.IsScalar() && it->second.IsMap() && it->second["profile"]) slots.push_back(it->first.Scalar());
  return slots;
}

void Loader::read_executor(const YAML::Node& n, const Source& src, TaskConfig& task) {
  const std::string e = scalar(n, src, "the executor");
  if (e == "threaded") task.executor = ExecutorKind::Threaded;
  else if (e == "deterministic") task.executor = ExecutorKind::Deterministic;
  else error(at(src, n), "executor '" + e + "' is not one of: threaded, deterministic");
}

void Loader::load_profile(const YAML::Node& root, const Source& src, TaskConfig& task) {
  std::string name = profile_option_;
  Location where{"--profile " + name, 0, 0};
  fs::path base = fs::current_path();  // a path on the command line means what the shell means
  std::string shown_base;
  const auto available = available_profiles(src.dir);
  const bool from_file = name.empty() && !profile_given_ && root["profile"];
  if (from_file) {
    name = scalar(root["profile"], src, "profile");
    where = at(src, root["profile"]);
    base = src.dir;
    shown_base = fs::path(src.shown).parent_path().string();
  }
  // An empty name is a mistake (an unset shell variable), not a request for the default profile.
  if (name.empty() && (profile_given_ || (from_file && root["profile"].IsScalar()))) {
    error(from_file ? where : Location{"--profile ''", 0, 0},
          std::string(from_file ? "'profile:'" : "--profile") + " expects a profile's name (profiles/NAME.yaml beside the task) or a file; "
          "found an empty name; profiles next to the task: " + list_of(available));
    return;
  }
  const auto slots = slot_names(root["components"]);
  if (name.empty()) {
    if (!slots.empty())
      error(at(src, root["components"]), "the task has device slots (" + list_of(slots) +
                                             ") and no profile binds them; choose one with --profile NAME or 'profile: NAME' in the task; "
                                             "profiles next to the task: " + list_of(available));
    return;
  }
  const bool is_path = name.find('/') != std::string::npos || fs::path(name).extension() == ".yaml";
  const fs::path path = is_path ? (base / name).lexically_normal() : src.dir / "profiles" / (name + ".yaml");
  const std::string shown = is_path ? (shown_base.empty() ? fs::path(name) : fs::path(shown_base) / name).lexically_normal().string()
                                    : (fs::path(src.shown).parent_path() / "profiles" / (name + ".yaml")).string();
  std::string problem;
  const std::string text = read_text(path, problem);
  if (!problem.empty()) {
    error(where, "profile '" + name + "': the file " + problem + " (looked for " + path.string() + "); profiles next to the task: " +
                     list_of(available));
    return;
  }
  const Source psrc{shown, path.parent_path(), true, "the profile file"};
  std::vector<Diagnostic> parse_errors;
  const auto doc = parse_yaml(text, shown, parse_errors);
  for (auto& x : parse_errors) error(x.where, x.message);
  if (!doc) return;
  if (!doc->IsMap()) {
    error(Location{shown, 1, 1}, std::string("a profile is a mapping with the keys profile, doc, executor, params, components; found ") + node_kind(*doc));
    return;
  }
  report_mappings(*doc, psrc);
  check_keys(*doc, psrc, {"profile", "doc", "executor", "params", "components"});
  // The devices a profile binds decide whether a virtual clock is valid (simulated ones: it is),
  // so its executor overrides the task file's; --executor overrides both.
  if (auto n = (*doc)["executor"]) read_executor(n, psrc, task);
  const YAML::Node comps = (*doc)["components"];
  if (comps && !comps.IsMap()) {
    error(at(psrc, comps), std::string("components of a profile: a mapping slot: {type: ..., params: ...}; found ") + node_kind(comps));
    return;
  }
  profile_.loaded = true;
  profile_.name = (*doc)["profile"] ? scalar((*doc)["profile"], psrc, "the profile's name") : name;
  profile_.src = psrc;
  profile_.root = *doc;
  profile_.components = comps;
  task.profile = profile_.name;
  task.profile_file = path;
}

std::optional<std::pair<YAML::Node, YAML::Node>> Loader::profile_entry(const std::string& slot) const {
  if (!profile_.loaded || !profile_.components || !profile_.components.IsMap()) return std::nullopt;
  for (auto it = profile_.components.begin(); it != profile_.components.end(); ++it)
    if (it->first.IsScalar() && it->first.Scalar() == slot) return std::make_pair(YAML::Node(it->first), YAML::Node(it->second));
  return std::nullopt;
}

Bindings Loader::task_params(const YAML::Node& root, const Source& src, TaskConfig& task) {
  std::vector<Diagnostic> d;
  auto decls = param_decls(root["params"], src, "a task", true, d);
  const std::size_t from_task = decls.size();
  if (profile_.loaded)
    for (auto& x : param_decls(std::as_const(profile_.root)["params"], profile_.src, "a profile", true, d)) decls.push_back(std::move(x));
  for (auto& x : d) error(x.where, x.message);
  for (const YAML::Node& params : {root["params"], profile_.loaded ? std::as_const(profile_.root)["params"] : YAML::Node()})
    if (params && params.IsMap())
      for (auto it = params.begin(); it != params.end(); ++it)
        if (it->first.IsScalar() && std::none_of(decls.begin(), decls.end(), [&](const auto& x) { return x.first.name == it->first.Scalar(); }))
          failed_params_.insert(it->first.Scalar());  // a declaration with errors (reported)
  std::set<std::string> names_declared;
  for (const auto& [ps, _] : decls) names_declared.insert(ps.name);
  collect_uses(root, src, names_declared);
  if (profile_.loaded) collect_uses(profile_.root, profile_.src, names_declared);
  Bindings b;
  std::map<std::string, Location> declared;
  for (std::size_t i = 0; i < decls.size(); ++i) {
    const auto& [ps, where] = decls[i];
    if (auto [first, fresh] = declared.emplace(ps.name, where); !fresh) {
      error(where, "parameter '" + ps.name + "' is declared by the task already (at " + first->second.str() +
                       "); a profile's parameters add to the task's, under names of their own");
      continue;
    }
    // --set group.name=... must mean this parameter and nothing else.
    if (const auto dot = ps.name.rfind('.'); dot != std::string::npos && root["components"] && root["components"].IsMap() &&
                                             root["components"][ps.name.substr(0, dot)]) {
      error(where, "parameter '" + ps.name + "' has the form of component '" + ps.name.substr(0, dot) + "''s parameter '" +
                       ps.name.substr(dot + 1) + "', and --set " + ps.name + "=... could mean either; name its group apart from the components");
      failed_params_.insert(ps.name);
      continue;
    }
    TaskParam tp{ps.name, ps.type, {}, i < from_task ? "default" : "profile default", ps.doc, where};
    if (const SetOption* o = overrides_.for_task_param(ps.name)) {
      const std::size_t before = diags_.size();
      const auto v = set_value(*o, ps);
      for (std::size_t k = before; k < diags_.size(); ++k)
        diags_[k].message += " (" + (o->target == ps.name ? "" : o->target + " is ${" + ps.name + "}, ") + "declared at " + where.str() + ")";
      if (!v) {
        failed_params_.insert(ps.name);
        continue;
      }
      tp.value = *v;
      // Set through the component parameter that is its only use: said, as that is what was typed.
      tp.source = o->target == ps.name ? "--set" : "--set " + o->target;
    } else if (ps.default_value) {
      tp.value = *ps.default_value;
    } else {
      error(where, "task parameter '" + ps.name + "' has no default; set it with --set " + ps.name + "=VALUE");
      failed_params_.insert(ps.name);
      continue;
    }
    b[ps.name] = tp.value;
    task.params.push_back(std::move(tp));
  }
  std::vector<std::string> names;
  for (const auto& [n, _] : declared) names.push_back(n);
  for (const SetOption* o : overrides_.unused())
    if (o->owner.empty()) {
      overrides_.mark_used(*o);
      error(o->where(), "--set " + o->target + ": the task has no parameter '" + o->target + "'; its parameters: " + list_of(names) +
                            " (a component's parameter is set with --set component.parameter=value)");
    }
  return b;
}

std::optional<Value> Loader::set_value(const SetOption& o, const ParamSpec& ps) {
  const Source cli{o.where().file, fs::current_path(), false, "the working folder"};
  if (taken_as_written(ps.type)) return param_value(ps, YAML::Node(o.value), cli, {});
  std::vector<Diagnostic> d;
  const auto node = parse_yaml(o.value, cli.shown, d);
  for (const auto& x : d) error(o.where(), "the value is not valid YAML: " + x.message);
  if (!node) return std::nullopt;
  report_mappings(*node, cli);
  return param_value(ps, *node, cli, {});
}

void Loader::collect_uses(const YAML::Node& root, const Source& src, const std::set<std::string>& declared) {
  std::set<std::tuple<int, int, bool>> seen;
  if (const YAML::Node comps = root["components"]; comps && comps.IsMap())
    for (auto c = comps.begin(); c != comps.end(); ++c) {
      if (!c->first.IsScalar() || !c->second.IsMap()) continue;
      for (auto k = c->second.begin(); k != c->second.end(); ++k) {
        if (!k->first.IsScalar()) continue;
        if (k->first.Scalar() != "params" || !k->second.IsMap()) {
          note_uses(k->second, src, k->first.Scalar(), declared, seen);
          continue;
        }
        for (auto p = k->second.begin(); p != k->second.end(); ++p)
          if (p->first.IsScalar() && p->second.IsScalar())
            note_uses(p->second, src, c->first.Scalar() + "." + p->first.Scalar(), declared, seen, true);
      }
    }
  if (const YAML::Node conns = root["connections"]) note_uses(conns, src, "a connection", declared, seen);
}

void Loader::note_uses(const YAML::Node& n, const Source& src, const std::string& what, const std::set<std::string>& declared,
               std::set<std::tuple<int, int, bool>>& seen, bool component_param) {
  if (n.IsScalar()) {
    const auto refs = references_in(n.Scalar());
    ParamUse u{what, component_param, n.Scalar(), at(src, n), {}, refs.size() == 1 && refs[0].len == n.Scalar().size()};
    for (const auto& r : refs)
      if (declared.count(r.name)) u.names.push_back(r.name);
    if (!u.names.empty()) overrides_.add_use(std::move(u));
    return;
  }
  // Walked once per node, as an alias can multiply a tree.
  if (!(n.IsMap() || n.IsSequence()) || !seen.insert({n.Mark().line, n.Mark().column, n.IsMap()}).second) return;
  if (n.IsSequence())
    for (const auto& e : n) note_uses(e, src, what, declared, seen);
  else
    for (auto it = n.begin(); it != n.end(); ++it) note_uses(it->second, src, it->first.IsScalar() ? it->first.Scalar() : what, declared, seen);
}

void Loader::check_profile_bindings(const YAML::Node& root, const Source& src, const TaskConfig& task) {
  if (!profile_.loaded || !profile_.components) return;
  const YAML::Node comps = root["components"];
  const auto slots = slot_names(comps);
  for (auto it = profile_.components.begin(); it != profile_.components.end(); ++it) {
    if (!it->first.IsScalar()) continue;
    const std::string name = it->first.Scalar();
    if (std::find(slots.begin(), slots.end(), name) != slots.end()) continue;
    const Location comps_at = comps ? at(src, comps) : Location{src.shown, 0, 0};
    std::optional<Location> own;
    if (comps && comps.IsMap())
      for (auto c = comps.begin(); c != comps.end(); ++c)
        if (c->first.IsScalar() && c->first.Scalar() == name) own = at(src, c->first);
    error(at(profile_.src, it->first),
          "profile '" + task.profile + "' binds '" + name + "', which is not a device slot of the task (" + src.shown + ")" +
              (own ? ": the task defines it itself at " + own->str() : "; the task's components are at " + comps_at.str()) +
              "; its slots: " + list_of(slots));
  }
}

std::vector<std::pair<ParamSpec, Location>> Loader::param_decls(const YAML::Node& params, const Source& src, const std::string& owner,
                                                        bool grouped, std::vector<Diagnostic>& d) {
  std::vector<std::pair<ParamSpec, Location>> out;
  if (!params) return out;
  auto err = [&](const YAML::Node& n, std::string m) { d.push_back(Diagnostic{at(src, n), std::move(m)}); };
  if (!params.IsMap()) {
    err(params, "params of " + owner + ": a mapping name: {type, default, doc}; found " + node_kind(params));
    return out;
  }
  for (auto it = params.begin(); it != params.end(); ++it) {
    const std::string pname = it->first.IsScalar() ? it->first.Scalar() : "";
    const YAML::Node p = it->second;
    if (grouped ? !is_valid_param_name(pname) : !is_valid_name(pname))
      err(it->first, "parameter name '" + pname + "' must be letters, digits and '_'" +
                         std::string(grouped ? " (words joined by '.' make a group: scene.mesh)" : ""));
    if (!p.IsMap() || !p["type"] || !p["type"].IsScalar()) {
      err(p, "parameter '" + pname + "' needs {type: bool|int|double|string|path|list, default: ..., doc: ...}");
      continue;
    }
    for (auto k = p.begin(); k != p.end(); ++k)
      if (const std::string key = k->first.IsScalar() ? k->first.Scalar() : "?";
          key != "type" && key != "default" && key != "min" && key != "max" && key != "doc")
        err(k->first, "parameter '" + pname + "': unknown key '" + key + "'; valid keys: type, default, min, max, doc");
    static const std::map<std::string, ParamType> types{{"bool", ParamType::Bool}, {"int", ParamType::Int}, {"double", ParamType::Double},
                                                        {"string", ParamType::String}, {"path", ParamType::Path}, {"list", ParamType::DoubleList}};
    auto t = types.find(p["type"].Scalar());
    if (t == types.end()) {
      err(p["type"], "parameter type '" + p["type"].Scalar() + "' is not one of: bool, int, double, string, path, list");
      continue;
    }
    ParamSpec ps;
    ps.name = pname;
    ps.type = t->second;
    for (const char* bound : {"min", "max"}) {
      const YAML::Node b = p[bound];
      if (!b) continue;
      if (ps.type != ParamType::Int && ps.type != ParamType::Double && ps.type != ParamType::DoubleList) {
        err(b, std::string(bound) + " applies to int and double parameters (and to every number of a list); '" + pname + "' is a " +
                   to_string(ps.type) + " parameter");
        continue;
      }
      double x = 0;
      if (!b.IsScalar() || !parse_double(b.Scalar(), x)) {
        err(b, "parameter '" + pname + "': " + bound + " must be a finite number; found " +
                   (b.IsScalar() ? "'" + b.Scalar() + "'" : std::string(node_kind(b))));
        continue;
      }
      (std::string(bound) == "min" ? ps.min : ps.max) = x;
    }
    if (p["doc"] && p["doc"].IsScalar()) ps.doc = p["doc"].Scalar();
    if (p["default"]) {
      auto v = check_param_value(ps, written_value(p["default"]), PathBase{src.dir, src.base});
      if (!v.value) {
        d.push_back(Diagnostic{at(src, p["default"]), std::move(v.error)});
        continue;  // reported; without it every use would be reported as well
      }
      ps.default_value = std::move(*v.value);
    }
    out.emplace_back(std::move(ps), at(src, it->first));
  }
  return out;
}

}  // namespace fba::loader
