// A task as loaded from YAML: flattened (composites expanded), fully checked, ready to build.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "fba/registry.hpp"
#include "fba/spec.hpp"
#include "fba/value.hpp"

namespace fba {

struct Location {
  std::string file;  // as the user named it
  int line = 0;      // 1-based; 0 when unknown
  int column = 0;    // 1-based
  std::string str() const;
};

struct Diagnostic {
  Location where;
  std::string message;
  std::string str() const { return where.str() + ": error: " + message; }
};

// Everything wrong with a task file, each with file, line and column.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(std::vector<Diagnostic> diagnostics);
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }

 private:
  std::vector<Diagnostic> diagnostics_;
};

enum class BufferPolicy {
  Latest,      // keep only the newest sample; never blocks the producer
  Lossless,    // bounded queue; a full queue holds the producer back, nothing is dropped
  DropOldest,  // bounded queue; when full the oldest sample is dropped (and counted)
};
const char* to_string(BufferPolicy p);

enum class ErrorPolicy { Stop, Restart };
enum class ExecutorKind { Threaded, Deterministic };
const char* to_string(ExecutorKind k);

struct ComponentConfig {
  std::string name;          // "relay/first" inside composite instance "relay"
  std::shared_ptr<const TypeEntry> type;
  std::map<std::string, Value> params;  // complete: defaults filled in, paths resolved
  Trigger trigger;
  ErrorPolicy on_error = ErrorPolicy::Stop;
  int max_restarts = 0;
  bool dedicated_thread = false;
  // Each output's data type as resolved by the check: declared, or that of the input it follows.
  std::map<std::string, const TypeInfo*> output_types;
  Location where;
};

struct ConnectionConfig {
  std::string from, from_port, to, to_port;
  const TypeInfo* type = nullptr;  // resolved
  BufferPolicy policy = BufferPolicy::Lossless;
  std::size_t capacity = 16;
  std::size_t max_bytes = 0;  // payload bytes queued at most (see Packet::bytes); 0 for no budget
  bool feedback = false;  // an explicit back edge of a cycle
  Location where;
};

enum class RuleAction { StopSuccess, StopFailure, Deliver };

struct EventRule {
  std::string source, event;     // component and event name
  RuleAction action = RuleAction::StopSuccess;
  std::string target, target_port;  // Deliver
  Location where;
};

// A task-level parameter (the task's or its profile's `params:`), as it was resolved.
struct TaskParam {
  std::string name;
  ParamType type = ParamType::Int;
  Value value;          // paths resolved
  std::string source;   // "default", "profile default" or "--set"
  std::string doc;
  Location where;       // its declaration
};

// A device slot of the task (`arm: {profile: true}`) and the component type its profile binds.
struct SlotConfig {
  std::string name;  // also the name of the component that fills it
  std::string doc;
  std::shared_ptr<const TypeEntry> type;
  Location where;  // in the task file
  Location bound;  // in the profile
};

struct TaskConfig {
  std::string name;
  std::filesystem::path file;  // the task file
  std::vector<TaskParam> params;
  std::string profile;                  // the profile's name; empty without one
  std::filesystem::path profile_file;
  std::vector<SlotConfig> slots;
  std::vector<ComponentConfig> components;
  std::vector<ConnectionConfig> connections;
  std::vector<EventRule> rules;
  ExecutorKind executor = ExecutorKind::Threaded;
  int threads = 0;  // 0: one per core (at least 2)

  const ComponentConfig* find(std::string_view name) const;
  const SlotConfig* find_slot(std::string_view name) const;
};

// What a component offers the task around it: the part of its spec that must agree for two types
// to be interchangeable (parameters may differ). Ports and events sorted by name.
struct PortInterface {
  std::string name;
  std::string type;  // a data type's name, "any", or "like input 'x'"
  bool required = true;
  bool operator==(const PortInterface&) const = default;
};
struct Interface {
  std::string type;  // the component type
  std::vector<PortInterface> inputs, outputs;
  std::vector<std::string> events;  // declared ones; every type has error and finished too
};
Interface interface_of(const Spec& spec);
// The interface of the type a slot is bound to; throws std::out_of_range for an unknown slot.
Interface slot_interface(const TaskConfig& task, std::string_view slot);
// What differs between two interfaces, one line each ("output 'frame': fba.Image in a, fba.Int in
// b"); empty when they are interchangeable.
std::vector<std::string> interface_differences(const Interface& a, const Interface& b);
// Indented lines for --check: inputs, outputs and events.
std::string describe(const Interface& i);

// "component.param=value", or "name=value" for a task parameter. A string or path parameter takes
// the value as written; any other reads it as YAML (so lists and numbers work).
struct Override {
  std::string text;
};

struct LoadOptions {
  std::vector<Override> overrides;
  bool require_inputs = true;  // the component harness feeds inputs itself
  // The profile binding the task's slots: a name (profiles/NAME.yaml beside the task) or a path
  // (with a '/' or ending in .yaml; relative to the working folder). Empty: the task's `profile:`,
  // unless profile_given.
  std::string profile;
  // --profile was on the command line: an empty name there is a mistake (an unset variable), not
  // the task's own profile, and is refused.
  bool profile_given = false;
};

// Parses, expands composites and checks everything; throws ConfigError listing every problem.
TaskConfig load_task(const std::filesystem::path& file, const Registry& registry, const LoadOptions& options = {});
// The same from text; `name` stands for the file in messages, `dir` resolves relative paths.
TaskConfig load_task_text(const std::string& text, const std::string& name, const std::filesystem::path& dir,
                          const Registry& registry, const LoadOptions& options = {});

// Reads a composite definition (a YAML file with a `composite:` key) and registers it.
// Throws ConfigError.
void register_composite_file(Registry& registry, const std::filesystem::path& file);
// The type name a composite file defines, read without looking up its inner types (so no plugin
// is loaded). Throws ConfigError.
std::string composite_file_type(const std::filesystem::path& file);
// Reads and checks a composite definition against the registry's types (loading the plugins they
// come from); registers nothing. Throws ConfigError.
std::shared_ptr<const TypeEntry> read_composite_file(const Registry& registry, const std::filesystem::path& file);

// The task graph as Graphviz DOT: components by kind, ports, buffer policies, feedback edges
// dashed, composites as clusters, event rules.
std::string to_dot(const TaskConfig& task);

}  // namespace fba
