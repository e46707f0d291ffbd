// Parameter checking (see param_checking.hpp): the rules of each parameter type, range and
// choices, over plain values.
#include "param_checking.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <system_error>

#include "fba/message_text.hpp"

namespace fba::loader {

namespace fs = std::filesystem;

namespace {

ParamCheck refused(std::string message) { return ParamCheck{std::nullopt, std::move(message)}; }
ParamCheck passed(Value v) { return ParamCheck{std::move(v), {}}; }

ParamCheck expected(const ParamSpec& ps, const std::string& what, const std::string& found) {
  return refused("parameter '" + ps.name + "' expects " + what + "; found " + found);
}

}  // namespace

const char* kind_text(WrittenValue::Kind kind) {
  switch (kind) {
    case WrittenValue::Kind::Nothing: return "nothing";
    case WrittenValue::Kind::Scalar: return "a scalar";
    case WrittenValue::Kind::List: return "a list";
    case WrittenValue::Kind::Mapping: return "a mapping";
    default: return "an undefined node";
  }
}

std::string list_of(const std::vector<std::string>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
  return s.empty() ? "(none)" : s;
}

bool parse_double(const std::string& s, double& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(out);
}

ParamCheck check_constraints(const ParamSpec& ps, Value v) {
  auto range_text = [&] {
    return "[" + (ps.min ? number_text(*ps.min) : std::string("-inf")) + ", " + (ps.max ? number_text(*ps.max) : std::string("inf")) + "]";
  };
  auto in_range = [&](double x) { return (!ps.min || x >= *ps.min) && (!ps.max || x <= *ps.max); };
  if (auto* i = std::get_if<std::int64_t>(&v); i && !in_range(static_cast<double>(*i)))
    return refused("parameter '" + ps.name + "' must be in " + range_text() + "; found " + std::to_string(*i));
  if (auto* d = std::get_if<double>(&v); d && !in_range(*d))
    return refused("parameter '" + ps.name + "' must be in " + range_text() + "; found " + number_text(*d));
  if (auto* l = std::get_if<std::vector<double>>(&v))
    for (double x : *l)
      if (!in_range(x))
        return refused("every element of parameter '" + ps.name + "' must be in " + range_text() + "; found " + number_text(x));
  if (auto* s = std::get_if<std::string>(&v); s && !ps.choices.empty() &&
                                               std::find(ps.choices.begin(), ps.choices.end(), *s) == ps.choices.end())
    return refused("parameter '" + ps.name + "' must be one of: " + list_of(ps.choices) + "; found '" + *s + "'");
  return passed(std::move(v));
}

ParamCheck check_bound_value(const ParamSpec& ps, Value bound) {
  // A composite parameter passed straight through keeps its type; ints widen to doubles.
  if (ps.type == ParamType::Double && std::holds_alternative<std::int64_t>(bound)) bound = static_cast<double>(std::get<std::int64_t>(bound));
  const bool ok = (ps.type == ParamType::Bool && std::holds_alternative<bool>(bound)) ||
                  (ps.type == ParamType::Int && std::holds_alternative<std::int64_t>(bound)) ||
                  (ps.type == ParamType::Double && std::holds_alternative<double>(bound)) ||
                  ((ps.type == ParamType::String || ps.type == ParamType::Path) && std::holds_alternative<std::string>(bound)) ||
                  (ps.type == ParamType::DoubleList && std::holds_alternative<std::vector<double>>(bound));
  if (!ok) return expected(ps, std::string("a ") + to_string(ps.type), "'" + to_string(bound) + "' (from a parameter)");
  if (ps.type != ParamType::Path) return check_constraints(ps, std::move(bound));
  return passed(std::move(bound));  // resolved where it was written
}

ParamCheck check_param_value(const ParamSpec& ps, const WrittenValue& n, const PathBase& base) {
  if (ps.type == ParamType::DoubleList) {
    if (n.kind != WrittenValue::Kind::List) return expected(ps, "a list of numbers like [1, 2.5]", kind_text(n.kind));
    std::vector<double> list;
    for (const auto& e : n.elements) {
      double d = 0;
      const bool scalar = e.kind == WrittenValue::Kind::Scalar;
      if (!scalar || !parse_double(e.text, d))
        return expected(ps, "a list of numbers", "an element '" + (scalar ? e.text : std::string(kind_text(e.kind))) + "'");
      list.push_back(d);
    }
    return check_constraints(ps, Value(list));
  }
  if (n.kind != WrittenValue::Kind::Scalar) return expected(ps, std::string("a ") + to_string(ps.type), kind_text(n.kind));
  const std::string& s = n.text;
  switch (ps.type) {
    case ParamType::Bool:
      if (s == "true" || s == "yes" || s == "on") return passed(Value(true));
      if (s == "false" || s == "no" || s == "off") return passed(Value(false));
      return expected(ps, "true or false", "'" + s + "'");
    case ParamType::Int: {
      std::int64_t i = 0;
      auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), i);
      if (ec != std::errc() || p != s.data() + s.size()) return expected(ps, "a whole number", "'" + s + "'");
      return check_constraints(ps, Value(i));
    }
    case ParamType::Double: {
      double d = 0;
      if (!parse_double(s, d)) return expected(ps, "a number", "'" + s + "'");
      return check_constraints(ps, Value(d));
    }
    case ParamType::String:
      return check_constraints(ps, Value(s));
    case ParamType::Path: {
      if (s.empty()) return expected(ps, "a path", "an empty string");
      fs::path p(s);
      if (p.is_relative()) p = (base.dir / p).lexically_normal();
      std::error_code ec;
      if (!fs::exists(p, ec))
        return refused("parameter '" + ps.name + "': path '" + s + "' does not exist (relative to " + base.name + ": " + p.string() + ")");
      return passed(Value(p.string()));
    }
    case ParamType::DoubleList:
      break;  // read above
  }
  return refused("parameter '" + ps.name + "' has a type the loader does not know");
}

}  // namespace fba::loader
