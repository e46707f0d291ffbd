#include "fba/registry.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <set>
#include <sstream>

#include <spdlog/spdlog.h>

#include "elf_file.hpp"
#include "fba/log.hpp"
#include "fba/plugin.hpp"
#include "fba/task_config.hpp"
#include "plugin_manifest.hpp"

namespace fba {

namespace fs = std::filesystem;

namespace detail {
// A plugin known from its manifest; loaded (dlopen'ed) on first use.
struct PluginSlot {
  std::string file;
  Manifest manifest;
  std::mutex mutex;    // guards what follows: find() loads from any thread
  std::string error;   // why it cannot be used
  bool loaded = false;
  std::map<std::string, std::shared_ptr<const TypeEntry>, std::less<>> entries;
};

// A composite file found on the path, known by its name until a task uses it: reading it whole
// looks up its inner types, which loads their plugins, so that waits until then.
struct CompositeSlot {
  std::filesystem::path file;
  std::shared_ptr<const TypeEntry> entry;  // once read
  std::string error;                       // why it cannot be used
  bool reading = false;                    // being read: a composite that uses it again is a cycle
};
}  // namespace detail

namespace {

using detail::CompositeSlot;
using detail::PluginSlot;

// Composites are read rarely, and one may use another: one lock for all of them, re-entered by
// the thread that reads a composite that uses another.
std::recursive_mutex composite_mutex;

thread_local const char* t_plugin_being_loaded = nullptr;

// Names the plugin whose code runs on this thread, for plugin_being_loaded().
class LoadingScope {
 public:
  explicit LoadingScope(const std::string& file) : previous_(t_plugin_being_loaded) { t_plugin_being_loaded = file.c_str(); }
  ~LoadingScope() { t_plugin_being_loaded = previous_; }
  LoadingScope(const LoadingScope&) = delete;
  LoadingScope& operator=(const LoadingScope&) = delete;

