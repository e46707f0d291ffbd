// A component type's declaration is checked when it registers; its parameter checks run on
// resolved values.
#include <gtest/gtest.h>

#include <fba/spec.hpp>

using fba::Spec;

namespace {
std::string validation_error(const Spec& s) {
  try {
    s.validate();
  } catch (const std::logic_error& e) {
    return e.what();
  }
  return "";
}

constexpr fba::In<std::int64_t> kIn{"in", ""};
constexpr fba::OptionalIn<std::int64_t> kMaybe{"maybe", ""};
constexpr fba::AnyIn kAny{"in", ""};
constexpr fba::Out<std::int64_t> kOut{"out", ""};
}  // namespace

TEST(Spec, SensorInputsMustBeOptional) {
  EXPECT_NE(validation_error(Spec::sensor("t.s", "").add(kIn, kOut)).find("must be optional"), std::string::npos);
  EXPECT_EQ(validation_error(Spec::sensor("t.s", "").add(kMaybe, kOut)), "");
}

TEST(Spec, ActuatorNeedsInputsAndMayReportOnOutputs) {
  EXPECT_NE(validation_error(Spec::actuator("t.a", "").add(kOut)).find("needs inputs"), std::string::npos);
  EXPECT_EQ(validation_error(Spec::actuator("t.a", "").add(kIn, kOut)), "");  // an arm publishing its joint states
}

TEST(Spec, OnlyAnActuatorDeclaresAConcurrentSafeState) {
  EXPECT_EQ(validation_error(Spec::actuator("t.a", "").add(kIn).concurrent_safe_state()), "");
  EXPECT_NE(validation_error(Spec::filter("t.f", "").add(kIn, kOut).concurrent_safe_state()).find("is for actuators"),
            std::string::npos);
}

TEST(Spec, OutLikeTakesTheTypeOfItsInput) {
  constexpr fba::OutLike kSame{"out", kAny, ""};
  const auto s = Spec::filter("t.f", "").add(kAny, kSame);
  EXPECT_EQ(validation_error(s), "");
  EXPECT_EQ(s.outputs()[0].same_as, "in");
}

TEST(Spec, DefaultMustLieInItsRange) {
  constexpr auto kN = fba::Param<std::int64_t>("n", 20, "").range(0, 10);
  EXPECT_NE(validation_error(Spec::sensor("t.s", "").add(kOut, kN)).find("out of its range"), std::string::npos);
}

TEST(Spec, DefaultMustBeOneOfTheChoices) {
  constexpr auto kMode = fba::Param<std::string>("mode", "fast", "").choices({"slow", "exact"});
  EXPECT_NE(validation_error(Spec::sensor("t.s", "").add(kOut, kMode)).find("choices"), std::string::npos);
}

TEST(Spec, DefaultListMustHaveAnAllowedLength) {
  static const auto kBox = fba::Param<std::vector<double>>("box", {1, 2}, "").size({0, 6});
  EXPECT_NE(validation_error(Spec::sensor("t.s", "").add(kOut, kBox)).find("length"), std::string::npos);
}

TEST(Spec, PortNamesAreUnique) {
  constexpr fba::Out<std::int64_t> kX{"in", ""};
  EXPECT_NE(validation_error(Spec::filter("t.f", "").add(kAny, kX)).find("declared twice"), std::string::npos);
}

TEST(Spec, BuiltInEventsCannotBeRedeclared) {
  constexpr fba::EventOut kError{"error", ""};
  EXPECT_NE(validation_error(Spec::sensor("t.s", "").add(kOut, kError)).find("built-in"), std::string::npos);
}

TEST(Spec, TransitionsNameDeclaredStages) {
  auto s = Spec::filter("t.f", "").add(kAny, kOut).stages({"a", "b"}, {{"a", "c"}});
  EXPECT_NE(validation_error(s).find("undeclared stage"), std::string::npos);
}

TEST(Spec, AnIntParameterIsKeptWithinInt) {
  constexpr fba::Param<int> kN{"n", 1, ""};
  const auto p = kN.spec();
  EXPECT_EQ(*p.min, std::numeric_limits<int>::min());
  EXPECT_EQ(*p.max, std::numeric_limits<int>::max());
  EXPECT_EQ(p.type, fba::ParamType::Int);
}

