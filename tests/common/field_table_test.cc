#include "common/field_table.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

namespace graspbed::common {
namespace {

using ::testing::HasSubstr;

struct Inner {
  double width_m = 0.01;
};

enum class Mode { kFast, kSlow };

struct Sample {
  double gain = 1.0;
  int count = 3;
  bool enabled = true;
  Mode mode = Mode::kFast;
  std::string label = "x";
  std::array<double, 2> pair = {0.0, 1.0};
  double gap_m = std::numeric_limits<double>::quiet_NaN();  // auto
  double low = 0.0;
  double high = 1.0;
  Inner inner;
};

const FieldTable<Inner>& InnerFields() {
  using Table = FieldTable<Inner>;
  static const Table table("inner",
                           {Table::Number("width_m", &Inner::width_m, {0.0, 0.1, true}, "m", "a width")});
  return table;
}

const FieldTable<Sample>& SampleFields() {
  using Table = FieldTable<Sample>;
  static const Table table(
      "sample",
      {
          Table::Number("gain", &Sample::gain, NumberRule::Positive(), "-", "a gain"),
          Table::Integer("count", &Sample::count, 1, 10, "", "a count"),
          Table::Bool("enabled", &Sample::enabled, "on or off"),
          Table::Choice("mode", &Sample::mode, {{Mode::kFast, "fast"}, {Mode::kSlow, "slow"}}, "speed"),
          Table::Text("label", &Sample::label, {}, "free text"),
          Table::Numbers("pair", &Sample::pair, NumberRule::Between(-1.0, 2.0), "m", "two numbers"),
          Table::Number("gap_m", &Sample::gap_m, NumberRule::Between(0.001, 0.2), "m", "auto when unset")
              .NanIsAuto(),
          Table::Number("low", &Sample::low, NumberRule::Between(0.0, 10.0), "", ""),
          Table::Number("high", &Sample::high, {0.0, 10.0, false, true}, "", "").Note("> `low`"),
          Table::Section("inner", &Sample::inner, InnerFields()),
      },
      [](const Sample& s) {
        if (!(s.high > s.low)) FieldError("high", s.high, "must be > low");
      });
  return table;
}

Sample Load(const std::string& text) {
  Sample sample;
  SampleFields().Load(YamlMap::LoadString(text, "f.yaml"), &sample);
  return sample;
}

ConfigError LoadError(const std::string& text) {
  try {
    Load(text);
  } catch (const ConfigError& error) {
    return error;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return ConfigError("(no error)");
}

TEST(FieldTableTest, LoadSetsTheKeysGivenAndKeepsTheRest) {
  const Sample sample = Load("gain: 2.5\nmode: slow\npair: [0.5, -0.5]\ninner: {width_m: 0.02}\n");
  EXPECT_DOUBLE_EQ(sample.gain, 2.5);
  EXPECT_EQ(sample.mode, Mode::kSlow);
  EXPECT_DOUBLE_EQ(sample.pair[0], 0.5);
  EXPECT_DOUBLE_EQ(sample.pair[1], -0.5);
  EXPECT_DOUBLE_EQ(sample.inner.width_m, 0.02);
  EXPECT_EQ(sample.count, 3);
  EXPECT_TRUE(sample.enabled);
  EXPECT_EQ(sample.label, "x");
  EXPECT_TRUE(std::isnan(sample.gap_m));
}

TEST(FieldTableTest, AValueOutsideItsRuleIsRefusedWithFileLineKeyAndValue) {
  const ConfigError error = LoadError("count: 4\ngain: -1\n");
  EXPECT_EQ(error.file(), "f.yaml");
  EXPECT_EQ(error.line(), 2);
  EXPECT_EQ(error.key(), "gain");
  EXPECT_EQ(error.value(), "-1");
  EXPECT_EQ(error.message(), "must be > 0");
  EXPECT_STREQ(error.what(), "f.yaml:2: gain = -1: must be > 0");

  EXPECT_STREQ(LoadError("count: 2.5\n").what(), "f.yaml:1: count = 2.5: expected a whole number");
  EXPECT_STREQ(LoadError("mode: medium\n").what(),
               "f.yaml:1: mode = medium: unknown name; valid names: fast, slow");
  EXPECT_STREQ(LoadError("pair: [0, 3]\n").what(), "f.yaml:1: pair[1] = 3: must be <= 2");
  EXPECT_STREQ(LoadError("high: 10\n").what(), "f.yaml:1: high = 10: must be < 10");
  EXPECT_STREQ(LoadError("x: 1\ninner:\n  width_m: 0\n").what(), "f.yaml:3: inner.width_m = 0: must be > 0");
}

TEST(FieldTableTest, UnknownKeysAreRefusedNamingTheValidOnes) {
  const ConfigError error = LoadError("gain: 1\ngian: 2\n");
  EXPECT_EQ(error.line(), 2);
  EXPECT_EQ(error.key(), "gian");
  EXPECT_FALSE(error.value().has_value());
  EXPECT_THAT(error.what(), HasSubstr("f.yaml:2: gian: unknown key; valid keys: "));
  EXPECT_THAT(error.what(), HasSubstr("gain"));
  EXPECT_THAT(LoadError("inner: {widht_m: 1}\n").what(), HasSubstr("f.yaml:1: inner.widht_m: unknown key"));
}

TEST(FieldTableTest, ACrossFieldCheckBlamesTheKeyAtItsLineOrTheMapWithTheValueInUse) {
  // The blamed key is in the file: its line and its text.
  EXPECT_STREQ(LoadError("low: 5\nhigh: 4\n").what(), "f.yaml:2: high = 4: must be > low");
  // Not in the file: the value in use (the default), at the enclosing section's line when there is
  // one, at no line when that is the document itself.
  EXPECT_STREQ(LoadError("low: 5\n").what(), "f.yaml: high = 1 (default): must be > low");
}

TEST(FieldTableTest, ValidateAppliesTheSameRulesToAConfigBuiltInCode) {
  Sample sample;
  SampleFields().Validate(sample);  // the defaults are valid; auto (NaN) is not checked
  sample.gain = 0.0;
  try {
    SampleFields().Validate(sample);
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.key(), "sample.gain");
    EXPECT_EQ(error.value(), "0");
    EXPECT_STREQ(error.what(), "sample.gain = 0: must be > 0");
  }
  sample.gain = 1.0;
  sample.inner.width_m = 0.5;
  EXPECT_THROW(SampleFields().Validate(sample), ConfigError);
  try {
    SampleFields().Validate(sample);
  } catch (const ConfigError& error) {
    EXPECT_STREQ(error.what(), "sample.inner.width_m = 0.5: must be <= 0.1");
  }
  sample.inner.width_m = 0.01;
  sample.gain = std::numeric_limits<double>::infinity();
  try {
    SampleFields().Validate(sample);
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.message(), "must be a finite number");
  }
  sample.gain = 1.0;
  sample.high = 0.0;  // within its own rule, not above low (0)
  try {
    SampleFields().Validate(sample);
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_STREQ(error.what(), "sample.high = 0: must be > low");
  }
}

TEST(FieldTableTest, EmitThenLoadGivesTheSameConfig) {
  Sample sample;
  sample.gain = 0.1 + 0.2;  // not a short decimal: the text must keep every bit
  sample.count = 7;
  sample.enabled = false;
  sample.mode = Mode::kSlow;
  sample.label = "two words";
  sample.pair = {-0.25, 1.0 / 3.0};
  sample.gap_m = 0.05;
  sample.low = 2.0;
  sample.high = 3.0;
  sample.inner.width_m = 0.07;
  const std::string text = SampleFields().EmitYaml(sample);
  const Sample again = Load(text);
  EXPECT_EQ(again.gain, sample.gain) << text;
  EXPECT_EQ(again.count, 7);
  EXPECT_FALSE(again.enabled);
  EXPECT_EQ(again.mode, Mode::kSlow);
  EXPECT_EQ(again.label, "two words");
  EXPECT_EQ(again.pair, sample.pair);
  EXPECT_EQ(again.gap_m, 0.05);
  EXPECT_EQ(again.inner.width_m, 0.07);
  EXPECT_EQ(SampleFields().EmitYaml(again), text);

  // Auto (NaN) values are left out, so a reload derives them again.
  const std::string defaults = SampleFields().EmitYaml(Sample{});
  EXPECT_THAT(defaults, ::testing::Not(HasSubstr("gap_m")));
  EXPECT_TRUE(std::isnan(Load(defaults).gap_m));
}

TEST(FieldTableTest, TheReferenceListsEveryFieldWithDefaultRuleAndUnit) {
  const std::vector<FieldReference> rows = SampleFields().Reference();
  ASSERT_EQ(rows.size(), 10u);
  EXPECT_EQ(rows[0].key, "gain");
  EXPECT_EQ(rows[0].default_value, "1");
  EXPECT_EQ(rows[0].allowed, "> 0");
  EXPECT_EQ(rows[1].allowed, "1 .. 10, whole");
  EXPECT_EQ(rows[3].allowed, "`fast`, `slow`");
  EXPECT_EQ(rows[3].default_value, "`fast`");
  EXPECT_EQ(rows[5].default_value, "[0, 1]");
  EXPECT_EQ(rows[6].default_value, "auto");
  EXPECT_EQ(rows[8].allowed, ">= 0, < 10; > `low`");
  EXPECT_EQ(rows[9].key, "inner.width_m");
  EXPECT_EQ(rows[9].unit, "m");
  EXPECT_EQ(rows[9].allowed, "> 0, <= 0.1");
  EXPECT_THAT(ReferenceMarkdown(rows), HasSubstr("| `inner.width_m` | m | 0.01 | > 0, <= 0.1 | a width |\n"));
}

// Three levels, each defaulting the level below apart from that level's own defaults: the
// reference shows the value a default-constructed top level holds, not a default-constructed
// member's.
struct Middle {
  Inner inner{0.02};
  double span_m = 1.0;
};
struct Outer {
  Middle middle{Inner{0.03}, 2.0};
};

TEST(FieldTableTest, ASectionsDefaultsAreTheOnesItsParentGivesIt) {
  using MiddleTable = FieldTable<Middle>;
  static const MiddleTable middle("middle", {MiddleTable::Section("inner", &Middle::inner, InnerFields()),
                                             MiddleTable::Number("span_m", &Middle::span_m, {}, "m", "")});
  using OuterTable = FieldTable<Outer>;
  const OuterTable outer("outer", {OuterTable::Section("middle", &Outer::middle, middle)});
  const std::vector<FieldReference> rows = outer.Reference();
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].key, "middle.inner.width_m");
  EXPECT_EQ(rows[0].default_value, "0.03");
  EXPECT_EQ(rows[1].key, "middle.span_m");
  EXPECT_EQ(rows[1].default_value, "2");
  EXPECT_EQ(rows[1].allowed, "any");
  EXPECT_EQ(middle.Reference()[0].default_value, "0.02");
  EXPECT_EQ(InnerFields().Reference()[0].default_value, "0.01");
}

