// `graspbed fea` end to end: the real binary, real files.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "sensor/calibration.h"
#include "tests/support/cli_runner.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::fea {
namespace {

namespace fs = std::filesystem;
using graspbed::test_support::CliBinary;
using graspbed::test_support::CliResult;
using graspbed::test_support::ReadText;
using graspbed::test_support::RunCli;
using graspbed::test_support::TempDir;
using ::testing::HasSubstr;

class FeaCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY must point at the CLI (run through ctest)";
  }
  /// Runs `graspbed fea <arguments>`.
  CliResult Run(const std::string& arguments) { return RunCli("fea " + arguments); }

  const TempDir temp_dir_{"fea_cli"};
  const fs::path dir_ = temp_dir_.path();
};

TEST_F(FeaCliTest, JsonSummaryCurvesPlotsAndCalibration) {
  const fs::path out = dir_ / "report";
  const fs::path calibration = dir_ / "calibration.yaml";
  const CliResult run = Run("--json --out " + out.string() + " --write-calibration " + calibration.string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json json = nlohmann::json::parse(run.out);
  const double kn = json.at("kn").get<double>();
  const double kt = json.at("kt").get<double>();
  EXPECT_GT(kn, 0.0);
  EXPECT_GT(kt, 0.0);
  EXPECT_GT(json.at("linearity").at("normal_r2").get<double>(), 0.9999);
  EXPECT_GT(json.at("linearity").at("shear_r2").get<double>(), 0.9999);
  EXPECT_LT(json.at("superposition_error").get<double>(), 0.01);
  EXPECT_NEAR(json.at("kn_ratio").get<double>(), kn / 5.5e-4, 1e-12);
  for (const char* name : {"fea_profile.csv", "fea_sweep.csv", "fea_profile.png", "fea_sweep.png",
                           "fea_summary.json", "fea_config_used.yaml"}) {
    EXPECT_TRUE(fs::is_regular_file(out / name)) << name;
    EXPECT_GT(fs::file_size(out / name), 100u) << name;
  }
  EXPECT_EQ(ReadText(out / "fea_profile.png").substr(1, 3), "PNG");
  const std::string sweep = ReadText(out / "fea_sweep.csv");
  EXPECT_EQ(std::count(sweep.begin(), sweep.end(), '\n'), 12);  // header + 0..10 N
  // The written calibration carries the analysis' sensitivities into the sensor model.
  const sensor::Calibration loaded = sensor::LoadCalibration(calibration.string(), 20);
  ASSERT_EQ(loaded.unit_count(), 20);
  EXPECT_NEAR(loaded.units[7].kn_per_n, kn, 1e-6 * kn);
  EXPECT_NEAR(loaded.units[7].kt_per_n, kt, 1e-6 * kt);
  EXPECT_DOUBLE_EQ(loaded.units[7].gauge_factor, 100.0);
  // The config that was used round-trips through the loader.
  const CliResult again = Run("--json --config " + (out / "fea_config_used.yaml").string());
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NEAR(nlohmann::json::parse(again.out).at("kn").get<double>(), kn, 1e-9 * kn);
}

TEST_F(FeaCliTest, BadConfigExitsTwoNamingFileLineKey) {
  const fs::path config = dir_ / "bad.yaml";
  std::ofstream(config) << "geometry:\n  beam_thickness_mm: 0.2\nmesh:\n  element_size_mm: 0.4\n";
  const CliResult run = Run("--config " + config.string() + " --out " + (dir_ / "never").string());
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr(config.string() + ":4: mesh.element_size_mm = 0.4: too coarse"));
  EXPECT_FALSE(fs::exists(dir_ / "never"));
}

TEST_F(FeaCliTest, TableOutputByDefault) {
  const CliResult run = Run("");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr("k_n [1/N]"));
  EXPECT_THAT(run.out, HasSubstr("superposition error"));
}

}  // namespace
}  // namespace graspbed::fea
