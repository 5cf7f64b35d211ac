// Runs the real `graspbed` executable ($GRASPBED_BINARY) for the sensor subcommands.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "sensor/strain_model.h"
#include "tests/support/cli_runner.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::sensor {
namespace {

using test_support::CliBinary;
using test_support::CliResult;
using test_support::RunCli;
using test_support::SourcePath;
using test_support::TempDir;
using ::testing::HasSubstr;

constexpr double kOhmTol = 0.5;
constexpr double kForceTolN = 1e-6;

class SensorCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY must point at the CLI";
  }
};

TEST_F(SensorCliTest, ForwardPrintsPaperNumbers) {
  const CliResult text = RunCli("sensor forward --fn 10 --ft 10");
  EXPECT_EQ(text.exit_code, 0) << text.err;
  EXPECT_THAT(text.out, HasSubstr("R1 = 6664.0 Ohm"));
  EXPECT_THAT(text.out, HasSubstr("R2 = 3876.0 Ohm"));
  EXPECT_THAT(text.out, HasSubstr("dR1/R1 = +0.9600"));
  const CliResult json = RunCli("sensor forward --fn 0 --ft 10 --json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json parsed = nlohmann::json::parse(json.out);
  EXPECT_NEAR(parsed.at("r1").get<double>(), 4794, kOhmTol);
  EXPECT_NEAR(parsed.at("r2").get<double>(), 2006, kOhmTol);
  EXPECT_EQ(parsed.at("fn").get<double>(), 0.0);
  EXPECT_EQ(parsed.at("ft").get<double>(), 10.0);
  const CliResult normal = RunCli("sensor forward --fn 10 --json");
  EXPECT_NEAR(nlohmann::json::parse(normal.out).at("r1").get<double>(), 5270, kOhmTol);
  EXPECT_NEAR(nlohmann::json::parse(normal.out).at("r2").get<double>(), 5270, kOhmTol);
}

TEST_F(SensorCliTest, ForwardTakesShearEitherWay) {
  // A unit measures shear both ways (rated -10..10 N). Paper eq. 3 with eps_t = kt Ft < 0:
  // R1 = R0 (1 + G (kn Fn + kt Ft)), R2 = R0 (1 + G (kn Fn - kt Ft)).
  const sensor::UnitConstants paper;
  const auto r1 = [&](double fn, double ft) {
    return paper.r0_ohm * (1.0 + paper.gauge_factor * (paper.kn_per_n * fn + paper.kt_per_n * ft));
  };
  const auto r2 = [&](double fn, double ft) { return r1(fn, -ft); };
  const CliResult json = RunCli("sensor forward --fn 3.7 --ft -2.2 --json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_EQ(json.err, "");  // inside the rated range: no note
  const nlohmann::json parsed = nlohmann::json::parse(json.out);
  EXPECT_EQ(parsed.at("ft").get<double>(), -2.2);
  EXPECT_NEAR(parsed.at("r1").get<double>(), r1(3.7, -2.2), 1e-9);  // 3785.2 Ohm
  EXPECT_NEAR(parsed.at("r2").get<double>(), r2(3.7, -2.2), 1e-9);  // 4398.6 Ohm
  EXPECT_LT(parsed.at("r1").get<double>(), parsed.at("r2").get<double>());
  // Reversing the shear swaps R1 and R2.
  const nlohmann::json mirrored =
      nlohmann::json::parse(RunCli("sensor forward --fn 3.7 --ft 2.2 --json").out);
  EXPECT_NEAR(mirrored.at("r1").get<double>(), parsed.at("r2").get<double>(), 1e-9);
  EXPECT_NEAR(mirrored.at("r2").get<double>(), parsed.at("r1").get<double>(), 1e-9);
  // And the inversion gives the force back, sign included.
  const CliResult back = RunCli("sensor invert --json --r1 " + std::to_string(parsed.at("r1").get<double>()) +
                                " --r2 " + std::to_string(parsed.at("r2").get<double>()));
  ASSERT_EQ(back.exit_code, 0) << back.err;
  EXPECT_NEAR(nlohmann::json::parse(back.out).at("fn").get<double>(), 3.7, 1e-5);
  EXPECT_NEAR(nlohmann::json::parse(back.out).at("ft").get<double>(), -2.2, 1e-5);
  // The whole rated range either way, the paper's worked numbers mirrored; beyond it, a note.
  const CliResult rated = RunCli("sensor forward --ft -10");
  EXPECT_EQ(rated.exit_code, 0) << rated.err;
  EXPECT_THAT(rated.out, HasSubstr("R1 = 2006.0 Ohm"));
  EXPECT_THAT(rated.out, HasSubstr("R2 = 4794.0 Ohm"));
  EXPECT_EQ(rated.err, "");
  const CliResult beyond = RunCli("sensor forward --ft -10.5");
  EXPECT_EQ(beyond.exit_code, 0) << beyond.err;
  EXPECT_THAT(beyond.err, HasSubstr("Ft = -10.5 N is beyond the rated 10 N range"));
}

TEST_F(SensorCliTest, InvertGivesTenAndTen) {
  const CliResult json = RunCli("sensor invert --r1 6664 --r2 3876 --json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json parsed = nlohmann::json::parse(json.out);
  EXPECT_NEAR(parsed.at("fn").get<double>(), 10.0, kForceTolN);
  EXPECT_NEAR(parsed.at("ft").get<double>(), 10.0, kForceTolN);
  EXPECT_EQ(parsed.at("r1").get<double>(), 6664);
  EXPECT_EQ(parsed.at("r2").get<double>(), 3876);
  const CliResult text = RunCli("sensor invert --r1 5270 --r2 5270 --r0 3400");
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_THAT(text.out, HasSubstr("Fn = 10.000 N"));
  EXPECT_THAT(text.out, HasSubstr("Ft = 0.000 N"));
  // Another tare resistance shifts the answer.
  const CliResult tare = RunCli("sensor invert --r1 3500 --r2 3500 --r0 3500 --json");
  EXPECT_NEAR(nlohmann::json::parse(tare.out).at("fn").get<double>(), 0.0, kForceTolN);
}

TEST_F(SensorCliTest, BadInputExitsTwoWithAMessage) {
  const struct {
    const char* arguments;
    const char* message;
  } cases[] = {
      {"sensor forward --fn abc", "--fn = abc: expected a number"},
      {"sensor forward --fn -1", "--fn = -1: must be >= 0"},
      {"sensor forward --fn=-0.5 --ft 2", "--fn = -0.5: must be >= 0"},
      {"sensor forward --ft=-30",
       "--ft = -30: the gauge model gives R1 = -782 Ohm, R2 = 7582 Ohm (<= 0: far beyond "
       "the rated 10 N)"},
      {"sensor forward --fn nan", "--fn = nan: must be a finite number"},
      {"sensor forward --fn inf", "--fn = inf: must be a finite number"},
      {"sensor forward --fn 1e999", "--fn = 1e999: must be a finite number"},
      {"sensor forward --fn 5 --r0 0", "--r0 = 0: must be > 0"},
      {"sensor invert --r1 3400 --r2 x", "--r2 = x: expected a number"},
      {"sensor invert --r1 -5 --r2 3400", "--r1 = -5: must be > 0"},
      {"sensor invert --r1 NaN --r2 3400", "--r1 = NaN: must be a finite number"},
      {"sensor invert --r1 3400 --r2 Infinity", "--r2 = Infinity: must be a finite number"},
      {"sensor invert --r1 0 --r2 3400", "--r1 = 0: must be > 0 (0 Ohm reads as a short circuit)"},
      {"sensor invert --r1 3400 --r2 3400 --r0 -3400", "--r0 = -3400: must be > 0"},
      {"sensor invert --r1 3400", "--r2 is required"},
  };
  for (const auto& c : cases) {
    const CliResult result = RunCli(c.arguments);
    EXPECT_EQ(result.exit_code, 2) << c.arguments;
    EXPECT_THAT(result.err, HasSubstr(c.message)) << c.arguments;
    EXPECT_EQ(result.out, "") << c.arguments;
  }
}

TEST_F(SensorCliTest, HelpOnEachSubcommand) {
  for (const char* command :
       {"sensor", "sensor forward", "sensor invert", "sensor layout", "sensor calibrate"}) {
    const CliResult result = RunCli(std::string(command) + " --help");
    EXPECT_EQ(result.exit_code, 0) << command;
    EXPECT_THAT(result.out, HasSubstr("Usage")) << command;
  }
  EXPECT_THAT(RunCli("sensor forward --help").out, HasSubstr("--json"));
}

TEST_F(SensorCliTest, LayoutPrintsPoses) {
  const CliResult text = RunCli("sensor layout");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_THAT(text.out, HasSubstr("layout default_20"));
  EXPECT_THAT(text.out, HasSubstr("20 units"));
  const CliResult json =
      RunCli("sensor layout --json --layout " + SourcePath("sensor/layouts/paper_3x3.yaml"));
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json parsed = nlohmann::json::parse(json.out);
  ASSERT_EQ(parsed.at("units").size(), 9u);
  EXPECT_EQ(parsed.at("units")[4].at("orientation"), "axial");
  EXPECT_NEAR(parsed.at("units")[4].at("position_m")[2].get<double>(), -4e-3, 1e-12);
  TempDir dir;
  const std::string bad = dir.Write("bad.yaml", "name: x\nunits:\n  - {row: 0, column: 0, axial_mm: 0}\n");
  const CliResult error = RunCli("sensor layout --layout " + bad);
  EXPECT_EQ(error.exit_code, 2);
  EXPECT_THAT(error.err, HasSubstr(bad + ":3: units[0].arc_mm = null: missing required key"));
}

TEST_F(SensorCliTest, CalibrateFitsALogAndWritesAFile) {
  TempDir dir;
  // One unit with kn 10% above the paper's, kt as the paper's, exact data.
  std::string log = "unit,fn_n,ft_n,dr1_rel,dr2_rel\n";
  for (double fn : {0.0, 5.0, 10.0}) {
    for (double ft : {-5.0, 0.0, 5.0}) {
      const double s = 100 * 6.05e-4 * fn, d = 100 * 4.1e-4 * ft;
      log += "0," + std::to_string(fn) + "," + std::to_string(ft) + "," + std::to_string(s + d) + "," +
             std::to_string(s - d) + "\n";
    }
  }
  const std::string log_path = dir.Write("log.csv", log);
  const std::string layout_path = dir.Write(
      "one.yaml", "name: one\nunits:\n  - {row: 0, column: 0, axial_mm: 0, arc_mm: 0, orientation: axial}\n");
  const std::string out_path = dir.Path("cal.yaml");
  const CliResult result =
      RunCli("sensor calibrate --json --log " + log_path + " --out " + out_path + " --layout " + layout_path);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json parsed = nlohmann::json::parse(result.out);
  EXPECT_NEAR(parsed.at("units")[0].at("kn_per_n").get<double>(), 6.05e-4, 1e-9);
  EXPECT_NEAR(parsed.at("units")[0].at("kt_per_n").get<double>(), 4.1e-4, 1e-9);
  std::FILE* written = std::fopen(out_path.c_str(), "r");
  ASSERT_NE(written, nullptr);
  std::fclose(written);
  const CliResult missing = RunCli("sensor calibrate --log " + dir.Path("none.csv") + " --out " + out_path +
                                   " --layout " + layout_path);
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_THAT(missing.err, HasSubstr("none.csv: cannot open file"));
}

}  // namespace
}  // namespace graspbed::sensor