TEST(FieldTableTest, ARuleLeftToTheCrossCheckIsStatedByItsNoteAlone) {
  using Table = FieldTable<Middle>;
  const Table table("middle", {Table::Number("span_m", &Middle::span_m, {}, "m", "").Note("> 0 and < 3")});
  EXPECT_EQ(table.Reference()[0].allowed, "> 0 and < 3");
}

struct Checks {
  std::optional<double> max_slip_mm;
  std::optional<bool> not_dropped;
};

TEST(FieldTableTest, OptionalFieldsStayUnsetUnlessGivenAndAreWrittenOnlyWhenSet) {
  using Table = FieldTable<Checks>;
  const Table table("checks", {
                                  Table::OptionalNumber("max_slip_mm", &Checks::max_slip_mm,
                                                        NumberRule::NonNegative(), "mm", "limit"),
                                  Table::OptionalBool("not_dropped", &Checks::not_dropped, "flag"),
                              });
  Checks checks;
  table.Load(YamlMap::LoadString("max_slip_mm: 2\n", "c.yaml"), &checks);
  EXPECT_EQ(checks.max_slip_mm, 2.0);
  EXPECT_FALSE(checks.not_dropped.has_value());
  EXPECT_EQ(table.EmitYaml(checks), "max_slip_mm: 2\n");
  Checks refused;
  try {
    table.Load(YamlMap::LoadString("not_dropped: true\nmax_slip_mm: -1\n", "c.yaml"), &refused);
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_STREQ(error.what(), "c.yaml:2: max_slip_mm = -1: must be >= 0");
  }
  checks.max_slip_mm = -1.0;
  EXPECT_THROW(table.Validate(checks), ConfigError);
  EXPECT_EQ(table.Reference()[0].default_value, "none");
}

