// Include and composite expansion: the composites a task includes read into types of its own
// (their interface checked against their inner components), then the task's components expanded,
// each composite instance into its inner components named instance/inner with ${name} bound to
// the instance's parameters, each component's parameters read against its type's spec (the
// values checked by param_checking.cpp); and the composite files fba-run and the registry read.
// Apart from the pipeline and the checks because it is where the task's shape is decided: what
// comes out is the flat list of components that the graph checks then see.
#include <algorithm>
#include <memory>
#include <set>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "loader.hpp"

namespace fba {

namespace loader {

WrittenValue written_value(const YAML::Node& n) {
  WrittenValue v;
  switch (n.Type()) {
    case YAML::NodeType::Scalar:
      v.text = n.Scalar();
      break;
    case YAML::NodeType::Sequence:
      v.kind = WrittenValue::Kind::List;
      v.elements.reserve(n.size());
      for (const auto& e : n) {
        WrittenValue& element = v.elements.emplace_back();
        if (e.IsScalar()) element.text = e.Scalar();
        else element.kind = e.IsSequence() ? WrittenValue::Kind::List : e.IsMap() ? WrittenValue::Kind::Mapping
                                           : e.IsNull() ? WrittenValue::Kind::Nothing : WrittenValue::Kind::Undefined;
      }
      break;
    case YAML::NodeType::Map: v.kind = WrittenValue::Kind::Mapping; break;
    case YAML::NodeType::Null: v.kind = WrittenValue::Kind::Nothing; break;
    default: v.kind = WrittenValue::Kind::Undefined; break;
  }
  return v;
}

std::shared_ptr<const TypeEntry> Loader::find_type(const std::string& name) const {
  if (auto it = local_types_.find(name); it != local_types_.end()) return it->second;
  return registry_.find(name);
}

std::vector<std::string> Loader::suggest(const std::string& name) const {
  auto s = registry_.closest(name);
  for (const auto& [n, _] : local_types_) s.push_back(n);
  return s;
}

bool Loader::load_includes(const YAML::Node& root, const Source& src, std::set<std::string>& stack) {
  const YAML::Node inc = root["include"];
  if (!inc) return true;
  bool acyclic = true;
  std::vector<YAML::Node> items;
  if (inc.IsScalar()) items.push_back(inc);
  else if (inc.IsSequence()) for (const auto& i : inc) items.push_back(i);
  else {
    error(at(src, inc), std::string("include takes a file name or a list of them; found ") + node_kind(inc));
    return true;
  }
  for (const auto& item : items) {
    const std::string rel = scalar(item, src, "an include");
    if (rel.empty()) {
      if (item.IsScalar()) error(at(src, item), "an include names a composite file, relative to this file's folder; found an empty name");
      continue;
    }
    const fs::path path = (src.dir / rel).lexically_normal();
    std::string problem;
    const std::string text = read_text(path, problem);
    if (!problem.empty()) {
      error(at(src, item), "included file '" + rel + "' " + problem + " (looked for " + path.string() + ")");
      continue;
    }
    std::error_code ec;
    const std::string key = fs::weakly_canonical(path, ec).string();
    if (stack.count(key)) {
      error(at(src, item), "include cycle: '" + rel + "' includes itself, directly or through other files");
      acyclic = false;
      continue;
    }
    if (included_.count(key)) continue;
    included_.insert(key);
    const Source inner{(src.dir / rel).lexically_normal().string(), path.parent_path()};
    std::vector<Diagnostic> parse_errors;
    const auto parsed = parse_yaml(text, inner.shown, parse_errors);
    for (auto& x : parse_errors) error(x.where, x.message);
    if (!parsed) continue;
    const YAML::Node doc = *parsed;
    report_mappings(doc, inner);
    if (!doc.IsMap() || !doc["composite"]) {
      error(at(src, item), "included file '" + rel + "' is not a composite definition (a mapping with 'composite: name')");
      continue;
    }
    stack.insert(key);
    const bool inner_acyclic = load_includes(doc, inner, stack);
    stack.erase(key);
    if (!inner_acyclic) {
      if (doc["composite"].IsScalar()) broken_types_.insert(doc["composite"].Scalar());
      acyclic = false;
      continue;
    }
    auto def = std::make_shared<CompositeDef>(CompositeDef{path, inner.shown, doc});
    const std::size_t before = diags_.size();
    Spec spec = composite_spec_checked(*def);
    if (diags_.size() != before) {
      broken_types_.insert(spec.type_name());
      continue;
    }
    const std::string name = spec.type_name();
    if (find_type(name)) {
      const auto other = find_type(name);
      error(at(inner, doc["composite"]), "component type '" + name + "' is defined already by " + other->origin);
      continue;
    }
    local_types_.emplace(name, std::make_shared<const TypeEntry>(TypeEntry{std::move(spec), nullptr, def, nullptr, inner.shown}));
  }
  return acyclic;
}

Spec Loader::composite_spec_checked(const CompositeDef& def) {
  std::vector<Diagnostic> d;
  Spec s = composite_spec_impl(def, d);
  for (auto& x : d) error(x.where, x.message);
  return s;
}

Spec Loader::composite_spec_impl(const CompositeDef& def, std::vector<Diagnostic>& d) {
  const Source src{def.shown, def.file.parent_path()};
  const YAML::Node& root = def.root;
  auto err = [&](const YAML::Node& n, std::string m) { d.push_back(Diagnostic{at(src, n), std::move(m)}); };
  const std::vector<std::string> keys{"composite", "doc", "include", "params", "inputs", "outputs", "events", "components", "connections", "on"};
  for (auto it = root.begin(); it != root.end(); ++it)
    if (!it->first.IsScalar() || std::find(keys.begin(), keys.end(), it->first.Scalar()) == keys.end())
      err(it->first, "unknown key '" + (it->first.IsScalar() ? it->first.Scalar() : std::string("?")) + "' in a composite; valid keys: " + list_of(keys));
  const YAML::Node name = root["composite"];
  std::string type_name = name && name.IsScalar() ? name.Scalar() : "";
  if (type_name.empty()) err(name ? name : root, "'composite:' needs the composite's type name");
  Spec spec = Spec::composite(type_name.empty() ? "invalid" : type_name, root["doc"] && root["doc"].IsScalar() ? root["doc"].Scalar() : "");
  for (const auto& [ps, _] : param_decls(root["params"], src, "a composite", false, d)) {
    spec.param(ps.name, ps.type, ps.default_value, ps.doc);
    if (ps.min || ps.max) spec.range(ps.min, ps.max);
  }
  const YAML::Node comps = root["components"];
  auto inner_port = [&](const YAML::Node& n, bool input) -> const PortSpec* {
    const std::string target = n.Scalar();
    const auto dot = target.find('.');
    if (dot == std::string::npos) { err(n, "expected component.port, found '" + target + "'"); return nullptr; }
    const std::string comp = target.substr(0, dot), port = target.substr(dot + 1);
    if (!comps || !comps.IsMap() || !comps[comp]) { err(n, "the composite has no component '" + comp + "'"); return nullptr; }
    const YAML::Node type = comps[comp]["type"];
    const auto te = type && type.IsScalar() ? find_type(type.Scalar()) : nullptr;
    if (!te && type && type.IsScalar() && broken_types_.count(type.Scalar())) return nullptr;  // its errors are reported
    if (!te && type && type.IsScalar() && type.Scalar() == type_name) {
      err(n, "composite '" + type_name + "' contains itself (as its component '" + comp + "')");
      return nullptr;
    }
    if (!te) {
      err(n, "component '" + comp + "' has " + (type && type.IsScalar() ? "an unknown type '" + type.Scalar() + "'" : std::string("no type")));
      return nullptr;
    }
    const PortSpec* ps = input ? te->spec.find_input(port) : te->spec.find_output(port);
    if (!ps) err(n, "component '" + comp + "' (" + te->spec.type_name() + ") has no " + (input ? "input" : "output") + " '" + port +
                        "'; it has: " + list_of(names_of(input ? te->spec.inputs() : te->spec.outputs())));
    return ps;
  };
  for (const char* section : {"inputs", "outputs"}) {
    const bool input = std::string(section) == "inputs";
    const YAML::Node ports = root[section];
    if (!ports) continue;
    if (!ports.IsMap()) { err(ports, std::string(section) + " of a composite: a mapping name: inner_component.port"); continue; }
    for (auto it = ports.begin(); it != ports.end(); ++it) {
      const std::string pname = it->first.Scalar();
      YAML::Node target;
      target.reset(it->second);
      std::string doc;
      if (it->second.IsMap()) {
        doc = it->second["doc"] && it->second["doc"].IsScalar() ? it->second["doc"].Scalar() : "";
        // reset() throws on a missing key; a null target is reported below.
        const YAML::Node inner = it->second[input ? "to" : "from"];
        target.reset(inner ? inner : YAML::Node());
      }
      if (!target || !target.IsScalar()) { err(it->second, "exported port '" + pname + "' needs inner_component.port"); continue; }
      const PortSpec* ps = inner_port(target, input);
      if (!ps) continue;
      const TypeInfo* t = ps->same_as.empty() ? ps->type : any_type();
      if (input) spec.input(pname, t, doc.empty() ? ps->doc : doc);
      else spec.output(pname, t, doc.empty() ? ps->doc : doc);
      if (input) {
        // The composite's input is as optional as what it leads to.
        const_cast<PortSpec&>(spec.inputs().back()).required = ps->required;
      }
    }
  }
  if (const YAML::Node events = root["events"]; events && events.IsMap())
    for (auto it = events.begin(); it != events.end(); ++it) spec.event(it->first.Scalar(), "exported from " + (it->second.IsScalar() ? it->second.Scalar() : std::string("?")));
  return spec;
}

Spec Loader::composite_spec_public(const CompositeDef& def, std::vector<Diagnostic>& d) { return composite_spec_impl(def, d); }

std::string Loader::unknown_reference(const std::string& name, const Bindings& b) const {
  std::vector<std::string> known;
  for (const auto& [k, _] : b) known.push_back(k);
  return std::string("unknown ") + (&b == task_bindings_ ? "task" : "composite") + " parameter '${" + name +
         "}'; the parameters here: " + list_of(known);
}

std::optional<YAML::Node> Loader::substitute(const YAML::Node& n, const Bindings& b, const Source& src, bool& whole, Value& whole_value) {
  whole = false;
  if (!n.IsScalar() || b.empty()) return n;
  const std::string s = n.Scalar();
  const std::vector<Reference> refs = references_in(s);
  if (refs.size() == 1 && refs[0].len == s.size()) {
    auto it = b.find(refs[0].name);
    if (it == b.end()) {
      if (!failed_params_.count(refs[0].name)) error(at(src, n), unknown_reference(refs[0].name, b), false);
      return std::nullopt;
    }
    whole = true;
    whole_value = it->second;
    return n;
  }
  std::string out;
  std::size_t begin = 0;
  bool unknown = false;
  for (const auto& r : refs) {
    out.append(s, begin, r.pos - begin);
    auto it = b.find(r.name);
    if (it == b.end()) {
      if (!failed_params_.count(r.name)) error(at(src, n), unknown_reference(r.name, b), false);
      unknown = true;
    } else {
      out += to_string(it->second);
    }
    begin = r.pos + r.len;
  }
  if (unknown) return std::nullopt;
  if (refs.empty()) return n;
  out.append(s, begin);
  YAML::Node copy(out);
  return copy;
}

std::optional<YAML::Node> Loader::substituted(const YAML::Node& n, const Bindings& b, const Source& src) {
  bool whole = false;
  Value bound;
  auto v = substitute(n, b, src, whole, bound);
  if (v && whole) return YAML::Node(to_string(bound));
  return v;
}

std::string Loader::text_of(const YAML::Node& n, const Bindings& b, const Source& src, const std::string& what) {
  const auto v = substituted(n, b, src);
  if (!v) return {};
  if (!v->IsScalar()) {
    error(at(src, n), what + " must be a scalar; found " + node_kind(*v));
    return {};
  }
  return v->Scalar();
}

std::optional<Value> Loader::param_value(const ParamSpec& ps, const YAML::Node& raw, const Source& src, const Bindings& bindings) {
  bool whole = false;
  Value bound;
  const auto substituted = substitute(raw, bindings, src, whole, bound);
  if (!substituted) return std::nullopt;
  ParamCheck checked = whole ? check_bound_value(ps, std::move(bound))
                             : check_param_value(ps, written_value(*substituted), PathBase{src.dir, src.base});
  if (!checked.value) error(at(src, raw), std::move(checked.error));
  return std::move(checked.value);
}

std::map<std::string, Value> Loader::read_params(const std::string& full, const Spec& spec, const YAML::Node& params, const Source& src,
                                         const Bindings& bindings, const Location& comp_where) {
  std::map<std::string, Value> out;
  std::set<std::string> given;
  if (params && !params.IsMap() && !params.IsNull()) error(at(src, params), std::string("params: a mapping name: value; found ") + node_kind(params));
  if (params && params.IsMap()) {
    for (auto it = params.begin(); it != params.end(); ++it) {
      const std::string name = it->first.IsScalar() ? it->first.Scalar() : "";
      const ParamSpec* ps = spec.find_param(name);
      if (!ps) {
        error(at(src, it->first), "component '" + full + "' (" + spec.type_name() + ") has no parameter '" + name +
                                      "'; its parameters: " + list_of(names_of(spec.params())));
        continue;
      }
      if (!given.insert(name).second) continue;  // a duplicate key: reported with both places by check_mappings
      if (auto v = param_value(*ps, it->second, src, bindings)) out[name] = *v;
    }
  }
  for (const auto& ps : spec.params()) {
    const auto set = overrides_.for_component_param(full + "." + ps.name);
    if (!set.refusal.empty()) error(set.option->where(), set.refusal);
    if (set.apply) {
      if (auto v = set_value(*set.option, ps)) out[ps.name] = *v;
      given.insert(ps.name);
    }
    if (given.count(ps.name)) continue;
    if (ps.default_value) out[ps.name] = *ps.default_value;
    else error(comp_where, "component '" + full + "' (" + spec.type_name() + ") needs parameter '" + ps.name + "' (" + to_string(ps.type) + ": " + ps.doc + ")");
  }
  return out;
}

void Loader::check_params(const ComponentConfig& cc, const YAML::Node& params, const Source& src) {
  if (cc.params.size() != cc.type->spec.params().size()) return;  // a value is missing: reported already
  std::vector<Spec::Problem> problems;
  try {
    problems = cc.type->spec.check_params(cc.params, cc.type->origin);
  } catch (const PluginBug& e) {
    error(Location{cc.type->origin, 0, 0}, e.what());
  }
  for (const auto& p : problems) {
    const YAML::Node given = !p.param.empty() && params && params.IsMap() ? params[p.param] : YAML::Node();
    error(given ? at(src, given) : cc.where, "component '" + cc.name + "' (" + cc.type->spec.type_name() + "): " + p.message);
  }
}

void Loader::read_component(const std::string& name, const std::string& full, const YAML::Node& c, const Source& src, const Location& where,
                    const Bindings& bindings, TaskConfig& task, const std::vector<std::string>& composite_stack) {
  auto reject = [&](const Location& place, const std::string& message) {
    error(place, message);
    kinds_[full] = nullptr;
  };
  if (!c.IsMap()) {
    reject(at(src, c), "component '" + name + "': a mapping {type: ..., params: ...}; found " + node_kind(c));
    return;
  }
  check_keys(c, src, {"type", "params", "trigger", "on_error", "thread", "doc"});
  const YAML::Node type = c["type"];
  if (!type || !type.IsScalar()) {
    reject(where, "component '" + name + "' needs 'type:' (see fba-inspect for the types available)");
    return;
  }
  const auto te = find_type(type.Scalar());
  if (!te && broken_types_.count(type.Scalar())) {
    kinds_[full] = nullptr;  // the composite's definition has its errors reported
    return;
  }
  if (!te) {
    const auto near = suggest(type.Scalar());
    reject(at(src, type), "unknown component type '" + type.Scalar() + "'" +
                              (near.empty() ? std::string("") : "; did you mean " + list_of(near) + "?") +
                              " (fba-inspect lists the types found; --plugin-path adds plugin folders)");
    return;
  }
  kinds_[full] = &te->spec;
  if (te->composite) {
    if (std::find(composite_stack.begin(), composite_stack.end(), te->spec.type_name()) != composite_stack.end()) {
      error(at(src, type), "composite '" + te->spec.type_name() + "' contains itself");
      return;
    }
    for (const char* k : {"trigger", "on_error", "thread"})
      if (c[k]) error(at(src, c[k]), std::string("'") + k + "' applies to the components inside a composite, not to the composite");
    const auto& def = *te->composite;
    const Source inner{def.shown, def.file.parent_path()};
    const auto vals = read_params(full, te->spec, c["params"], src, bindings, where);
    // A parameter missing or invalid is reported already; expanding the body would only
    // report each use of it as an unknown '${name}'.
    if (vals.size() != te->spec.params().size()) return;
    const Bindings b(vals.begin(), vals.end());
    auto stack = composite_stack;
    stack.push_back(te->spec.type_name());
    expand(def.root, inner, full + "/", b, task, stack);
    Exports ex;
    for (const char* section : {"inputs", "outputs"}) {
      const bool input = std::string(section) == "inputs";
      const YAML::Node ports = def.root[section];
      if (!ports || !ports.IsMap()) continue;
      for (auto p = ports.begin(); p != ports.end(); ++p) {
        YAML::Node t = p->second.IsMap() ? p->second[input ? "to" : "from"] : p->second;
        if (!t || !t.IsScalar()) continue;
        const std::string s = t.Scalar();
        const auto dot = s.rfind('.');
        if (dot == std::string::npos) continue;
        (input ? ex.inputs : ex.outputs)[p->first.Scalar()] = Endpoint{full + "/" + s.substr(0, dot), s.substr(dot + 1)};
      }
    }
    if (const YAML::Node evs = def.root["events"]; evs && evs.IsMap())
      for (auto e = evs.begin(); e != evs.end(); ++e) {
        if (!e->second.IsScalar()) continue;
        const std::string s = e->second.Scalar();
        const auto dot = s.rfind('.');
        if (dot != std::string::npos) ex.events[e->first.Scalar()] = Endpoint{full + "/" + s.substr(0, dot), s.substr(dot + 1)};
      }
    exports_[full] = std::move(ex);
    return;
  }
  ComponentConfig cc;
  cc.name = full;
  cc.type = te;
  cc.where = where;
  cc.trigger = te->spec.default_trigger();
  cc.params = read_params(full, te->spec, c["params"], src, bindings, where);
  check_params(cc, c["params"], src);
  if (const YAML::Node t = c["trigger"]) read_trigger(t, src, bindings, cc);
  if (const YAML::Node e = c["on_error"]) read_error_policy(e, src, bindings, cc);
  if (const YAML::Node t = c["thread"]) {
    const std::string s = text_of(t, bindings, src, "thread");
    if (s == "dedicated") cc.dedicated_thread = true;
    else if (s != "shared") error(at(src, t), "thread must be 'shared' (the worker pool, default) or 'dedicated'; found '" + s + "'");
  }
  task.components.push_back(std::move(cc));
}

void Loader::expand(const YAML::Node& body, const Source& src, const std::string& prefix, const Bindings& bindings, TaskConfig& task,
            std::vector<std::string> composite_stack) {
  const YAML::Node comps = body["components"];
  if (comps && !comps.IsMap()) {
    error(at(src, comps), std::string("components: a mapping name: {type: ..., params: ...}; found ") + node_kind(comps));
    return;
  }
  if (comps)
    for (auto it = comps.begin(); it != comps.end(); ++it) {
      const Location where = at(src, it->first);
      if (!it->first.IsScalar()) {
        error(where, std::string("a component's name is a plain name (letters, digits and '_'); found ") + node_kind(it->first));
        continue;
      }
      const std::string name = it->first.Scalar();
      const std::string full = prefix + name;
      if (kinds_.count(full)) continue;  // a duplicate key: reported with both places by check_mappings
      // A component that cannot be read is still known by name (with no spec), so that the
      // connections and rules naming it do not add a 'no component' error to its own.
      auto reject = [&](const Location& place, const std::string& message) {
        error(place, message);
        kinds_[full] = nullptr;
      };
      if (!is_valid_name(name)) {
        reject(where, "component name '" + name + "' must be letters, digits and '_'");
        continue;
      }
      const YAML::Node c = it->second;
      if (prefix.empty() && c.IsMap() && c["profile"]) {  // a device slot: its profile says what fills it
        check_keys(c, src, {"profile", "doc"});
        const YAML::Node flag = c["profile"];
        if (!flag.IsScalar() || flag.Scalar() != "true") {
          reject(at(src, flag), "a device slot reads 'NAME: {profile: true, doc: ...}' (its profile binds it to a type); found profile: " +
                                    (flag.IsScalar() ? "'" + flag.Scalar() + "'" : std::string(node_kind(flag))));
          continue;
        }
        SlotConfig slot;
        slot.name = name;
        slot.where = where;
        if (c["doc"] && c["doc"].IsScalar()) slot.doc = c["doc"].Scalar();
        const auto entry = profile_entry(name);
        if (!profile_.loaded) {
          kinds_[full] = nullptr;  // no profile: reported once for all slots
          continue;
        }
        if (!entry) {
          reject(where, "slot '" + name + "' is not bound by profile '" + profile_.name + "' (" + Location{profile_.src.shown, 1, 1}.str() +
                            "); a profile binds every slot: add '" + name + ": {type: ..., params: ...}' under its components");
          continue;
        }
        slot.bound = at(profile_.src, entry->first);
        const YAML::Node bound = entry->second;
        const std::size_t before = task.components.size();
        read_component(name, full, bound, profile_.src, slot.bound, bindings, task, composite_stack);
        if (bound.IsMap() && bound["type"] && bound["type"].IsScalar()) slot.type = find_type(bound["type"].Scalar());
        if (slot.type && (task.components.size() > before || slot.type->composite)) task.slots.push_back(std::move(slot));
        continue;
      }
      read_component(name, full, c, src, where, bindings, task, composite_stack);
    }

  // Connections.
  if (const YAML::Node conns = body["connections"]) {
    if (!conns.IsSequence()) error(at(src, conns), std::string("connections: a list of 'a.out -> b.in' (or {from, to, buffer, capacity, max_bytes, feedback}); found ") + node_kind(conns));
    else
      for (const auto& n : conns) read_connection(n, src, prefix, bindings, task);
  }
  // Event rules.
  if (const YAML::Node on = body["on"]) {
    if (!on.IsMap()) error(at(src, on), std::string("on: a mapping component.event: stop_success | stop_failure | {deliver: component.port}; found ") + node_kind(on));
    else
      for (auto it = on.begin(); it != on.end(); ++it) read_rule(it->first, it->second, src, prefix, task);
  }
}

}  // namespace loader

namespace fs = std::filesystem;

namespace {
// The file parsed and its mappings checked; its inner types are not looked up yet.
std::shared_ptr<CompositeDef> parse_composite_file(const fs::path& file) {
  const std::string shown = file.string();
  std::string problem;
  const std::string text = loader::read_text(file, problem);
  if (!problem.empty()) throw ConfigError({Diagnostic{Location{shown, 0, 0}, "the composite file " + problem}});
  std::vector<Diagnostic> d;
  const auto root = loader::parse_yaml(text, shown, d);
  if (!root) throw ConfigError(d);
  if (!root->IsMap() || !(*root)["composite"]) throw ConfigError({Diagnostic{Location{shown, 0, 0}, "not a composite definition (no 'composite:' key)"}});
  auto def = std::make_shared<CompositeDef>(CompositeDef{fs::absolute(file), shown, *root});
  loader::check_mappings(def->root, loader::Source{shown, def->file.parent_path()}, d);
  if (!d.empty()) throw ConfigError(d);
  return def;
}
}  // namespace

std::string composite_file_type(const fs::path& file) {
  const auto def = parse_composite_file(file);
  const YAML::Node name = def->root["composite"];
  if (!name.IsScalar() || name.Scalar().empty())
    throw ConfigError({Diagnostic{loader::at(loader::Source{def->shown, def->file.parent_path()}, name), "'composite:' needs the composite's type name"}});
  return name.Scalar();
}

std::shared_ptr<const TypeEntry> read_composite_file(const Registry& registry, const fs::path& file) {
  const auto def = parse_composite_file(file);
  std::vector<Diagnostic> d;
  loader::Loader loader(registry, {});
  Spec spec = loader.composite_spec_public(*def, d);
  if (!d.empty()) throw ConfigError(d);
  return std::make_shared<const TypeEntry>(TypeEntry{std::move(spec), nullptr, def, nullptr, def->shown});
}

void register_composite_file(Registry& registry, const fs::path& file) {
  const auto entry = read_composite_file(registry, file);
  registry.add_composite(entry->spec, entry->composite, entry->origin);
}

}  // namespace fba
