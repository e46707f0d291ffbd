// fba-inspect: what the plugins on the search path provide, in the spirit of gst-inspect.
#include <iostream>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>

#include "fba/registry.hpp"
#include "fba/version.hpp"

namespace po = boost::program_options;
using nlohmann::json;

namespace {

json value_json(const fba::Value& v) {
  return std::visit([](const auto& x) { return json(x); }, v);
}

json port_json(const fba::PortSpec& p, bool input) {
  json j{{"name", p.name}, {"type", p.same_as.empty() ? p.type->name : "same as input '" + p.same_as + "'"}, {"doc", p.doc}};
  if (input) j["required"] = p.required;
  return j;
}

json type_json(const fba::TypeEntry& t) {
  const fba::Spec& s = t.spec;
  json j{{"type", s.type_name()}, {"kind", fba::to_string(s.kind())}, {"doc", s.doc()}, {"origin", t.origin}};
  j["trigger"] = fba::to_string(s.default_trigger().policy);
  if (s.is_blocking()) j["thread"] = "dedicated";
  j["inputs"] = json::array();
  for (const auto& p : s.inputs()) j["inputs"].push_back(port_json(p, true));
  j["outputs"] = json::array();
  for (const auto& p : s.outputs()) j["outputs"].push_back(port_json(p, false));
  j["params"] = json::array();
  for (const auto& p : s.params()) {
    json pj{{"name", p.name}, {"type", fba::to_string(p.type)}, {"required", p.required()}, {"doc", p.doc}};
    if (p.default_value) pj["default"] = value_json(*p.default_value);
    if (p.min) pj["min"] = *p.min;
    if (p.max) pj["max"] = *p.max;
    if (!p.choices.empty()) pj["choices"] = p.choices;
    j["params"].push_back(pj);
  }
  j["events"] = json::array();
  for (const auto& e : s.events()) j["events"].push_back({{"name", e.name}, {"doc", e.doc}});
  j["events"].push_back({{"name", "error"}, {"doc", "built-in: the component failed; payload: the reason"}});
  j["events"].push_back({{"name", "finished"}, {"doc", "built-in: the component produced its last sample"}});
  if (!s.stage_names().empty()) {
    j["stages"] = s.stage_names();
    json tr = json::array();
    for (const auto& [a, b] : s.transitions()) tr.push_back({a, b});
    j["transitions"] = tr;
  }
  return j;
}

void print_type(const fba::TypeEntry& t) {
  const fba::Spec& s = t.spec;
  std::cout << s.type_name() << " (" << fba::to_string(s.kind()) << ")\n  " << s.doc() << "\n  from: " << t.origin
            << "\n  trigger: " << fba::to_string(s.default_trigger().policy) << (s.is_blocking() ? ", own thread (blocking)" : "")
            << "\n";
  auto ports = [](const char* title, const std::vector<fba::PortSpec>& v, bool input) {
    std::cout << "\n  " << title << ":\n";
    if (v.empty()) std::cout << "    (none)\n";
    for (const auto& p : v)
      std::cout << "    " << p.name << "  " << (p.same_as.empty() ? p.type->name : "same type as input '" + p.same_as + "'")
                << (input && !p.required ? "  (optional)" : "") << "\n      " << p.doc << "\n";
  };
  ports("inputs", s.inputs(), true);
  ports("outputs", s.outputs(), false);
  std::cout << "\n  parameters:\n";
  if (s.params().empty()) std::cout << "    (none)\n";
  for (const auto& p : s.params()) {
    std::cout << "    " << p.name << "  " << fba::to_string(p.type);
    if (p.default_value) std::cout << ", default " << fba::to_string(*p.default_value);
    else std::cout << ", required";
    if (p.min || p.max)
      std::cout << ", range [" << (p.min ? fba::to_string(fba::Value(*p.min)) : "-inf") << ", " << (p.max ? fba::to_string(fba::Value(*p.max)) : "inf") << "]";
    if (!p.choices.empty()) {
      std::cout << ", one of:";
      for (const auto& c : p.choices) std::cout << " " << c;
    }
    std::cout << "\n      " << p.doc << "\n";
  }
  std::cout << "\n  events:\n";
  for (const auto& e : s.events()) std::cout << "    " << e.name << "\n      " << e.doc << "\n";
  std::cout << "    error, finished  (built-in)\n";
  if (!s.stage_names().empty()) {
    std::cout << "\n  stages:";
    for (const auto& st : s.stage_names()) std::cout << " " << st;
    std::cout << "\n  transitions:";
    for (const auto& [a, b] : s.transitions()) std::cout << " " << a << "->" << b;
    std::cout << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  po::options_description visible("Usage: fba-inspect [options] [TYPE]\n\nLists the plugins and component types found, or "
                                  "shows one type's interface.\n\nOptions");
  std::vector<std::string> plugin_dirs;
  visible.add_options()("help,h", "show this help")("json", "print JSON for programs")(
      "plugin-path,p", po::value(&plugin_dirs)->composing(), "add a plugin folder (repeatable; also FBA_PLUGIN_PATH)");
  po::options_description all;
  all.add(visible).add_options()("type", po::value<std::string>());
  po::positional_options_description positional;
  positional.add("type", 1);
  po::variables_map vm;
  try {
    po::store(po::command_line_parser(argc, argv).options(all).positional(positional).run(), vm);
    po::notify(vm);
  } catch (const po::error& e) {
    std::cerr << "fba-inspect: " << e.what() << "\n";
    return 2;
  }
  if (vm.count("help")) {
    std::cout << visible << "\n";
    return 0;
  }
  const bool as_json = vm.count("json") > 0;
  fba::Registry registry;
  std::vector<std::filesystem::path> extra(plugin_dirs.begin(), plugin_dirs.end());
  const auto search = fba::plugin_search_path(extra);
  const auto errors = registry.load_path(search);
  for (const auto& e : errors) std::cerr << "fba-inspect: plugin " << e.file() << ": " << e.reason() << "\n";

  if (vm.count("type")) {
    const std::string name = vm["type"].as<std::string>();
    const auto t = registry.find(name);
    if (!t) {
      std::cerr << "fba-inspect: no component type '" << name << "'";
      const auto near = registry.closest(name);
      if (!near.empty()) {
        std::cerr << "; did you mean";
        for (const auto& n : near) std::cerr << " " << n;
        std::cerr << "?";
      }
      std::cerr << "\n";
      return 2;
    }
    if (as_json) std::cout << type_json(*t).dump(2) << "\n";
    else print_type(*t);
    return errors.empty() ? 0 : 2;
  }

  if (as_json) {
    json j;
    j["version"] = FBA_VERSION;
    j["search_path"] = json::array();
    for (const auto& d : search) j["search_path"].push_back(d.string());
    j["plugins"] = json::array();
    for (const auto& p : registry.plugins()) j["plugins"].push_back({{"file", p.file}, {"name", p.name}, {"fba_version", p.version}, {"types", p.types}});
    j["types"] = json::array();
    for (const auto* t : registry.types()) j["types"].push_back(type_json(*t));
    j["errors"] = json::array();
    for (const auto& e : errors) j["errors"].push_back({{"file", e.file()}, {"reason", e.reason()}});
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << "Plugin search path:\n";
    for (const auto& d : search) std::cout << "  " << d.string() << "\n";
    std::cout << "\nPlugins:\n";
    for (const auto& p : registry.plugins()) {
      std::cout << "  " << p.name << "  (" << p.file << ", fba " << p.version << ")\n";
      for (const auto& t : p.types) std::cout << "    " << t << "  " << fba::to_string(registry.find(t)->spec.kind()) << "\n";
    }
    std::cout << "\nComposites:\n";
    for (const auto* t : registry.types())
      if (t->composite) std::cout << "  " << t->spec.type_name() << "  (" << t->origin << ")\n";
    std::cout << "\n" << registry.types().size() << " component types. 'fba-inspect TYPE' shows one.\n";
  }
  return errors.empty() ? 0 : 2;
}
