// The task loader's Loader: it reads a task's YAML (and the composites, profile and --set values
// it uses) into a flat TaskConfig, collecting every problem as a Diagnostic. Its stages share the
// diagnostics, the --set options and the types found, so they are one class whose members are
// defined by stage: task_loader.cpp (the pipeline, diagnostics, the generic readers),
// task_params.cpp (the task's and its profile's parameters, the profile), expansion.cpp
// (includes, composites, components and their parameters), graph_checking.cpp (connections,
// triggers, error policies, event rules). The stages free of YAML are yaml_reading.hpp's reading,
// param_checking.hpp and graph_checking.hpp. Not part of the public API.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "fba/task_config.hpp"
#include "overrides.hpp"
#include "param_checking.hpp"
#include "yaml_reading.hpp"

namespace fba {

struct CompositeDef {
  std::filesystem::path file;  // absolute, for includes and relative paths inside
  std::string shown;           // as messages name it
  YAML::Node root;
};

namespace loader {

template <class V>
std::vector<std::string> names_of(const V& v) {
  std::vector<std::string> out;
  for (const auto& x : v) out.push_back(x.name);
  return out;
}

struct Endpoint {
  std::string comp, port;
};

// What a composite instance exports, in terms of flattened inner names.
struct Exports {
  std::map<std::string, Endpoint> inputs, outputs, events;
};

using Bindings = std::map<std::string, Value>;

// A YAML node as the value written for a parameter, for the checks free of YAML.
WrittenValue written_value(const YAML::Node& n);

class Loader {
 public:
  Loader(const Registry& registry, const LoadOptions& options);

  TaskConfig load(const YAML::Node& root, const Source& src, const fs::path& file);

  std::vector<Diagnostic>& diags() { return diags_; }

  // Parses a composite file's interface into a Spec (registration and inspection), its errors in `d`.
  Spec composite_spec_public(const CompositeDef& def, std::vector<Diagnostic>& d);

 private:
  // A lossless queue of this many samples is already more memory than most hosts should give one
  // connection; more is a mistake (an extra zero) rather than a design.
  static constexpr std::int64_t kMaxCapacity = 1000000;
  // A byte budget per connection (0: none); 1 TiB is far beyond any host, so more is a typo.
  static constexpr std::int64_t kMaxBytesBudget = std::int64_t{1} << 40;
  // Periods are int64 nanoseconds at run time; this keeps every deadline far from overflow.
  static constexpr double kMaxPeriodSeconds = 1e9;

  // The first kMaxShown errors are kept, and the rest counted: a file with thousands of mistakes
  // gets a screenful and the total, not thousands of lines.
  static constexpr std::size_t kMaxShown = 100;

  // --- diagnostics and generic readers (task_loader.cpp) ---------------------------------------

  // An error about a value that takes a task parameter given by --set is said at the --set, with
  // the place in the file: the value typed is what the user must change.
  void error(Location where, std::string message, bool blame_set = true);

  void report_mappings(const YAML::Node& root, const Source& src);

  std::vector<Diagnostic> all_diagnostics() const;

  void check_keys(const YAML::Node& map, const Source& src, const std::vector<std::string>& allowed);

  std::string scalar(const YAML::Node& n, const Source& src, const std::string& what);

  std::int64_t integer(const YAML::Node& n, const Source& src, const std::string& what, std::int64_t lo, std::int64_t hi);

  // Errors point at `place`: a value made by substituting composite parameters has no position.
  std::int64_t integer(const YAML::Node& n, const YAML::Node& place, const Source& src, const std::string& what, std::int64_t lo,
                       std::int64_t hi);

  // --- task parameters and profiles (task_params.cpp) -----------------------------------------

  // The profile files next to a task (profiles/*.yaml), by name.
  static std::vector<std::string> available_profiles(const fs::path& task_dir);

  static std::vector<std::string> slot_names(const YAML::Node& comps);

  // `executor:` of a task file or of a profile.
  void read_executor(const YAML::Node& n, const Source& src, TaskConfig& task);

  // Finds and reads the profile (--profile, else the task's `profile:`); a task with slots needs one.
  void load_profile(const YAML::Node& root, const Source& src, TaskConfig& task);

  // The profile's entry for a slot: its key and its value.
  std::optional<std::pair<YAML::Node, YAML::Node>> profile_entry(const std::string& slot) const;

  // The task's and the profile's parameters: declared, then given by --set NAME=VALUE or their
  // defaults. They are the bindings of ${name} in the task's components and the profile's.
  Bindings task_params(const YAML::Node& root, const Source& src, TaskConfig& task);

  // A --set's value for parameter `ps`, checked as a value in the file would be; a relative path
  // means the working folder, as in the shell that gave it.
  std::optional<Value> set_value(const SetOption& o, const ParamSpec& ps);

  // Every value of the task's (or the profile's) components and connections that refers to the
  // task parameters `declared`: what each --set may mean depends on where they are used.
  void collect_uses(const YAML::Node& root, const Source& src, const std::set<std::string>& declared);

  void note_uses(const YAML::Node& n, const Source& src, const std::string& what, const std::set<std::string>& declared,
                 std::set<std::tuple<int, int, bool>>& seen, bool component_param = false);

