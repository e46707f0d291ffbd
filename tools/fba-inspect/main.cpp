// fba-inspect: what the plugins on the search path provide, in the spirit of gst-inspect. It reads
// the plugins' manifests and runs no plugin code (only composites load the plugins they use).
#include <filesystem>
#include <iostream>
#include <optional>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>

#include "fba/registry.hpp"
#include "fba/version.hpp"

namespace po = boost::program_options;
using nlohmann::json;

namespace {

constexpr int kError = 2;

// A component type's interface, with what fba-inspect adds to it: where it comes from and the
// events every component has.
json type_json(const fba::Registry& registry, const std::string& name, const std::string& origin) {
  json j = json::parse(registry.interface_json(name));
  j["origin"] = origin;
  j["events"].push_back({{"name", "error"}, {"doc", "built-in: the component failed; payload: the reason"}});
  j["events"].push_back({{"name", "finished"}, {"doc", "built-in: the component produced its last sample"}});
  return j;
}

json data_type_json(const fba::DataTypeRecord& d) {
  json j{{"name", d.name}, {"doc", d.doc}, {"header", d.header}, {"used_by", d.used_by}};
  if (d.layout.known()) j["layout"] = {{"size", d.layout.size}, {"align", d.layout.align}, {"version", d.layout.version}};
  return j;
}

std::string value_text(const json& v) {
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

void print_type(const json& t) {
  std::cout << t["type"].get<std::string>() << " (" << t["kind"].get<std::string>() << ")\n  " << t["doc"].get<std::string>()
            << "\n  from: " << t["origin"].get<std::string>() << "\n  trigger: " << t["trigger"].get<std::string>()
            << (t.value("blocking", false) ? ", own thread (blocking)" : "")
            << (t.value("concurrent_safe_state", false) ? "\n  safe state: at once on a stop, beside a running process()" : "")
            << "\n";
  auto ports = [](const char* title, const json& v, bool input) {
    std::cout << "\n  " << title << ":\n";
    if (v.empty()) std::cout << "    (none)\n";
    for (const auto& p : v)
      std::cout << "    " << p["name"].get<std::string>() << "  "
                << (p.contains("type") ? p["type"].get<std::string>() : "same type as input '" + p["same_as"].get<std::string>() + "'")
                << (input && !p.value("required", true) ? "  (optional)" : "") << "\n      " << p["doc"].get<std::string>() << "\n";
  };
  ports("inputs", t["inputs"], true);
  ports("outputs", t["outputs"], false);
  std::cout << "\n  parameters:\n";
  if (t["params"].empty()) std::cout << "    (none)\n";
  for (const auto& p : t["params"]) {
    std::cout << "    " << p["name"].get<std::string>() << "  " << p["type"].get<std::string>();
    if (p.contains("default")) std::cout << ", default " << value_text(p["default"]);
    else std::cout << ", required";
    if (p.contains("min") || p.contains("max"))
      std::cout << ", range [" << (p.contains("min") ? fba::to_string(fba::Value(p["min"].get<double>())) : "-inf") << ", "
                << (p.contains("max") ? fba::to_string(fba::Value(p["max"].get<double>())) : "inf") << "]";
    if (p.contains("choices")) {
      std::cout << ", one of:";
      for (const auto& c : p["choices"]) std::cout << " " << c.get<std::string>();
    }
    std::cout << "\n      " << p["doc"].get<std::string>() << "\n";
  }
  std::cout << "\n  events:\n";
  for (const auto& e : t["events"])
    if (e["doc"].get<std::string>().rfind("built-in:", 0) != 0)
      std::cout << "    " << e["name"].get<std::string>() << "\n      " << e["doc"].get<std::string>() << "\n";
  std::cout << "    error, finished  (built-in)\n";
  if (t.contains("stages")) {
    std::cout << "\n  stages:";
    for (const auto& st : t["stages"]) std::cout << " " << st.get<std::string>();
    std::cout << "\n  transitions:";
    for (const auto& tr : t["transitions"]) std::cout << " " << tr[0].get<std::string>() << "->" << tr[1].get<std::string>();
    std::cout << "\n";
  }
}

void print_data_type(const fba::DataTypeRecord& d) {
  std::cout << d.name << " (data type)\n  " << d.doc << "\n  layout: " << fba::to_string(d.layout) << "\n";
  if (!d.header.empty()) std::cout << "  declared in: <" << d.header << ">\n";
  std::cout << "  used by:";
  if (d.used_by.empty()) std::cout << " (no plugin on the path)";
  for (const auto& f : d.used_by) std::cout << "\n    " << f;
  std::cout << "\n";
}

// The command line, or the exit status when it asks for nothing more (help, version, an error).
struct Options {
  std::vector<std::filesystem::path> plugin_dirs;
  std::optional<std::string> type;  // none: list everything
  bool as_json = false;
};

std::optional<int> parse_options(int argc, char** argv, Options& options) {
  po::options_description visible("Usage: fba-inspect [options] [TYPE]\n\nLists the plugins, component types and data types "
                                  "found, or shows one component type's interface or one data type.\n\nOptions");
  std::vector<std::string> plugin_dirs;
  visible.add_options()("help,h", "show this help")("version", "print the version")("json", "print JSON for programs")(
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
    std::cerr << "fba-inspect: " << e.what() << "\nTry 'fba-inspect --help'.\n";
    return kError;
  }
  if (vm.count("help")) {
    std::cout << visible << "\n";
    return 0;
  }
  if (vm.count("version")) {
    std::cout << "fba-inspect " FBA_VERSION "\n";
    return 0;
  }
  options.as_json = vm.count("json") > 0;
  if (vm.count("type")) options.type = vm["type"].as<std::string>();
  options.plugin_dirs.assign(plugin_dirs.begin(), plugin_dirs.end());
  for (const auto& d : options.plugin_dirs) {
    std::error_code ec;
    if (!std::filesystem::is_directory(d, ec)) {
      std::cerr << "fba-inspect: --plugin-path '" << d.string() << "' is not a folder\nTry 'fba-inspect --help'.\n";
      return kError;
    }
  }
  return std::nullopt;
}

// The plugin file that provides a component type, or the origin of a built-in or composite one.
std::string origin_of(const fba::Registry& registry, const std::vector<fba::PluginRecord>& plugins, const std::string& type) {
  for (const auto& p : plugins)
    for (const auto& t : p.types)
      if (t == type) return p.file;
  for (const auto* t : registry.types())
    if (t->spec.type_name() == type) return t->origin;
  return std::string();
}

// What the search path holds, read once after loading: listing a composite's interface loads
// plugins, which must not change what is listed.
struct Found {
  std::vector<std::filesystem::path> search;
  std::vector<fba::PluginError> errors;
  std::vector<fba::PluginRecord> plugins;
  std::vector<fba::DataTypeRecord> data_types;
};

// One component type or data type, by name; the exit status.
int show_one(const fba::Registry& registry, const Found& found, const std::string& name, bool as_json) {
  const auto& plugins = found.plugins;
  for (const auto& d : found.data_types)
    if (d.name == name) {
      if (as_json) std::cout << data_type_json(d).dump(2) << "\n";
      else print_data_type(d);
      return 0;
    }
  if (registry.interface_json(name).empty()) {
    std::cerr << "fba-inspect: no component type or data type '" << name << "'";
    const auto near = registry.closest(name);
    if (!near.empty()) {
      std::cerr << "; did you mean";
      for (const auto& n : near) std::cerr << " " << n;
      std::cerr << "?";
    }
    std::cerr << "\n";
    return kError;
  }
  const json t = type_json(registry, name, origin_of(registry, plugins, name));
  if (as_json) std::cout << t.dump(2) << "\n";
  else print_type(t);
  for (const auto& p : plugins)
    if (p.file == t["origin"] && !p.error.empty()) return kError;  // shown, but its plugin cannot be used
  return 0;
}

void list_json(const fba::Registry& registry, const Found& found) {
  const auto names = registry.type_names();
  const auto& plugins = found.plugins;
  json j;
  j["version"] = FBA_VERSION;
  j["search_path"] = json::array();
  for (const auto& d : found.search) j["search_path"].push_back(d.string());
  j["plugins"] = json::array();
  for (const auto& p : plugins) {
    json pj{{"file", p.file}, {"name", p.name}, {"fba_version", p.version}, {"types", p.types}, {"loaded", p.loaded}};
    if (!p.error.empty()) pj["error"] = p.error;
    j["plugins"].push_back(pj);
  }
  j["types"] = json::array();
  for (const auto& n : names) j["types"].push_back(type_json(registry, n, origin_of(registry, plugins, n)));
  j["data_types"] = json::array();
  for (const auto& d : found.data_types) j["data_types"].push_back(data_type_json(d));
  j["errors"] = json::array();
  for (const auto& e : found.errors) j["errors"].push_back({{"file", e.file()}, {"reason", e.reason()}});
  std::cout << j.dump(2) << "\n";
}

void list_text(const fba::Registry& registry, const Found& found) {
  const auto names = registry.type_names();
  const auto& data_types = found.data_types;
  std::cout << "Plugin search path:\n";
  for (const auto& d : found.search) std::cout << "  " << d.string() << "\n";
  std::cout << "\nPlugins:\n";
  for (const auto& p : found.plugins) {
    std::cout << "  " << (p.name.empty() ? std::filesystem::path(p.file).filename().string() : p.name) << "  (" << p.file;
    if (!p.version.empty()) std::cout << ", fba " << p.version;
    std::cout << ")" << (p.error.empty() ? "" : "  BROKEN: " + p.error) << "\n";
    for (const auto& t : p.types) {
      const json j = json::parse(registry.interface_json(t));
      std::cout << "    " << t << "  " << j["kind"].get<std::string>() << "\n";
    }
  }
  std::cout << "\nComposites:\n";
  for (const auto* t : registry.types())
    if (t->composite) std::cout << "  " << t->spec.type_name() << "  (" << t->origin << ")\n";
  std::cout << "\nData types:\n";
  for (const auto& d : data_types)
    std::cout << "  " << d.name << "  (" << fba::to_string(d.layout) << (d.header.empty() ? "" : ", <" + d.header + ">")
              << ")\n      " << d.doc << "\n";
  std::cout << "\n" << names.size() << " component types, " << data_types.size()
            << " data types. 'fba-inspect TYPE' shows one.\n";
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (const auto status = parse_options(argc, argv, options)) return *status;
  fba::Registry registry;
  Found found;
  found.search = fba::plugin_search_path(options.plugin_dirs);
  found.errors = registry.load_path(found.search);
  for (const auto& e : found.errors) std::cerr << "fba-inspect: plugin " << e.file() << ": " << e.reason() << "\n";
  found.plugins = registry.plugins();
  found.data_types = registry.data_types();
  if (options.type) return show_one(registry, found, *options.type, options.as_json);
  if (options.as_json) list_json(registry, found);
  else list_text(registry, found);
  return found.errors.empty() ? 0 : kError;
}