TEST(FieldTableTest, DocNumbersAreShort) {
  EXPECT_EQ(DocNumber(1e6), "1e6");
  EXPECT_EQ(DocNumber(5e-4), "0.0005");
  EXPECT_EQ(DocNumber(1e-15), "1e-15");
  EXPECT_EQ(DocNumber(0.0999), "0.0999");
}

TEST(ConfigErrorTest, CarriesItsPartsAsDataAndFormatsThePresentOnes) {
  const ConfigError full("s.yaml", 12, "object.mass_kg", "-0.1", "must be > 0");
  EXPECT_STREQ(full.what(), "s.yaml:12: object.mass_kg = -0.1: must be > 0");
  EXPECT_STREQ(full.WithContext("--set object.mass_kg=-0.1").what(),
               "--set object.mass_kg=-0.1: s.yaml:12: object.mass_kg = -0.1: must be > 0");
  EXPECT_EQ(full.WithContext("--set x=1").key(), "object.mass_kg");
  EXPECT_STREQ(ConfigError("s.yaml", 0, "", std::nullopt, "cannot open file").what(),
               "s.yaml: cannot open file");
  EXPECT_STREQ(ConfigError("", 0, "gain", "2", "too high").WithKeyPrefix("controller").what(),
               "controller.gain = 2: too high");
  EXPECT_STREQ(ConfigError("", 0, "k", std::nullopt, "bad").WithLocation("f.yaml", 3).what(),
               "f.yaml:3: k: bad");
  const std::invalid_argument& as_base = full;  // caught as bad input wherever invalid_argument is
  EXPECT_STREQ(as_base.what(), full.what());
}

}  // namespace
}  // namespace graspbed::common
