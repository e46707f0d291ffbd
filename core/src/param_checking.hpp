// Parameter checking: a value written for a parameter (in a task, composite or profile file, or by
// a --set) read by the parameter's type and checked against its range and choices. Free of YAML:
// the loader hands over the value as written (a scalar's text, a list's elements, or the kind of
// node found instead), so these rules are one function a test calls directly with plain values.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "fba/spec.hpp"
#include "fba/value.hpp"

namespace fba::loader {

// A parameter's value as written, without YAML.
struct WrittenValue {
  enum class Kind { Scalar, List, Mapping, Nothing, Undefined };
  Kind kind = Kind::Scalar;
  std::string text;                    // a scalar's text
  std::vector<WrittenValue> elements;  // a list's elements
};
// How messages name a kind: "a scalar", "a list", "a mapping", "nothing", "an undefined node".
const char* kind_text(WrittenValue::Kind kind);

// Where a relative path resolves: the folder of the file it is written in (the working folder for
// a --set), and how messages name what it is relative to ("the task file").
struct PathBase {
  std::filesystem::path dir;
  std::string name;
};

// A value that passed, or why not: "parameter 'count' must be in [0, inf]; found -1".
struct ParamCheck {
  std::optional<Value> value;
  std::string error;  // set when value is empty
};

// A value written for parameter `ps`, read by its type (bool, int, double, string, path, list of
// numbers) and checked against its range and choices; a relative path resolves against `base`
// and must exist.
ParamCheck check_param_value(const ParamSpec& ps, const WrittenValue& written, const PathBase& base);
// A value passed whole from a task or composite parameter (`"${name}"`): it keeps its type (an
// int widens to a double), which must be the parameter's, and its range and choices apply.
ParamCheck check_bound_value(const ParamSpec& ps, Value bound);
// The range and choices of `ps` applied to a value of its type.
ParamCheck check_constraints(const ParamSpec& ps, Value v);

// A finite number as a whole string ("2.5", "1e3"); false for anything else.
bool parse_double(const std::string& s, double& out);

// Names joined for a message ("a, b, c"), or "(none)".
std::string list_of(const std::vector<std::string>& v);

}  // namespace fba::loader