  // A profile binds the task's slots and nothing else.
  void check_profile_bindings(const YAML::Node& root, const Source& src, const TaskConfig& task);

  // The parameters a composite, a task or a profile declares: `name: {type, default, min, max, doc}`.
  // grouped: names may join words with dots (a task's and a profile's; a composite's parameters are
  // set as instance.parameter, where a dot would read as another component's).
  std::vector<std::pair<ParamSpec, Location>> param_decls(const YAML::Node& params, const Source& src, const std::string& owner,
                                                          bool grouped, std::vector<Diagnostic>& d);

  // --- includes, composites, components and their parameters (expansion.cpp) ------------------

  std::shared_ptr<const TypeEntry> find_type(const std::string& name) const;

  std::vector<std::string> suggest(const std::string& name) const;

  // Returns false when an include cycle was found below `root`: the composites on the cycle are
  // then left out quietly, as their missing types would only repeat the cycle's one error.
  bool load_includes(const YAML::Node& root, const Source& src, std::set<std::string>& stack);

  Spec composite_spec_checked(const CompositeDef& def);

  Spec composite_spec_impl(const CompositeDef& def, std::vector<Diagnostic>& d);

  std::string unknown_reference(const std::string& name, const Bindings& b) const;

  // Substitutes ${name} from a composite's (or the task's) bindings; nullopt when a name is unknown (reported
  // here, so that the caller does not report the unsubstituted text as a bad value as well).
  std::optional<YAML::Node> substitute(const YAML::Node& n, const Bindings& b, const Source& src, bool& whole, Value& whole_value);

  // A setting of the task itself (not a component parameter) after substitution: the text a
  // literal would have, so that it is checked by the same rules, range included.
  std::optional<YAML::Node> substituted(const YAML::Node& n, const Bindings& b, const Source& src);

  // A scalar setting after substitution; empty when it is missing or not a scalar (reported).
  std::string text_of(const YAML::Node& n, const Bindings& b, const Source& src, const std::string& what);

  // A component parameter's value: ${...} substituted, then checked (param_checking.hpp).
  std::optional<Value> param_value(const ParamSpec& ps, const YAML::Node& raw, const Source& src, const Bindings& bindings);

  // Reads a component's params against its spec; fills defaults; applies --set overrides.
  std::map<std::string, Value> read_params(const std::string& full, const Spec& spec, const YAML::Node& params, const Source& src,
                                           const Bindings& bindings, const Location& comp_where);

  // The spec's checks of the resolved values (list lengths, cross-parameter rules): reported at
  // the parameter they are about when the file sets it, else at the component.
  void check_params(const ComponentConfig& cc, const YAML::Node& params, const Source& src);

  // One component of `body` (or the one a profile binds to a slot, read with the profile's Source).
  void read_component(const std::string& name, const std::string& full, const YAML::Node& c, const Source& src, const Location& where,
                      const Bindings& bindings, TaskConfig& task, const std::vector<std::string>& composite_stack);

  void expand(const YAML::Node& body, const Source& src, const std::string& prefix, const Bindings& bindings, TaskConfig& task,
              std::vector<std::string> composite_stack);

  // --- connections, triggers, error policies and rules (graph_checking.cpp) -------------------

  Endpoint resolve(const Endpoint& e, bool input) const;

  std::optional<Endpoint> endpoint(const std::string& text, const YAML::Node& n, const Source& src, const std::string& prefix);

  // Checks a port exists on a component (or exported by a composite instance).
  bool check_port(const Endpoint& e, bool input, const YAML::Node& n, const Source& src, const std::string& prefix);

  void read_trigger(const YAML::Node& t, const Source& src, const Bindings& bindings, ComponentConfig& cc);

  void read_error_policy(const YAML::Node& e, const Source& src, const Bindings& bindings, ComponentConfig& cc);

  void read_connection(const YAML::Node& n, const Source& src, const std::string& prefix, const Bindings& bindings, TaskConfig& task);

  void read_rule(const YAML::Node& key, const YAML::Node& value, const Source& src, const std::string& prefix, TaskConfig& task);

  const Registry& registry_;
  bool require_inputs_ = true;
  std::vector<Diagnostic> diags_;
  std::size_t more_ = 0;   // errors beyond kMaxShown
  Location first_hidden_;  // where the first of them is
  Overrides overrides_;
  std::map<std::string, std::shared_ptr<const TypeEntry>, std::less<>> local_types_;
  std::set<std::string> included_;
  std::set<std::string> broken_types_;  // composites whose definition has errors (reported)
  std::map<std::string, const Spec*> kinds_;  // every instance, composites included; null: could not be read
  std::map<std::string, Exports> exports_;
  struct Profile {
    bool loaded = false;
    std::string name;
    Source src;
    YAML::Node root, components;
  };
  std::string profile_option_;
  bool profile_given_ = false;
  Profile profile_;
  const Bindings* task_bindings_ = nullptr;  // the task's (not a composite's): names them in messages
  std::set<std::string> failed_params_;  // task parameters without a value (reported): their uses are not reported again
};

}  // namespace loader
}  // namespace fba
