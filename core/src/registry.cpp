#include "fba/registry.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <set>
#include <sstream>

#include "fba/plugin.hpp"
#include "fba/task_config.hpp"

namespace fba {

namespace fs = std::filesystem;

namespace {
// Under a sanitizer, leaks are reported at exit; a plugin unloaded by then leaves the report's
// frames unnamed, so sanitizer builds keep plugins mapped (objects still release them).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr int kKeepMapped = RTLD_NODELETE;
#else
constexpr int kKeepMapped = 0;
#endif
}  // namespace

Library::~Library() {
  if (handle_) dlclose(handle_);
}

void* Library::symbol(const char* name) const { return dlsym(handle_, name); }

namespace {
// A blocking component waits in process() on a device: without interrupt() nothing could
// unblock it, and shutdown would hang.
void check_interrupt(const Spec& spec, bool implements_interrupt) {
  if (spec.is_blocking() && !implements_interrupt)
    throw std::logic_error("type '" + spec.type_name() +
                           "' is declared blocking() but does not implement interrupt(), so a stop could not unblock it");
}
}  // namespace

void Registry::add(Spec spec, Factory make, std::string origin, std::shared_ptr<const Library> library, bool implements_interrupt) {
  spec.validate();
  check_interrupt(spec, implements_interrupt);
  const std::string name = spec.type_name();
  if (auto it = types_.find(name); it != types_.end())
    throw std::logic_error("component type '" + name + "' is registered twice: by " + it->second->origin + " and by " + origin);
  types_.emplace(name, std::make_shared<const TypeEntry>(TypeEntry{std::move(spec), make, nullptr, std::move(library), std::move(origin)}));
}

void Registry::add_composite(Spec spec, std::shared_ptr<const CompositeDef> def, std::string origin) {
  const std::string name = spec.type_name();
  if (auto it = types_.find(name); it != types_.end())
    throw std::logic_error("component type '" + name + "' is registered twice: by " + it->second->origin + " and by " + origin);
  types_.emplace(name, std::make_shared<const TypeEntry>(TypeEntry{std::move(spec), nullptr, std::move(def), nullptr, std::move(origin)}));
}

void Registry::add_builtin(const std::vector<detail::ComponentEntry>& entries, const std::string& origin) {
  for (const auto& e : entries) add(e.spec(), e.make, origin, nullptr, e.implements_interrupt);
}

void Registry::load_plugin(const fs::path& file) {
  const std::string f = file.string();
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw PluginError(f, "no such file");
  dlerror();
  void* handle = dlopen(f.c_str(), RTLD_NOW | RTLD_LOCAL | kKeepMapped);
  if (!handle) {
    const char* err = dlerror();
    throw PluginError(f, std::string("cannot be loaded: ") + (err ? err : "unknown dlopen error"));
  }
  auto lib = std::make_shared<const Library>(handle, f);

  // The ABI record is read before any of the plugin's code is called.
  const auto* info = static_cast<const PluginInfo*>(lib->symbol(kPluginInfoSymbol));
  if (!info)
    throw PluginError(f, std::string("is not an fba plugin: the symbol '") + kPluginInfoSymbol +
                             "' is missing (build it with fba_add_plugin)");
  if (info->magic != kPluginMagic) throw PluginError(f, "is not an fba plugin: its plugin record has a wrong magic number");
  if (info->abi_version != kAbiVersion)
    throw PluginError(f, "was built for fba plugin ABI " + std::to_string(info->abi_version) + " (fba " +
                             (info->fba_version ? info->fba_version : "?") + "); this fba " FBA_VERSION " needs ABI " +
                             std::to_string(kAbiVersion) + ": rebuild the plugin against this fba");
  if (!info->build_abi || std::strcmp(info->build_abi, FBA_BUILD_ABI_TAG) != 0)
    throw PluginError(f, std::string("was built with C++ library ABI '") + (info->build_abi ? info->build_abi : "?") +
                             "', this fba uses '" FBA_BUILD_ABI_TAG "'");
  auto components = reinterpret_cast<PluginComponentsFn>(lib->symbol(kPluginComponentsSymbol));
  if (!components)
    throw PluginError(f, std::string("the symbol '") + kPluginComponentsSymbol + "' is missing");
  const auto* entries = components();
  if (!entries || entries->empty()) throw PluginError(f, "registers no component types (no FBA_COMPONENT in its sources)");

  // All or nothing: check every spec and name before registering any.
  std::vector<Spec> specs;
  for (const auto& e : *entries) {
    try {
      specs.push_back(e.spec());
      specs.back().validate();
      check_interrupt(specs.back(), e.implements_interrupt);
    } catch (const std::exception& ex) {
      throw PluginError(f, std::string("declares an invalid component: ") + ex.what());
    }
    const std::string& name = specs.back().type_name();
    if (auto it = types_.find(name); it != types_.end())
      throw PluginError(f, "registers component type '" + name + "', which " + it->second->origin + " registered already");
    for (std::size_t i = 0; i + 1 < specs.size(); ++i)
      if (specs[i].type_name() == name) throw PluginError(f, "registers component type '" + name + "' twice");
  }
  PluginRecord record{f, info->name ? info->name : "?", info->fba_version ? info->fba_version : "?", {}};
  for (std::size_t i = 0; i < specs.size(); ++i) {
    record.types.push_back(specs[i].type_name());
    add(std::move(specs[i]), (*entries)[i].make, f, lib, (*entries)[i].implements_interrupt);
  }
  plugins_.push_back(std::move(record));
}

std::vector<PluginError> Registry::load_path(const std::vector<fs::path>& dirs) {
  std::vector<PluginError> errors;
  std::vector<fs::path> composites;
  std::set<fs::path> seen;
  for (const auto& dir : dirs) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) continue;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir, ec)) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& p : files) {
      auto canonical = fs::weakly_canonical(p, ec);
      if (!seen.insert(canonical).second) continue;
      if (p.extension() == ".so") {
        try {
          load_plugin(p);
        } catch (const PluginError& e) {
          errors.push_back(e);
        }
      } else if (p.extension() == ".yaml" || p.extension() == ".yml") {
        composites.push_back(p);
      }
    }
  }
  // Composites may use each other: register in passes until no more can be resolved.
  std::vector<std::pair<fs::path, std::string>> pending;
  for (auto& c : composites) pending.emplace_back(c, "");
  for (bool progress = true; progress && !pending.empty();) {
    progress = false;
    for (auto it = pending.begin(); it != pending.end();) {
      try {
        register_composite_file(*this, it->first);
        it = pending.erase(it);
        progress = true;
      } catch (const std::exception& e) {
        it->second = e.what();
        ++it;
      }
    }
  }
  for (auto& [file, why] : pending) errors.emplace_back(file.string(), "composite not usable: " + why);
  return errors;
}

