// A component type's declaration is checked when it registers.
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
}  // namespace

TEST(Spec, SensorInputsMustBeOptional) {
  auto s = Spec::sensor("t.s", "").input<std::int64_t>("in", "").output<std::int64_t>("out", "");
  EXPECT_NE(validation_error(s).find("must be optional"), std::string::npos);
}

TEST(Spec, ActuatorHasNoOutputs) {
  auto s = Spec::actuator("t.a", "").input<std::int64_t>("in", "").output<std::int64_t>("out", "");
  EXPECT_NE(validation_error(s).find("no outputs"), std::string::npos);
}

TEST(Spec, OutputLikeNeedsADeclaredInput) {
  auto s = Spec::filter("t.f", "").any_input("in", "").output_like("out", "missing", "");
  EXPECT_NE(validation_error(s).find("'missing'"), std::string::npos);
}

TEST(Spec, DefaultMustLieInItsRange) {
  auto s = Spec::sensor("t.s", "").output<std::int64_t>("out", "").param("n", 20, "").range(0, 10);
  EXPECT_NE(validation_error(s).find("out of its range"), std::string::npos);
}

TEST(Spec, DefaultMustBeOneOfTheChoices) {
  auto s = Spec::sensor("t.s", "").output<std::int64_t>("out", "").param("mode", "fast", "").choices({"slow", "exact"});
  EXPECT_NE(validation_error(s).find("choices"), std::string::npos);
}

TEST(Spec, PortNamesAreUnique) {
  auto s = Spec::filter("t.f", "").any_input("x", "").output<std::int64_t>("x", "");
  EXPECT_NE(validation_error(s).find("declared twice"), std::string::npos);
}

TEST(Spec, BuiltInEventsCannotBeRedeclared) {
  auto s = Spec::sensor("t.s", "").output<std::int64_t>("out", "").event("error", "");
  EXPECT_NE(validation_error(s).find("built-in"), std::string::npos);
}

TEST(Spec, TransitionsNameDeclaredStages) {
  auto s = Spec::filter("t.f", "").any_input("in", "").output<std::int64_t>("out", "").stages({"a", "b"}, {{"a", "c"}});
  EXPECT_NE(validation_error(s).find("undeclared stage"), std::string::npos);
}

TEST(Spec, AValidSpecPasses) {
  auto s = Spec::filter("t.f", "doc").any_input("in", "").output_like("out", "in", "").param("k", 1.5, "").range(0, 2);
  EXPECT_EQ(validation_error(s), "");
}
