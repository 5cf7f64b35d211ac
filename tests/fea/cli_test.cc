// `graspbed fea` end to end: the real binary, real files.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "sensor/calibration.h"

namespace graspbed::fea {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class FeaCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* binary = std::getenv("GRASPBED_BINARY");
    if (binary == nullptr) GTEST_SKIP() << "GRASPBED_BINARY not set (run through ctest)";
    binary_ = binary;
    dir_ = fs::temp_directory_path() /
           ("graspbed_fea_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  RunResult Run(const std::string& arguments) {
    const std::string command = binary_ + " fea " + arguments + " >" + (dir_ / "stdout").string() + " 2>" +
                                (dir_ / "stderr").string();
    const int status = std::system(command.c_str());
    RunResult result;
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.out = ReadFile(dir_ / "stdout");
    result.err = ReadFile(dir_ / "stderr");
    return result;
  }
  std::string binary_;
  fs::path dir_;
};

TEST_F(FeaCliTest, JsonSummaryCurvesPlotsAndCalibration) {
  const fs::path out = dir_ / "report";
  const fs::path calibration = dir_ / "calibration.yaml";
  const RunResult run = Run("--json --out " + out.string() + " --write-calibration " + calibration.string());
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
  EXPECT_EQ(ReadFile(out / "fea_profile.png").substr(1, 3), "PNG");
  const std::string sweep = ReadFile(out / "fea_sweep.csv");
  EXPECT_EQ(std::count(sweep.begin(), sweep.end(), '\n'), 12);  // header + 0..10 N
  // The written calibration carries the analysis' sensitivities into the sensor model.
  const sensor::Calibration loaded = sensor::LoadCalibration(calibration.string(), 20);
  ASSERT_EQ(loaded.unit_count(), 20);
  EXPECT_NEAR(loaded.units[7].kn_per_n, kn, 1e-6 * kn);
  EXPECT_NEAR(loaded.units[7].kt_per_n, kt, 1e-6 * kt);
  EXPECT_DOUBLE_EQ(loaded.units[7].gauge_factor, 100.0);
  // The config that was used round-trips through the loader.
  const RunResult again = Run("--json --config " + (out / "fea_config_used.yaml").string());
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NEAR(nlohmann::json::parse(again.out).at("kn").get<double>(), kn, 1e-9 * kn);
}

TEST_F(FeaCliTest, BadConfigExitsTwoNamingFileLineKey) {
  const fs::path config = dir_ / "bad.yaml";
  std::ofstream(config) << "geometry:\n  beam_thickness_mm: 0.2\nmesh:\n  element_size_mm: 0.4\n";
  const RunResult run = Run("--config " + config.string() + " --out " + (dir_ / "never").string());
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr(config.string() + ":4: mesh.element_size_mm = 0.4: too coarse"));
  EXPECT_FALSE(fs::exists(dir_ / "never"));
}

TEST_F(FeaCliTest, TableOutputByDefault) {
  const RunResult run = Run("");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr("k_n [1/N]"));
  EXPECT_THAT(run.out, HasSubstr("superposition error"));
}

}  // namespace
}  // namespace graspbed::fea