std::shared_ptr<const TypeEntry> Registry::find(std::string_view type_name) const {
  auto it = types_.find(type_name);
  return it == types_.end() ? nullptr : it->second;
}

std::vector<const TypeEntry*> Registry::types() const {
  std::vector<const TypeEntry*> out;
  for (const auto& [_, t] : types_) out.push_back(t.get());
  return out;
}

namespace {
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}
}  // namespace

std::vector<std::string> Registry::closest(std::string_view type_name, std::size_t n) const {
  std::vector<std::pair<std::size_t, std::string>> scored;
  for (const auto& [name, _] : types_) scored.emplace_back(edit_distance(type_name, name), name);
  std::sort(scored.begin(), scored.end());
  std::vector<std::string> out;
  for (auto& [d, name] : scored)
    if (out.size() < n && d <= std::max<std::size_t>(3, type_name.size() / 3)) out.push_back(name);
  return out;
}

std::vector<fs::path> plugin_search_path(const std::vector<fs::path>& extra) {
  std::vector<fs::path> dirs;
  if (const char* env = std::getenv("FBA_PLUGIN_PATH")) {
    std::stringstream ss(env);
    std::string item;
    while (std::getline(ss, item, ':'))
      if (!item.empty()) dirs.emplace_back(item);
  }
  dirs.insert(dirs.end(), extra.begin(), extra.end());
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) dirs.push_back((exe.parent_path() / FBA_PLUGIN_DIR_FROM_BIN).lexically_normal());
  return dirs;
}

}  // namespace fba
