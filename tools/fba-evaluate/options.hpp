// fba-evaluate's command-line options, declared one way in every subcommand: a number option is
// declared with its range (`ranged`) and checked when the line is read, so a bad value is refused
// with the option's name, what was expected and what was found, and exit status 2, as fba-run
// refuses a bad parameter.
#pragma once

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <string>
#include <type_traits>
#include <vector>

#include <boost/program_options.hpp>

namespace fba::evaluate {

namespace po = boost::program_options;

// A command line that asks for nothing sensible: reported as boost's own parse errors are, with
// exit status 2, like a bad task file.
struct ArgumentError : po::error {
  using po::error::error;
};

// The shortest text that reads back as v: a range message must not round 1000001 to 1e+06.
inline std::string number(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

template <class T>
std::string number_text(T v) {
  if constexpr (std::is_floating_point_v<T>) return number(v);
  else return std::to_string(v);
}

// --name must be in [lo, hi] (which also refuses NaN); for bounds that depend on another option.
template <class T>
void check_range(const std::string& name, T v, T lo, T hi) {
  if (!(v >= lo && v <= hi))
    throw ArgumentError("--" + name + " must be in [" + number_text(lo) + ", " + number_text(hi) + "]; found " + number_text(v));
}

// The option --name, a number of T's kind in [lo, hi], stored in *target (whose value is the
// default). It is read as text and converted here, because boost would read "-1" into an unsigned
// as 2^64-1 and take "nan" for a double.
template <class T>
po::typed_value<std::string>* ranged(const char* name, T* target, T lo, T hi) {
  static_assert(std::is_arithmetic_v<T>);
  return po::value<std::string>()->default_value(number_text(*target))->notifier([=](const std::string& text) {
    const std::string range = "[" + number_text(lo) + ", " + number_text(hi) + "]";
    const std::string kind = std::is_floating_point_v<T> ? "a number" : "an integer";
    T v{};
    bool read = false;
    if constexpr (std::is_floating_point_v<T>) {
      // strtod: also "nan" and "inf", which the range then refuses by name.
      char* end = nullptr;
      v = static_cast<T>(std::strtod(text.c_str(), &end));
      read = !text.empty() && !std::isspace(static_cast<unsigned char>(text[0])) && end == text.c_str() + text.size();
    } else {
      const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
      read = r.ec == std::errc() && r.ptr == text.data() + text.size();
    }
    if (!read) throw ArgumentError("--" + std::string(name) + " must be " + kind + " in " + range + "; found '" + text + "'");
    check_range(name, v, lo, hi);
    *target = v;
  });
}

// A list option of `count` finite numbers (a box, a pose): the size and each value checked.
inline void check_finite_numbers(const std::string& name, const std::vector<double>& v, std::size_t count, const std::string& what) {
  if (v.size() != count)
    throw ArgumentError("--" + name + " needs " + std::to_string(count) + " numbers (" + what + "); found " + std::to_string(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      throw ArgumentError("--" + name + " needs finite numbers (" + what + "); number " + std::to_string(i + 1) + " is " + number(v[i]));
}

// Parses `args` with boost's GNU-style rules, except that "-0.08" (or "-inf") is a (negative)
// value, not an option: boost's single-dash options are turned off, a declared short option (-h, -j 4, -j4) is
// read as its long name, and any other word after a single dash is refused here (else a
// multi-token option such as --mesh would take it).
inline po::variables_map parse(std::vector<std::string> args, const po::options_description& opts) {
  std::vector<std::string> out;
  for (const auto& a : args) {
    char* end = nullptr;
    std::strtod(a.c_str(), &end);
    const bool a_number = !a.empty() && end == a.c_str() + a.size();  // also "-inf" and "-nan", which a range refuses by name
    const bool dash_word = !a_number && a.size() > 1 && a[0] == '-' && a[1] != '-';
    if (!dash_word) {
      out.push_back(a);
      continue;
    }
    const po::option_description* found = nullptr;
    for (const auto& d : opts.options())
      if (d->canonical_display_name(po::command_line_style::allow_dash_for_short) == a.substr(0, 2)) found = d.get();
    if (!found || found->long_name().empty()) throw ArgumentError("unrecognised option '" + a + "'");
    out.push_back("--" + found->long_name());
    if (a.size() > 2) out.push_back(a.substr(2));
  }
  po::variables_map vm;
  po::store(po::command_line_parser(out)
                .options(opts)
                .style(po::command_line_style::unix_style ^ po::command_line_style::allow_short)
                .run(),
            vm);
  return vm;
}

}  // namespace fba::evaluate
