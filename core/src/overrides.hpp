// The --set options of one load: each split once, matched to what it sets, and the ways it can
// disagree with another --set or with the task file refused rather than resolved silently.
#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "fba/task_config.hpp"
#include "fba/value.hpp"

namespace fba {

// A `${name}` reference to a task or composite parameter in a value (name: letters, digits, '_',
// and dots for a task parameter's group).
struct Reference {
  std::size_t pos, len;  // of the whole `${name}`
  std::string name;
};
std::vector<Reference> references_in(const std::string& s);

// One --set: `owner.param=value` (a component's parameter, or a grouped task parameter such as
// scene.mesh) or `name=value` (a task parameter).
struct SetOption {
  std::string text;    // as given
  std::string target;  // before the first '='
  std::string owner;   // the target before its last '.'; empty for a plain name
  std::string param;   // the target after its last '.'
  std::string value;   // after the first '=', as written
  Location where() const { return Location{"--set " + text, 0, 0}; }
};

// Splits one --set; nullopt, with `problem` said, when it is not NAME=VALUE.
std::optional<SetOption> parse_set(const std::string& text, std::string& problem);

// A --set value for a string or path parameter is the value as written, whole: a shell has already
// taken its own quotes off, and '#', spaces or quotes are part of a file name or a label. Values
// of other types are read as YAML (3, 2.5, true, [1, 2]).
bool taken_as_written(ParamType type);

// A value in the task or profile file that refers to task parameters.
struct ParamUse {
  std::string what;              // "carver.max_depth" for a component's parameter, else its key ("capacity")
  bool component_param = false;
  std::string text;              // as written
  Location where;
  std::vector<std::string> names;  // the task parameters it refers to
  bool whole = false;            // exactly one `${name}`: the value is the parameter's own
};

class Overrides {
 public:
  // Splits the options; malformed and repeated ones are in errors().
  explicit Overrides(const std::vector<Override>& options);
  const std::vector<Diagnostic>& errors() const { return errors_; }

  void add_use(ParamUse use);

  // The --set that gives task parameter `name` its value: `--set name=...`, or else a --set of the
  // component parameter that is exactly `${name}` and its only use, so that the value shown for
  // the task parameter is the value that runs. Null when neither is given.
  const SetOption* for_task_param(const std::string& name);

  // The --set of component parameter `target` ("carver.max_depth"), if any, and whether to apply
  // it: not when its task parameter took its value, nor when it is refused (it conflicts with a
  // --set of the task parameter written there, or would split what the file derives from task
  // parameters; `refusal` says why).
  struct ComponentSet {
    const SetOption* option = nullptr;
    bool apply = false;
    std::string refusal;
  };
  ComponentSet for_component_param(const std::string& target);

  // An error at `where`, a value that takes a task parameter given by --set, is that --set's doing:
  // its place, and what the file says there ("carver.max_depth is ${depth} at grasp.yaml:51:26").
  struct Blame {
    Location set;
    std::string use;
  };
  std::optional<Blame> blame(const Location& where) const;

  // The options that matched no parameter so far, in the order given.
  std::vector<const SetOption*> unused() const;
  void mark_used(const SetOption& o) { used_.insert(o.target); }

 private:
  const SetOption* find(const std::string& target) const;
  std::vector<const ParamUse*> uses_of(const std::string& name) const;
  static std::string describe(const ParamUse& u);

  std::vector<SetOption> options_;
  std::vector<Diagnostic> errors_;
  std::vector<ParamUse> uses_;
  std::set<std::string> used_, routed_;  // targets; routed_: given to their task parameter
  std::map<std::string, Blame> blame_;  // by Location::str()
};

}  // namespace fba
