// Parameter values: the few types a task file can give a component.
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace fba {

enum class ParamType { Bool, Int, Double, String, Path, DoubleList };

// Path values are stored as strings, already resolved against the task file's folder.
using Value = std::variant<bool, std::int64_t, double, std::string, std::vector<double>>;

const char* to_string(ParamType t);
std::string to_string(const Value& v);

// The C++ type a parameter of each kind is read as, for Context::param<T>.
template <class T>
constexpr bool is_param_type_v = std::is_same_v<T, bool> || std::is_same_v<T, std::int64_t> ||
                                 std::is_same_v<T, double> || std::is_same_v<T, std::string> ||
                                 std::is_same_v<T, std::vector<double>>;

template <class T>
constexpr ParamType param_type_of() {
  if constexpr (std::is_same_v<T, bool>) return ParamType::Bool;
  else if constexpr (std::is_same_v<T, std::int64_t>) return ParamType::Int;
  else if constexpr (std::is_same_v<T, double>) return ParamType::Double;
  else if constexpr (std::is_same_v<T, std::string>) return ParamType::String;
  else return ParamType::DoubleList;
}

}  // namespace fba
