// Component types by name: from plugins (shared objects), composites (YAML) and, in tests,
// from the program itself.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "fba/component.hpp"
#include "fba/spec.hpp"

namespace fba {

struct CompositeDef;  // task_config.hpp

// A loaded shared object; every component created from it keeps it loaded.
class Library {
 public:
  explicit Library(void* handle, std::string file) : handle_(handle), file_(std::move(file)) {}
  ~Library();
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
  // Validates the spec; a name registered twice is an error naming both origins, and so is a
  // blocking type that does not implement Component::interrupt().
  void add(Spec spec, Factory make, std::string origin, std::shared_ptr<const Library> library = {},
           bool implements_interrupt = false);
  void add_composite(Spec spec, std::shared_ptr<const CompositeDef> def, std::string origin);
  // Registers what FBA_COMPONENT collected in this program (tests, static builds).
  void add_builtin(const std::vector<detail::ComponentEntry>& entries, const std::string& origin = "built-in");

  // Loads one plugin; throws PluginError.
  void load_plugin(const std::filesystem::path& file);
  // Loads every plugin (*.so) and composite (*.yaml) in the folders, in order; returns the
  // failures instead of stopping at the first, so a user sees all of them.
  std::vector<PluginError> load_path(const std::vector<std::filesystem::path>& dirs);

  // Tasks hold their types (specs, factories, libraries) themselves: a task outlives the
  // registry it was loaded from.
  std::shared_ptr<const TypeEntry> find(std::string_view type_name) const;
  std::vector<const TypeEntry*> types() const;
  const std::vector<PluginRecord>& plugins() const { return plugins_; }
  // Known type names closest to a misspelt one, for "did you mean".
  std::vector<std::string> closest(std::string_view type_name, std::size_t n = 3) const;

 private:
  std::map<std::string, std::shared_ptr<const TypeEntry>, std::less<>> types_;
  std::vector<PluginRecord> plugins_;
};

// FBA_PLUGIN_PATH (colon-separated), then extra folders, then the plugins installed beside the
// running executable (<prefix>/bin/../<libdir>/fba/plugins), which the build tree mirrors.
std::vector<std::filesystem::path> plugin_search_path(const std::vector<std::filesystem::path>& extra = {});

}  // namespace fba
