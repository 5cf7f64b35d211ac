// `graspbed hw` refuses bad controller settings before it touches a port: the config's controller
// section (file, line, key, value) and --param, each with exit code 2; its --help names exactly the
// config sections the loader takes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/support/cli_runner.h"
#include "tests/support/temp_dir.h"

namespace graspbed::hardware {
namespace {

using graspbed::test_support::CliResult;
using graspbed::test_support::RunCli;
using graspbed::test_support::TempDir;
using ::testing::HasSubstr;

constexpr int kExitBadInput = 2;

class HwCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (graspbed::test_support::CliBinary().empty())
      GTEST_FAIL() << "GRASPBED_BINARY not set (run through ctest)";
  }
  TempDir dir_{"hw_cli"};
};

TEST_F(HwCliTest, ControllerParameterOutOfRangeInTheConfigNamesFileLineKeyAndValue) {
  const std::string config = dir_.Write(
      "hw.yaml", "controller:\n  name: grip_slip\n  params:\n    min_grip_n: 2\n    max_grip_n: 300\n");
  const CliResult result = RunCli("hw --config " + config + " --port " + dir_.Path("no-device"));
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr(config + ":5: controller.params.max_grip_n = 300"));
  EXPECT_THAT(result.err, HasSubstr("must be <= 200"));
}

TEST_F(HwCliTest, CrossFieldChecksSeeEveryParameterWhateverTheirOrder) {
  // Both orders are valid: the check runs on the whole set, not one key at a time.
  for (const char* params : {"{min_grip_n: 12, max_grip_n: 20}", "{max_grip_n: 20, min_grip_n: 12}"}) {
    SCOPED_TRACE(params);
    const std::string config =
        dir_.Write("order.yaml", std::string("controller:\n  params: ") + params + "\n");
    const CliResult result = RunCli("hw --config " + config + " --port " + dir_.Path("no-device"));
    EXPECT_EQ(result.exit_code, kExitBadInput);
    EXPECT_THAT(result.err, HasSubstr("does not exist"));  // got past the config to the port
  }
  // Alone, min_grip_n 12 exceeds the default 10 N ceiling: named at its line.
  const std::string config = dir_.Write("alone.yaml", "controller:\n  params:\n    min_grip_n: 12\n");
  const CliResult result = RunCli("hw --config " + config + " --port " + dir_.Path("no-device"));
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr(config + ":3: controller.params.min_grip_n = 12"));
  EXPECT_THAT(result.err, HasSubstr("must not exceed max_grip_n"));
}

// `graspbed soak` refuses a schedule it cannot run before it starts anything (exit 2, no output).
TEST_F(HwCliTest, SoakRefusesAScheduleItCannotRunNamingTheOption) {
  const std::string out = dir_.Path("soak");
  const std::string scenario = "tests/hardware/data/soak_hold.yaml";
  CliResult result = RunCli("soak " + scenario + " --duration 25 --period 10 --out " + out);
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr("--duration 25 must be a whole number (>= 1) of --period 10"));
  result = RunCli("soak " + scenario + " --duration 30 --period 3 --out " + out);
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr("soak.period_s = 3: must be >= 5 s"));
  result = RunCli("soak " + scenario + " --duration 30 --period 10 --downtime 5 --out " + out);
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr("soak.downtime_s = 5: must be > 0 and <= 0.1 x period_s"));
  result = RunCli("emulate --link " + dir_.Path("dev") + " --soak-cycles 1 --soak-period 2");
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr("soak.period_s = 2"));
  EXPECT_FALSE(std::filesystem::exists(out)) << "a refused soak left an output directory";
}

TEST_F(HwCliTest, AnUnwritableLogIsRefusedBeforeThePort) {
  const std::string file_in_the_way = dir_.Write("not_a_dir", "x");
  const CliResult result =
      RunCli("hw --port " + dir_.Path("no-device") + " --log " + file_in_the_way + "/frames.csv");
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr("--log " + file_in_the_way + "/frames.csv: cannot write this file"));
}

TEST_F(HwCliTest, UnknownControllerAndUnknownKeyInTheConfigAreRefused) {
  std::string config = dir_.Write("name.yaml", "controller: {name: pid}\n");
  CliResult result = RunCli("hw --config " + config + " --port " + dir_.Path("no-device"));
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr("controller.name = pid"));
  EXPECT_THAT(result.err, HasSubstr("grip_slip"));  // lists the valid names

  config = dir_.Write("key.yaml", "controller:\n  name: grip_slip\n  ceiling: 3\n");
  result = RunCli("hw --config " + config + " --port " + dir_.Path("no-device"));
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr(config + ":3"));
  EXPECT_THAT(result.err, HasSubstr("ceiling"));
}

TEST_F(HwCliTest, BadParamOnTheCommandLineIsRefusedBeforeThePortIsOpened) {
  CliResult result = RunCli("hw --port " + dir_.Path("no-device") + " --param safety_margin=abc");
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr("--param safety_margin=abc: expected NAME=NUMBER"));

  result = RunCli("hw --port " + dir_.Path("no-device") + " --param no_such_gain=1");
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_THAT(result.err, HasSubstr("controller 'grip_slip': no_such_gain: no such parameter"));
  // Refused before the port: the missing device is not what the message is about.
  EXPECT_THAT(result.err, ::testing::Not(HasSubstr("does not exist")));
}

TEST_F(HwCliTest, EverySectionTheHelpNamesIsAccepted) {
  // `hw --help` lists the sections of --config; each must load (the run then gets as far as the
  // missing port), and a section it does not list is refused with file, line and key.
  const CliResult help = RunCli("hw --help");
  ASSERT_EQ(help.exit_code, 0) << help.err;
  const std::string marker = "YAML with ";
  const size_t start = help.out.find(marker);
  ASSERT_NE(start, std::string::npos) << help.out;
  const size_t begin = start + marker.size();
  const std::string list = help.out.substr(begin, help.out.find(" sections", begin) - begin);
  std::vector<std::string> sections;
  for (size_t at = 0; (at = list.find_first_of("abcdefghijklmnopqrstuvwxyz", at)) != std::string::npos;) {
    const size_t colon = list.find(':', at);
    ASSERT_NE(colon, std::string::npos) << list;
    sections.push_back(list.substr(at, colon - at));
    at = colon + 1;
  }
  EXPECT_EQ(sections, (std::vector<std::string>{"serial", "controller", "readout", "inversion"})) << list;
  std::string all;
  for (const std::string& section : sections) all += section + ": {}\n";
  const std::string config = dir_.Write("sections.yaml", all);
  const CliResult loaded = RunCli("hw --config " + config + " --port " + dir_.Path("no-device"));
  EXPECT_EQ(loaded.exit_code, kExitBadInput);
  EXPECT_THAT(loaded.err, HasSubstr("does not exist")) << "the config loaded; the port is what is missing";

  const std::string unknown = dir_.Write("control.yaml", "serial: {}\ncontrol: {rate_hz: 500}\n");
  const CliResult refused = RunCli("hw --config " + unknown + " --port " + dir_.Path("no-device"));
  EXPECT_EQ(refused.exit_code, kExitBadInput);
  EXPECT_THAT(refused.err, HasSubstr(unknown + ":2"));
  EXPECT_THAT(refused.err, HasSubstr("control"));
}

}  // namespace
}  // namespace graspbed::hardware
