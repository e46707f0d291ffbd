// Component types by name: from plugins (shared objects), composites (YAML) and, in tests,
// from the program itself.
//
// Plugins are lazy. Registry::load_path reads each plugin's manifest ("fba-x.manifest.json",
// written beside "fba-x.so" at build time) and the ELF header of the .so, and checks the ABI
// record, the file and the data-type layouts from them, without running any of the plugin's
// code. A plugin is dlopen'ed only when a type it provides is looked up with find(), that is,
// when a task (or its check) uses it; so a broken plugin fails only the tasks that need it. A
// .so without a manifest is refused with a message saying so: fba never runs code it has not
// checked first. Plugins are never unloaded (RTLD_NODELETE), so nothing made by a plugin (a
// component, a payload and its deleter) can outlive its code.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "fba/component.hpp"
#include "fba/data_type.hpp"
#include "fba/spec.hpp"

namespace fba {

struct CompositeDef;  // task_config.hpp
namespace detail {
struct PluginSlot;     // registry.cpp
struct CompositeSlot;  // registry.cpp
}

// A loaded shared object. It stays mapped for the life of the process (see above).
class Library {
 public:
  explicit Library(void* handle, std::string file) : handle_(handle), file_(std::move(file)) {}
  Library(const Library&) = delete;
  Library& operator=(const Library&) = delete;
  void* symbol(const char* name) const;
  const std::string& file() const { return file_; }

 private:
  void* handle_;
  std::string file_;
};

using Factory = std::unique_ptr<Component> (*)(Context&);

struct TypeEntry {
  Spec spec;
  Factory make = nullptr;                         // null for composites
  std::shared_ptr<const CompositeDef> composite;  // set for composites
  std::shared_ptr<const Library> library;         // null when built into the program
  std::string origin;                             // plugin file, composite file, or "built-in"
};

struct PluginRecord {
  std::string file;
  std::string name;
  std::string version;
  std::vector<std::string> types;
  std::string error;    // why it cannot be used; empty when it can
  bool loaded = false;  // dlopen'ed (a task used it)
};

// A data type known from the program or from a plugin's manifest.
struct DataTypeRecord {
  std::string name, doc, header;
  TypeLayout layout;
  std::vector<std::string> used_by;  // plugin files whose ports use it
};

// A plugin that cannot be used: names the file and the reason.
class PluginError : public std::runtime_error {
 public:
  PluginError(std::string file, std::string reason)
      : std::runtime_error(file + ": " + reason), file_(std::move(file)), reason_(std::move(reason)) {}
  const std::string& file() const { return file_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string file_, reason_;
};

class Registry {
 public:
  Registry();
  ~Registry();
  Registry(Registry&&) noexcept;
  Registry& operator=(Registry&&) noexcept;

  // Validates the spec; a name registered twice is an error naming both origins, and so is a
  // blocking type that does not implement Component::interrupt().
  void add(Spec spec, Factory make, std::string origin, std::shared_ptr<const Library> library = {},
           bool implements_interrupt = false);
  // The single place that checks a spec and makes its entry: add() and plugin loading use it.
  static std::shared_ptr<const TypeEntry> make_entry(Spec spec, Factory make, std::string origin,
                                                     std::shared_ptr<const Library> library, bool implements_interrupt);
  void add_composite(Spec spec, std::shared_ptr<const CompositeDef> def, std::string origin);
  // Registers what FBA_COMPONENT collected in this program (tests, static builds).
  void add_builtin(const std::vector<detail::ComponentEntry>& entries, const std::string& origin = "built-in");

  // Checks one plugin from its manifest and loads it now; throws PluginError.
  void load_plugin(const std::filesystem::path& file);
  // Reads every plugin's manifest (*.so) and every composite's name (*.yaml) in the folders, in
  // order; returns the failures instead of stopping at the first, so a user sees all of them.
  // Loads no plugin code: a composite is read whole, and its inner types looked up, on first use.
  std::vector<PluginError> load_path(const std::vector<std::filesystem::path>& dirs);

  // Tasks hold their types (specs, factories, libraries) themselves: a task outlives the
  // registry it was loaded from. Loads the type's plugin on first use; throws PluginError when
  // that plugin (or a composite found on the path) cannot be used. nullptr for an unknown name.
  std::shared_ptr<const TypeEntry> find(std::string_view type_name) const;
  // Built-in, composite and already loaded plugin types (plugins() lists the others). Reads the
  // composites found on the path, loading the plugins their inner types come from.
  std::vector<const TypeEntry*> types() const;
  // Every known type name, including those of plugins not loaded yet.
  std::vector<std::string> type_names() const;
  // A type's interface as JSON (see fba-inspect --json), from its plugin's manifest when the
  // plugin is not loaded; empty for an unknown name. Loads a plugin only for a composite found on
  // the path, which is read then (see types()).
  std::string interface_json(std::string_view type_name) const;
  std::vector<PluginRecord> plugins() const;
  std::vector<DataTypeRecord> data_types() const;
  // Known type names closest to a misspelt one, for "did you mean".
  std::vector<std::string> closest(std::string_view type_name, std::size_t n = 3) const;

 private:
  // Reads and checks a plugin's manifest and file; registers its types as not loaded yet.
  std::shared_ptr<detail::PluginSlot> add_plugin(const std::filesystem::path& file);
  bool has_type(std::string_view name, std::string* origin = nullptr) const;

  std::map<std::string, std::shared_ptr<const TypeEntry>, std::less<>> types_;
  std::map<std::string, std::shared_ptr<detail::PluginSlot>, std::less<>> plugin_types_;
  std::vector<std::shared_ptr<detail::PluginSlot>> plugins_;
  std::map<std::string, std::shared_ptr<detail::CompositeSlot>, std::less<>> composite_files_;
  // A composite found on the path, read whole on first use; throws PluginError.
  std::shared_ptr<const TypeEntry> resolve_composite(detail::CompositeSlot& slot) const;
};

// The plugin file whose code runs for the first time on the calling thread (dlopen, its static
// initialisers, its specs), for crash and exit reports: a plugin that crashes or exits while it
// loads is named. Null when none. Async-signal-safe: it only reads a thread-local pointer.
const char* plugin_being_loaded() noexcept;

// FBA_PLUGIN_PATH (colon-separated), then extra folders, then the plugins installed beside the
// running executable (<prefix>/bin/../<libdir>/fba/plugins), which the build tree mirrors.
std::vector<std::filesystem::path> plugin_search_path(const std::vector<std::filesystem::path>& extra = {});

}  // namespace fba