 private:
  const char* previous_;
};

// Runs the plugin's code for the first time: dlopen, its static initialisers, its specs. Every
// check that can be made from the files was made before (Registry::add_plugin).
void load_code(PluginSlot& slot, bool describe = false) {
  const std::string& f = slot.file;
  const LoadingScope loading(f);
  // Named before dlopen, so a crash inside it (a static initialiser) is attributable.
  make_logger("plugins")->debug("loading plugin {}", f);  // a fresh logger: the level may have changed
  dlerror();
  // Never unloaded: payloads, their deleters and components from it may live anywhere.
  void* handle = dlopen(f.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (!handle) {
    const char* err = dlerror();
    throw std::runtime_error(std::string("cannot be loaded: ") + (err ? err : "unknown dlopen error"));
  }
  auto lib = std::make_shared<const Library>(handle, f);

  // The record compiled into the plugin must say what its manifest said.
  const auto* info = static_cast<const PluginInfo*>(lib->symbol(kPluginInfoSymbol));
  if (!info)
    throw std::runtime_error(std::string("is not an fba plugin: the symbol '") + kPluginInfoSymbol +
                             "' is missing (build it with fba_add_plugin)");
  if (info->magic != kPluginMagic || info->abi_version != slot.manifest.abi_version || !info->build_abi ||
      slot.manifest.build_abi != info->build_abi)
    throw std::runtime_error("its ABI record does not match its manifest " + detail::manifest_path(f).string() +
                             ": rebuild the plugin to rewrite the manifest");
  auto components = reinterpret_cast<PluginComponentsFn>(lib->symbol(kPluginComponentsSymbol));
  if (!components) throw std::runtime_error(std::string("the symbol '") + kPluginComponentsSymbol + "' is missing");
  const auto* entries = components();
  if (!entries || entries->empty()) throw std::runtime_error("registers no component types (no FBA_COMPONENT in its sources)");

  // Layouts registered while reading its specs are this plugin's.
  TypeOriginScope origin(f);
  std::map<std::string, std::shared_ptr<const TypeEntry>, std::less<>> made;
  for (const auto& e : *entries) {
    std::shared_ptr<const TypeEntry> entry;
    try {
      entry = Registry::make_entry(e.spec(), e.make, f, lib, e.implements_interrupt);
    } catch (const std::exception& ex) {
      throw std::runtime_error(std::string("declares an invalid component: ") + ex.what());
    }
    const std::string name = entry->spec.type_name();
    if (!made.emplace(name, std::move(entry)).second) throw std::runtime_error("registers component type '" + name + "' twice");
  }
  if (describe) {
    slot.entries = std::move(made);
    return;
  }
  std::set<std::string> listed;
  for (const auto& t : slot.manifest.types) listed.insert(t.name);
  for (const auto& [name, _] : made)
    if (!listed.count(name))
      throw std::runtime_error("registers component type '" + name + "', which its manifest does not list: rebuild the plugin");
  for (const auto& name : listed)
    if (!made.count(name)) throw std::runtime_error("does not register component type '" + name + "', which its manifest lists");
  slot.entries = std::move(made);
}

// Loads the slot once; throws PluginError when it cannot be used.
void ensure_loaded(PluginSlot& slot) {
  std::lock_guard lock(slot.mutex);
  if (slot.error.empty() && !slot.loaded) {
    try {
      load_code(slot);
      slot.loaded = true;
    } catch (const std::exception& e) {
      slot.error = e.what();
    }
  }
  if (!slot.error.empty()) throw PluginError(slot.file, slot.error);
}

}  // namespace

const char* plugin_being_loaded() noexcept { return t_plugin_being_loaded; }

namespace detail {
Manifest describe_plugin(const fs::path& file) {
  PluginSlot slot;
  slot.file = file.string();
  slot.manifest.build_id = check_elf(file).build_id;
  const LoadingScope loading(slot.file);
  {
    // The record first, on its own: a plugin for another ABI is described, not run further.
    dlerror();
    void* handle = dlopen(slot.file.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (!handle) {
      const char* err = dlerror();
      throw std::runtime_error(std::string("cannot be loaded: ") + (err ? err : "unknown dlopen error"));
    }
    const auto* info = static_cast<const PluginInfo*>(dlsym(handle, kPluginInfoSymbol));
    if (!info)
      throw std::runtime_error(std::string("is not an fba plugin: the symbol '") + kPluginInfoSymbol + "' is missing");
    slot.manifest.magic = info->magic;
    slot.manifest.abi_version = info->abi_version;
    slot.manifest.name = info->name ? info->name : "";
    slot.manifest.fba_version = info->fba_version ? info->fba_version : "";
    slot.manifest.build_abi = info->build_abi ? info->build_abi : "";
    if (info->magic != kPluginMagic || info->abi_version != kAbiVersion) return slot.manifest;
  }
  // Every type it registers, as its manifest will list them.
  load_code(slot, /*describe=*/true);
  std::set<std::string> seen;
  for (const auto& [name, entry] : slot.entries) {
    slot.manifest.types.push_back({name, to_string(entry->spec.kind()), spec_json(entry->spec)});
    for (auto& d : data_types_of(entry->spec))
      if (seen.insert(d.name).second) slot.manifest.data_types.push_back(std::move(d));
  }
  return slot.manifest;
}
}  // namespace detail

void* Library::symbol(const char* name) const { return dlsym(handle_, name); }

Registry::Registry() = default;
Registry::~Registry() = default;
Registry::Registry(Registry&&) noexcept = default;
Registry& Registry::operator=(Registry&&) noexcept = default;

std::shared_ptr<const TypeEntry> Registry::make_entry(Spec spec, Factory make, std::string origin,
                                                      std::shared_ptr<const Library> library, bool implements_interrupt) {
  spec.validate();
  // A blocking component waits in process() on a device: without interrupt() nothing could
  // unblock it, and shutdown would hang.
  if (spec.is_blocking() && !implements_interrupt)
    throw std::logic_error("type '" + spec.type_name() +
                           "' is declared blocking() but does not implement interrupt(), so a stop could not unblock it");
  return std::make_shared<const TypeEntry>(TypeEntry{std::move(spec), make, nullptr, std::move(library), std::move(origin)});
}

bool Registry::has_type(std::string_view name, std::string* origin) const {
  if (auto it = types_.find(name); it != types_.end()) {
    if (origin) *origin = it->second->origin;
    return true;
  }
  if (auto it = plugin_types_.find(name); it != plugin_types_.end()) {
    if (origin) *origin = it->second->file;
    return true;
  }
  if (auto it = composite_files_.find(name); it != composite_files_.end()) {
    if (origin) *origin = it->second->file.string();
    return true;
  }
  return false;
}

void Registry::add(Spec spec, Factory make, std::string origin, std::shared_ptr<const Library> library,
                   bool implements_interrupt) {
  auto entry = make_entry(std::move(spec), make, std::move(origin), std::move(library), implements_interrupt);
  const std::string& name = entry->spec.type_name();
  if (std::string first; has_type(name, &first))
    throw std::logic_error("component type '" + name + "' is registered twice: by " + first + " and by " + entry->origin);
  types_.emplace(name, std::move(entry));
}

void Registry::add_composite(Spec spec, std::shared_ptr<const CompositeDef> def, std::string origin) {
  const std::string name = spec.type_name();
  if (std::string first; has_type(name, &first))
    throw std::logic_error("component type '" + name + "' is registered twice: by " + first + " and by " + origin);
  types_.emplace(name, std::make_shared<const TypeEntry>(TypeEntry{std::move(spec), nullptr, std::move(def), nullptr, std::move(origin)}));
}

void Registry::add_builtin(const std::vector<detail::ComponentEntry>& entries, const std::string& origin) {
  for (const auto& e : entries) add(e.spec(), e.make, origin, nullptr, e.implements_interrupt);
}

std::shared_ptr<PluginSlot> Registry::add_plugin(const fs::path& file) {
  auto slot = std::make_shared<PluginSlot>();
  slot->file = file.string();
  const std::string& f = slot->file;
  plugins_.push_back(slot);
  const auto refuse = [&](const std::string& why) {
    slot->error = why;
    // Its types stay known, so a task that uses one is told why it cannot be used.
    for (const auto& t : slot->manifest.types)
      if (!has_type(t.name)) plugin_types_.emplace(t.name, slot);
    throw PluginError(f, why);
  };
  // The file itself first: a directory, a dangling link, a truncated or foreign .so.
  detail::ElfFile elf;
  try {
    elf = detail::check_elf(file);
  } catch (const std::exception& e) {
    refuse(e.what());
  }
  const fs::path mf = detail::manifest_path(file);
  std::error_code ec;
  if (!fs::exists(mf, ec))
    refuse("has no manifest " + mf.filename().string() +
           " beside it, so it is not loaded: fba reads what a plugin offers, and checks its ABI, before running any of "
           "its code. Build it with fba_add_plugin(), which writes the manifest");
  try {
    slot->manifest = detail::read_manifest(mf);
  } catch (const std::exception& e) {
    refuse(e.what());
  }
  const detail::Manifest& m = slot->manifest;
  // The ABI record, checked before any of the plugin's code runs.
  if (m.magic != kPluginMagic) refuse("is not an fba plugin: its manifest has a wrong magic number");
  if (m.abi_version != kAbiVersion)
    refuse("was built for fba plugin ABI " + std::to_string(m.abi_version) + " (fba " + m.fba_version + "); this fba " FBA_VERSION
           " needs ABI " + std::to_string(kAbiVersion) + ": rebuild the plugin against this fba");
  if (m.build_abi != FBA_BUILD_ABI_TAG)
    refuse("was built with C++ library ABI '" + m.build_abi + "', this fba uses '" FBA_BUILD_ABI_TAG "'");
  if (m.build_id != elf.build_id)
    refuse("its manifest " + mf.filename().string() + " describes another build of it (build id " +
           (m.build_id.empty() ? "none" : m.build_id) + ", the file has " + (elf.build_id.empty() ? "none" : elf.build_id) +
           "): the manifest is stale; rebuild the plugin");
  if (m.types.empty()) refuse("registers no component types (its manifest lists none)");

  // Names and data-type layouts against everything registered before it.
  std::set<std::string> names;
  for (const auto& t : m.types) {
    if (std::string first; has_type(t.name, &first))
      refuse("registers component type '" + t.name + "', which " + first + " registered already");
    if (!names.insert(t.name).second) refuse("registers component type '" + t.name + "' twice");
  }
  for (const auto& d : m.data_types) {
    if (!d.layout.known()) continue;
    if (const TypeInfo* known = find_type(d.name); known && known->layout.known() && known->layout != d.layout)
      refuse("uses data type '" + d.name + "' with " + to_string(d.layout) + ", but " +
             (known->origin.empty() ? "this fba" : known->origin) + " defines it with " + to_string(known->layout) +
             ": rebuild the plugins against the same definition of '" + d.name + "'");
    for (const auto& other : plugins_) {
      if (other == slot || !other->error.empty()) continue;
      for (const auto& od : other->manifest.data_types)
        if (od.name == d.name && od.layout.known() && od.layout != d.layout)
          refuse("uses data type '" + d.name + "' with " + to_string(d.layout) + ", but " + other->file + " uses it with " +
                 to_string(od.layout) + ": rebuild both against the same definition of '" + d.name + "'");
    }
  }
  for (const auto& t : m.types) plugin_types_.emplace(t.name, slot);
  return slot;
}

void Registry::load_plugin(const fs::path& file) {
  for (const auto& slot : plugins_)
    if (slot->file == file.string()) return ensure_loaded(*slot);  // found on the path before
  ensure_loaded(*add_plugin(file));
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
      if (ec) canonical = p;  // a symbolic link that loops: reported by add_plugin
      if (!seen.insert(canonical).second) continue;
      if (p.extension() == ".so") {
        try {
          add_plugin(p);
        } catch (const PluginError& e) {
          errors.push_back(e);
        }
      } else if (p.extension() == ".yaml" || p.extension() == ".yml") {
        composites.push_back(p);
      }
    }
  }
  // Composites are known by name only, after every plugin: a task that uses one reads it then
  // (find), so its inner types' plugins are loaded only for the tasks that use it.
  for (const auto& c : composites) {
    try {
      const std::string name = composite_file_type(c);
      if (std::string first; has_type(name, &first))
        throw std::logic_error("component type '" + name + "' is registered twice: by " + first + " and by " + c.string());
      auto slot = std::make_shared<CompositeSlot>();
      slot->file = c;
      composite_files_.emplace(name, std::move(slot));
    } catch (const std::exception& e) {
      errors.emplace_back(c.string(), std::string("composite not usable: ") + e.what());
    }
  }
  return errors;
}

std::shared_ptr<const TypeEntry> Registry::resolve_composite(CompositeSlot& slot) const {
  std::lock_guard lock(composite_mutex);
  if (!slot.entry && slot.error.empty()) {
    if (slot.reading)
      throw PluginError(slot.file.string(), "composite not usable: it contains itself, through the composites it uses");
    slot.reading = true;
    try {
      slot.entry = read_composite_file(*this, slot.file);
    } catch (const PluginError& e) {  // an inner type's plugin, or a composite it uses
      slot.error = "composite not usable: it uses " + e.file() + ", which cannot be used: " + e.reason();
    } catch (const std::exception& e) {
      slot.error = std::string("composite not usable: ") + e.what();
    }
    slot.reading = false;
  }
  if (!slot.error.empty()) throw PluginError(slot.file.string(), slot.error);
  return slot.entry;
}

std::shared_ptr<const TypeEntry> Registry::find(std::string_view type_name) const {
  if (auto it = types_.find(type_name); it != types_.end()) return it->second;
  if (auto c = composite_files_.find(type_name); c != composite_files_.end()) return resolve_composite(*c->second);
  auto it = plugin_types_.find(type_name);
  if (it == plugin_types_.end()) return nullptr;
  PluginSlot& slot = *it->second;
  try {
    ensure_loaded(slot);
  } catch (const PluginError& e) {
    throw PluginError(e.file(), e.reason() + " (it provides component type '" + std::string(type_name) + "')");
  }
  return slot.entries.at(std::string(type_name));
}

std::vector<const TypeEntry*> Registry::types() const {
  std::vector<const TypeEntry*> out;
  for (const auto& [_, t] : types_) out.push_back(t.get());
  for (const auto& [_, c] : composite_files_) {
    try {
      out.push_back(resolve_composite(*c).get());
    } catch (const PluginError&) {  // load_path or a task's find() reports it
    }
  }
  for (const auto& slot : plugins_) {
    std::lock_guard lock(slot->mutex);
    if (slot->loaded)
      for (const auto& [_, t] : slot->entries) out.push_back(t.get());
  }
  return out;
}

std::vector<std::string> Registry::type_names() const {
  std::vector<std::string> out;
  for (const auto& [name, _] : types_) out.push_back(name);
  for (const auto& [name, _] : plugin_types_) out.push_back(name);
  for (const auto& [name, _] : composite_files_) out.push_back(name);
  std::sort(out.begin(), out.end());
  return out;
}

std::string Registry::interface_json(std::string_view type_name) const {
  if (auto it = types_.find(type_name); it != types_.end()) return detail::spec_json(it->second->spec);
  if (auto it = composite_files_.find(type_name); it != composite_files_.end()) {
    try {
      return detail::spec_json(resolve_composite(*it->second)->spec);
    } catch (const PluginError&) {
      return "";
    }
  }
  if (auto it = plugin_types_.find(type_name); it != plugin_types_.end())
    for (const auto& t : it->second->manifest.types)
      if (t.name == type_name) return t.interface;
  return "";
}

std::vector<PluginRecord> Registry::plugins() const {
  std::vector<PluginRecord> out;
  for (const auto& slot : plugins_) {
    std::lock_guard lock(slot->mutex);
    PluginRecord r{slot->file, slot->manifest.name, slot->manifest.fba_version, {}, slot->error, slot->loaded};
    for (const auto& t : slot->manifest.types) r.types.push_back(t.name);
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<DataTypeRecord> Registry::data_types() const {
  std::map<std::string, DataTypeRecord, std::less<>> by_name;
  // The built-in types are listed even when no plugin on the path uses them.
  type_of<std::int64_t>(), type_of<double>(), type_of<std::string>(), type_of<Event>();
  for (const TypeInfo* t : registered_types())
    if (t != any_type()) by_name[t->name] = DataTypeRecord{t->name, t->doc, t->header, t->layout, {}};
  for (const auto& slot : plugins_)
    for (const auto& d : slot->manifest.data_types) {
      auto& r = by_name[d.name];
      if (r.name.empty()) r = DataTypeRecord{d.name, d.doc, d.header, d.layout, {}};
      if (!r.layout.known()) r.layout = d.layout;
      r.used_by.push_back(slot->file);
    }
  std::vector<DataTypeRecord> out;
  for (auto& [_, r] : by_name) out.push_back(std::move(r));
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
  for (const auto& name : type_names()) scored.emplace_back(edit_distance(type_name, name), name);
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
