// Parameter checking (core/src/param_checking.cpp): a value is read by its parameter's type and
// checked against its range and choices; through the loader, and the stage called directly with
// values as written, no task file and no YAML.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <fba/task_config.hpp>

#include "param_checking.hpp"
#include "support/build_paths.hpp"
#include "fixture_components.hpp"

using fba::test::errors_of;
using fba::test::load;

TEST(Loader, ParameterTypesAreChecked) {
  EXPECT_NE(errors_of("components:\n  a: { type: examples.counter, params: { count: many } }\n").find("expects a whole number; found 'many'"),
            std::string::npos);
  EXPECT_NE(errors_of("components:\n  a: { type: examples.counter, params: { rate: [1] } }\n").find("expects a double; found a list"),
            std::string::npos);
}

TEST(Loader, ChoicesAreChecked) {
  const auto e = errors_of("components:\n  r: { type: test.reader, params: { file: loader_test.cpp, mode: words } }\n");
  EXPECT_NE(e.find("must be one of: bytes, lines; found 'words'"), std::string::npos) << e;
}

TEST(Loader, RequiredParametersMustBeGiven) {
  const auto e = errors_of("components:\n  r: { type: test.reader }\n");
  EXPECT_NE(e.find("needs parameter 'file'"), std::string::npos) << e;
}

TEST(Loader, RelativePathsResolveAgainstTheTaskFile) {
  const auto task = load("components:\n  r: { type: test.reader, params: { file: loader_test.cpp } }\n");
  const std::string path = std::get<std::string>(task.find("r")->params.at("file"));
  EXPECT_EQ(path, (std::filesystem::path(fba::test::source_dir() + "/core/tests") / "loader_test.cpp").string());
  EXPECT_NE(errors_of("components:\n  r: { type: test.reader, params: { file: nowhere.txt } }\n").find("does not exist"), std::string::npos);
}

TEST(ParamChecking, EachTypeReadsTheTextAsWrittenAndSaysWhatItExpected) {
  using fba::loader::check_param_value;
  using Kind = fba::loader::WrittenValue::Kind;
  const fba::loader::PathBase base{fba::test::source_dir() + "/core/tests", "the task file"};
  const fba::ParamSpec count{.name = "count", .type = fba::ParamType::Int, .min = 0};
  EXPECT_EQ(std::get<std::int64_t>(check_param_value(count, {.text = "42"}, base).value.value()), 42);
  EXPECT_EQ(check_param_value(count, {.text = "many"}, base).error, "parameter 'count' expects a whole number; found 'many'");
  EXPECT_EQ(check_param_value(count, {.text = "-1"}, base).error, "parameter 'count' must be in [0, inf]; found -1");
  EXPECT_EQ(check_param_value(count, {.kind = Kind::Mapping}, base).error, "parameter 'count' expects a int; found a mapping");
  const fba::ParamSpec on{.name = "on", .type = fba::ParamType::Bool};
  EXPECT_EQ(std::get<bool>(check_param_value(on, {.text = "yes"}, base).value.value()), true);
  EXPECT_EQ(check_param_value(on, {.text = "maybe"}, base).error, "parameter 'on' expects true or false; found 'maybe'");
  const fba::ParamSpec rate{.name = "rate", .type = fba::ParamType::Double, .max = 1e6};
  EXPECT_EQ(std::get<double>(check_param_value(rate, {.text = "1e3"}, base).value.value()), 1000.0);
  EXPECT_EQ(check_param_value(rate, {.text = "inf"}, base).error, "parameter 'rate' expects a number; found 'inf'");
  const fba::ParamSpec mode{.name = "mode", .type = fba::ParamType::String, .choices = {"bytes", "lines"}};
  EXPECT_EQ(check_param_value(mode, {.text = "words"}, base).error, "parameter 'mode' must be one of: bytes, lines; found 'words'");
}

TEST(ParamChecking, ListsTakeNumbersAndTheRangeAppliesToEveryElement) {
  using fba::loader::check_param_value;
  using Kind = fba::loader::WrittenValue::Kind;
  const fba::loader::PathBase base{".", "the task file"};
  const fba::ParamSpec gains{.name = "gains", .type = fba::ParamType::DoubleList, .min = 0, .max = 5};
  const auto two = check_param_value(gains, {.kind = Kind::List, .elements = {{.text = "1"}, {.text = "2.5"}}}, base);
  EXPECT_EQ(std::get<std::vector<double>>(two.value.value()), (std::vector<double>{1, 2.5}));
  EXPECT_EQ(check_param_value(gains, {.text = "1"}, base).error, "parameter 'gains' expects a list of numbers like [1, 2.5]; found a scalar");
  EXPECT_EQ(check_param_value(gains, {.kind = Kind::List, .elements = {{.text = "x"}}}, base).error,
            "parameter 'gains' expects a list of numbers; found an element 'x'");
  EXPECT_EQ(check_param_value(gains, {.kind = Kind::List, .elements = {{.kind = Kind::List}}}, base).error,
            "parameter 'gains' expects a list of numbers; found an element 'a list'");
  EXPECT_EQ(check_param_value(gains, {.kind = Kind::List, .elements = {{.text = "1"}, {.text = "6"}}}, base).error,
            "every element of parameter 'gains' must be in [0, 5]; found 6");
}

TEST(ParamChecking, APathResolvesAgainstItsFileAndMustExist) {
  using fba::loader::check_param_value;
  const std::string dir = fba::test::source_dir() + "/core/tests";
  const fba::loader::PathBase base{dir, "the profile file"};
  const fba::ParamSpec file{.name = "file", .type = fba::ParamType::Path};
  EXPECT_EQ(std::get<std::string>(check_param_value(file, {.text = "param_checking_test.cpp"}, base).value.value()),
            (std::filesystem::path(dir) / "param_checking_test.cpp").string());
  EXPECT_EQ(check_param_value(file, {.text = "nowhere.txt"}, base).error,
            "parameter 'file': path 'nowhere.txt' does not exist (relative to the profile file: " +
                (std::filesystem::path(dir) / "nowhere.txt").string() + ")");
  EXPECT_EQ(check_param_value(file, {.text = ""}, base).error, "parameter 'file' expects a path; found an empty string");
}

// A value passed whole from a task or composite parameter keeps its type: an int widens to a
// double, another type is refused, and the range applies as to a literal.
TEST(ParamChecking, AValueBoundFromAParameterKeepsItsType) {
  using fba::loader::check_bound_value;
  const fba::ParamSpec rate{.name = "rate", .type = fba::ParamType::Double, .min = 0};
  EXPECT_EQ(std::get<double>(check_bound_value(rate, fba::Value(std::int64_t{3})).value.value()), 3.0);
  EXPECT_EQ(check_bound_value(rate, fba::Value(std::string("fast"))).error, "parameter 'rate' expects a double; found 'fast' (from a parameter)");
  EXPECT_EQ(check_bound_value(rate, fba::Value(-1.5)).error, "parameter 'rate' must be in [0, inf]; found -1.5");
}
