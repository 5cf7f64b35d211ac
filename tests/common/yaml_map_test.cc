#include "common/yaml_map.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/support/error_of.h"

namespace graspbed::common {
namespace {

using ::testing::HasSubstr;

// The errors refused here are ConfigError; one of another type fails the test.
std::string ErrorOf(const std::function<void()>& action) {
  return graspbed::test_support::ErrorOf<ConfigError>(action);
}

TEST(YamlMapTest, ReadsTypedValuesWithDefaults) {
  const YamlMap map = YamlMap::LoadString("mass: 0.25\nname: box\nflag: true\ncount: 3\n", "t.yaml");
  EXPECT_DOUBLE_EQ(map.GetNumber("mass", 1.0, NumberRule::Positive()), 0.25);
  EXPECT_DOUBLE_EQ(map.GetNumber("absent", 1.5), 1.5);
  EXPECT_EQ(map.GetString("name", "", {"box", "sphere"}), "box");
  EXPECT_TRUE(map.GetBool("flag", false));
  EXPECT_EQ(map.GetInt("count", 0, 0, 10), 3);
  EXPECT_NO_THROW(map.RejectUnknownKeys());
}

TEST(YamlMapTest, OutOfRangeNamesFileLineKeyAndValue) {
  const YamlMap root = YamlMap::LoadString("object:\n  shape: box\n  mass: -0.1\n", "lift.yaml");
  const YamlMap object = root.RequireMap("object");
  EXPECT_EQ(ErrorOf([&] { object.GetNumber("mass", 1.0, NumberRule::Positive()); }),
            "lift.yaml:3: object.mass = -0.1: must be > 0");
}

TEST(YamlMapTest, UnknownKeyListsValidKeys) {
  const YamlMap map = YamlMap::LoadString("mass: 1\nfriciton: 0.5\n", "s.yaml");
  map.GetNumber("mass", 1.0);
  map.GetNumber("friction", 0.5);
  const std::string error = ErrorOf([&] { map.RejectUnknownKeys(); });
  EXPECT_THAT(error, HasSubstr("s.yaml:2: friciton: unknown key"));
  EXPECT_THAT(error, HasSubstr("friction, mass"));
}

TEST(YamlMapTest, SyntaxErrorAndMissingKeyAndWrongType) {
  EXPECT_THAT(ErrorOf([] { YamlMap::LoadString("a: [1, 2\nb: 3\n", "bad.yaml"); }), HasSubstr("bad.yaml:"));
  const YamlMap map = YamlMap::LoadString("a: hello\nlist: [1, x]\n", "m.yaml");
  EXPECT_EQ(ErrorOf([&] { map.RequireNumber("a"); }), "m.yaml:1: a = hello: expected a number");
  EXPECT_THAT(ErrorOf([&] { map.RequireNumber("b"); }), HasSubstr("b = null: missing required key"));
  EXPECT_EQ(ErrorOf([&] { map.GetNumberList("list", {}); }), "m.yaml:2: list[1] = x: expected a number");
  EXPECT_THAT(ErrorOf([&] {
                map.GetString("a", "", {"box", "sphere"});
              }),
              HasSubstr("valid names: box, sphere"));
  EXPECT_THAT(ErrorOf([] { YamlMap::LoadFile("/nonexistent/x.yaml"); }),
              HasSubstr("/nonexistent/x.yaml: cannot open file"));
}

TEST(YamlMapTest, RejectsNonFiniteNumbers) {
  const YamlMap map = YamlMap::LoadString("a: .nan\nb: inf\n", "n.yaml");
  EXPECT_THAT(ErrorOf([&] { map.RequireNumber("a"); }), HasSubstr("n.yaml:1: a ="));
  EXPECT_THAT(ErrorOf([&] { map.RequireNumber("b"); }), HasSubstr("must be a finite number"));
}

}  // namespace
}  // namespace graspbed::common