TEST(Spec, HandlesDeclareTypesDefaultsAndDocs) {
  constexpr auto kRate = fba::Param<double>("rate", 1.5, "per second").range(0, 2);
  constexpr fba::Param<std::filesystem::path> kFile{"file", fba::required, "a file"};
  const auto s = Spec::filter("t.f", "doc").add(kAny, kOut, kRate, kFile);
  EXPECT_EQ(validation_error(s), "");
  ASSERT_EQ(s.params().size(), 2u);
  EXPECT_EQ(std::get<double>(*s.params()[0].default_value), 1.5);
  EXPECT_EQ(*s.params()[0].max, 2);
  EXPECT_EQ(s.params()[0].doc, "per second");
  EXPECT_EQ(s.params()[1].type, fba::ParamType::Path);
  EXPECT_TRUE(s.params()[1].required());
  EXPECT_EQ(s.inputs()[0].type, fba::any_type());
  EXPECT_EQ(s.outputs()[0].type, fba::type_of<std::int64_t>());
}

namespace {
constexpr auto kLow = fba::Param<double>("low", 0.0, "");
constexpr auto kHigh = fba::Param<double>("high", 1.0, "");
static inline const auto kBox = fba::Param<std::vector<double>>("box", {}, "").size({0, 6});
}  // namespace

TEST(SpecChecks, ACrossParameterComparisonNamesBothValues) {
  const auto s = Spec::sensor("t.s", "").add(kOut, kLow, kHigh).add(kLow <= kHigh);
  EXPECT_TRUE(s.check_params({{"low", 1.0}, {"high", 1.0}}).empty());
  EXPECT_EQ(Spec::sensor("t.s", "").add(kOut, kLow, kHigh).add(kLow < kHigh).check_params({{"low", 1.0}, {"high", 1.0}}).size(), 1u);
  const auto problems = s.check_params({{"low", 2.0}, {"high", 1.0}});
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].param, "low");
  EXPECT_EQ(problems[0].message, "parameter 'low' (2) must be <= parameter 'high' (1)");
}

int g_calls = 0;

TEST(SpecChecks, AListLengthIsCheckedBeforeTheGeneralChecks) {
  g_calls = 0;
  const auto s = Spec::sensor("t.s", "").add(kOut, kBox).check(kBox, [](const fba::ParamValues& p) {
    ++g_calls;
    return p(kBox).size() == 6 && p(kBox)[0] >= p(kBox)[3] ? std::string("min >= max") : std::string();
  });
  const auto wrong = s.check_params({{"box", std::vector<double>{1, 2, 3}}});
  ASSERT_EQ(wrong.size(), 1u);
  EXPECT_EQ(wrong[0].message, "parameter 'box' must have 0 or 6 numbers; found 3");
  EXPECT_EQ(g_calls, 0);
  const auto inverted = s.check_params({{"box", std::vector<double>{1, 0, 0, 0, 1, 1}}});
  ASSERT_EQ(inverted.size(), 1u);
  EXPECT_EQ(inverted[0].param, "box");
  EXPECT_EQ(inverted[0].message, "min >= max");
  EXPECT_TRUE(s.check_params({{"box", std::vector<double>{}}}).empty());
}

TEST(SpecChecks, ACheckAboutAnUndeclaredParameterIsRefused) {
  auto s = Spec::sensor("t.s", "").add(kOut, kLow).add(kLow <= kHigh);
  EXPECT_NE(validation_error(s).find("'high', which is not declared"), std::string::npos);
}

TEST(SpecChecks, ReadingAnUndeclaredParameterIsAPluginBug) {
  const auto s = Spec::sensor("t.s", "").add(kOut, kLow).check([](const fba::ParamValues& p) {
    return p(kHigh) > 0 ? std::string() : std::string("never");
  });
  try {
    s.check_params({{"low", 0.0}}, "libdemo.so");
    FAIL() << "no PluginBug";
  } catch (const fba::PluginBug& e) {
    EXPECT_EQ(std::string(e.what()), "plugin bug in libdemo.so (type 't.s'): reads parameter 'high', which its spec does not declare");
  }
}
