// The config reference tables in docs/ are the ones the field tables derive, and
// `graspbed config-reference` prints them.
#include "testbed/config_reference.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "tests/support/cli_runner.h"

namespace graspbed::testbed {
namespace {

using ::testing::HasSubstr;

std::string ReadDoc(const std::string& name) {
  std::ifstream stream(std::string(GRASPBED_SOURCE_DIR) + "/docs/" + name);
  std::stringstream text;
  text << stream.rdbuf();
  return text.str();
}

// The blocks "<!-- config-reference PATH -->\n...<!-- /config-reference -->" of `doc`, by path.
std::map<std::string, std::string> Blocks(const std::string& doc) {
  std::map<std::string, std::string> blocks;
  const std::string open = "<!-- config-reference ";
  const std::string close = "<!-- /config-reference -->";
  for (size_t start = doc.find(open); start != std::string::npos; start = doc.find(open, start + 1)) {
    const size_t name_end = doc.find(" -->\n", start);
    const size_t end = doc.find(close, name_end);
    if (name_end == std::string::npos || end == std::string::npos) break;
    const std::string path = doc.substr(start + open.size(), name_end - start - open.size());
    blocks[path] = doc.substr(name_end + 5, end - name_end - 5);
  }
  return blocks;
}

TEST(ConfigReferenceTest, DocsCarryEveryFieldTableAsItIs) {
  std::set<std::string> documented;
  for (const char* doc : {"scenarios.md", "hardware.md", "fea.md", "sensor.md"}) {
    for (const auto& [path, block] : Blocks(ReadDoc(doc))) {
      SCOPED_TRACE(std::string(doc) + ": " + path);
      documented.insert(path);
      EXPECT_EQ(block, ConfigReferenceMarkdown(path)) << "regenerate it: graspbed config-reference " << path;
    }
  }
  for (const ConfigSection& section : ConfigReference()) {
    EXPECT_EQ(documented.count(section.path), 1u)
        << "no <!-- config-reference " << section.path << " --> block in docs/";
  }
}

// A section's defaults are its parent's (the gauge's resistors span 0 .. 0.75 mm and -0.75 .. 0 mm),
// not those of a default-constructed section (0 .. 0), and the span rule the loader applies is
// stated with its range, as `graspbed config-reference fea` prints it.
TEST(ConfigReferenceTest, ASectionsDefaultsAreItsParentsAndItsRulesAreNamed) {
  if (test_support::CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY not set (run through ctest)";
  const test_support::CliResult fea = test_support::RunCli("config-reference fea");
  ASSERT_EQ(fea.exit_code, 0) << fea.err;
  const std::string span = "within the free span under the beam, -1 .. 1 at the default geometry";
  EXPECT_THAT(fea.out, HasSubstr("| `gauge.r1.start_mm` | mm | 0 | " + span + " |"));
  EXPECT_THAT(fea.out, HasSubstr("| `gauge.r1.end_mm` | mm | 0.75 | > `start_mm`, " + span + " |"));
  EXPECT_THAT(fea.out, HasSubstr("| `gauge.r2.start_mm` | mm | -0.75 | " + span + " |"));
  EXPECT_THAT(fea.out, HasSubstr("| `gauge.r2.end_mm` | mm | 0 | > `start_mm`, " + span + " |"));
  EXPECT_EQ(fea.out, ConfigReferenceMarkdown("fea"));
}

TEST(ConfigReferenceTest, EveryRowHasADefaultAndARule) {
  for (const ConfigSection& section : ConfigReference()) {
    std::set<std::string> keys;
    for (const common::FieldReference& row : section.rows) {
      SCOPED_TRACE(section.path + "." + row.key);
      EXPECT_TRUE(keys.insert(row.key).second) << "listed twice";
      EXPECT_FALSE(row.default_value.empty());
      EXPECT_FALSE(row.allowed.empty());
    }
  }
}

TEST(ConfigReferenceTest, TheCommandPrintsOneSectionOrAllAndRefusesAnUnknownOne) {
  if (test_support::CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY not set (run through ctest)";
  const test_support::CliResult one = test_support::RunCli("config-reference sensor.readout");
  EXPECT_EQ(one.exit_code, 0) << one.err;
  EXPECT_EQ(one.out, ConfigReferenceMarkdown("sensor.readout"));
  const test_support::CliResult all = test_support::RunCli("config-reference");
  EXPECT_EQ(all.exit_code, 0) << all.err;
  EXPECT_THAT(all.out, HasSubstr("### `serial`\n\n| key |"));
  const test_support::CliResult bad = test_support::RunCli("config-reference objekt");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("section = objekt: no such config section; sections: object, hand"));
}

}  // namespace
}  // namespace graspbed::testbed
