// `sensor.sensitivities: fea`: the strain model (and with it the host's inversion) takes kn and kt
// from graspbed's finite-element analysis of the unit instead of the paper's constants.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "sensor/calibration.h"
#include "sensor/fea/fea_config.h"
#include "sensor/fea/unit_analysis.h"
#include "testbed/scenario_config.h"
#include "tests/support/error_of.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::testbed {
namespace {

using graspbed::test_support::TempDir;

constexpr double kPaperKn = 5.5e-4;
constexpr double kPaperKt = 4.1e-4;
/// Relative tolerance of an exactly linear scaling (solver round-off only).
constexpr double kLinearTol = 1e-9;

std::string ErrorOf(const std::string& text) {
  return graspbed::test_support::ErrorOf<std::invalid_argument>(
      [&] { LoadScenarioFromString(text, "test.yaml"); });
}

/// The shipped FEA config with `from` replaced by `to`; "" when `from` is not in it.
std::string ShippedFeaConfigWith(const std::string& from, const std::string& to) {
  std::string text = graspbed::test_support::ReadText(fea::DefaultFeaConfigPath());
  const size_t at = text.find(from);
  if (at == std::string::npos) return "";
  return text.replace(at, from.size(), to);
}

TEST(SensitivitiesTest, PaperIsTheDefault) {
  const ScenarioConfig config = LoadScenarioFromString("duration_s: 1\n", "t.yaml");
  EXPECT_EQ(config.sensor.sensitivities, "paper");
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.nominal.kn_per_n, kPaperKn);
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.nominal.kt_per_n, kPaperKt);
}

TEST(SensitivitiesTest, FeaTakesKnAndKtFromTheAnalysisOfTheShippedUnit) {
  const ScenarioConfig config = LoadScenarioFromString("sensor: {sensitivities: fea}\n", "t.yaml");
  const fea::Sensitivities analysed =
      fea::ComputeSensitivities(fea::LoadFeaConfigFile(fea::DefaultFeaConfigPath()));
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.nominal.kn_per_n, analysed.kn_per_n);
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.nominal.kt_per_n, analysed.kt_per_n);
  EXPECT_NE(analysed.kn_per_n, kPaperKn);
  // The host inverts with the same nominal constants.
  const sensor::Calibration calibration = sensor::NominalCalibration(config.sensor.strain_model.nominal, 20);
  EXPECT_DOUBLE_EQ(calibration.units[7].kn_per_n, analysed.kn_per_n);
  EXPECT_DOUBLE_EQ(calibration.units[7].kt_per_n, analysed.kt_per_n);
}

TEST(SensitivitiesTest, AStifferSteelInTheFeaConfigHalvesTheSensitivities) {
  const TempDir temp("sensitivities_stiff");
  const std::filesystem::path& dir = temp.path();
  // The shipped config with twice the Young's modulus: a linear model halves every strain.
  const std::string text = ShippedFeaConfigWith("youngs_modulus_gpa: 197", "youngs_modulus_gpa: 394");
  ASSERT_FALSE(text.empty()) << "shipped FEA config no longer names youngs_modulus_gpa: 197";
  std::ofstream(dir / "stiff.yaml") << text;
  std::ofstream(dir / "scenario.yaml") << "sensor: {sensitivities: fea, fea_config: stiff.yaml}\n";

  const ScenarioConfig stiff = LoadScenario((dir / "scenario.yaml").string());
  const ScenarioConfig shipped_unit = LoadScenarioFromString("sensor: {sensitivities: fea}\n", "t.yaml");
  EXPECT_NEAR(stiff.sensor.strain_model.nominal.kn_per_n / shipped_unit.sensor.strain_model.nominal.kn_per_n,
              0.5, kLinearTol);
  EXPECT_NEAR(stiff.sensor.strain_model.nominal.kt_per_n / shipped_unit.sensor.strain_model.nominal.kt_per_n,
              0.5, kLinearTol);
  // The resolved configuration names the file absolutely and loads back to the same constants.
  const ScenarioConfig again =
      LoadScenarioFromString(EmitScenarioYaml(stiff), (dir / "resolved.yaml").string());
  EXPECT_EQ(again.sensor.fea_config, (dir / "stiff.yaml").lexically_normal().string());
  EXPECT_DOUBLE_EQ(again.sensor.strain_model.nominal.kn_per_n, stiff.sensor.strain_model.nominal.kn_per_n);
}

TEST(SensitivitiesTest, AFeaConfigEditedBetweenLoadsIsAnalysedAgain) {
  // The loader keeps each unit's analysis for the process (the scorecard loads one unit many
  // times); the key is the config's content, so a file edited between loads gives its new unit.
  const TempDir temp("sensitivities_edited");
  const std::filesystem::path& dir = temp.path();
  std::ofstream(dir / "unit.yaml") << graspbed::test_support::ReadText(fea::DefaultFeaConfigPath());
  std::ofstream(dir / "scenario.yaml") << "sensor: {sensitivities: fea, fea_config: unit.yaml}\n";
  const ScenarioConfig first = LoadScenario((dir / "scenario.yaml").string());
  const ScenarioConfig again = LoadScenario((dir / "scenario.yaml").string());
  EXPECT_DOUBLE_EQ(again.sensor.strain_model.nominal.kn_per_n, first.sensor.strain_model.nominal.kn_per_n);
  EXPECT_DOUBLE_EQ(again.sensor.strain_model.nominal.kt_per_n, first.sensor.strain_model.nominal.kt_per_n);

  const std::string stiff = ShippedFeaConfigWith("youngs_modulus_gpa: 197", "youngs_modulus_gpa: 394");
  ASSERT_FALSE(stiff.empty()) << "shipped FEA config no longer names youngs_modulus_gpa: 197";
  std::ofstream(dir / "unit.yaml") << stiff;
  const ScenarioConfig edited = LoadScenario((dir / "scenario.yaml").string());
  EXPECT_NEAR(edited.sensor.strain_model.nominal.kn_per_n / first.sensor.strain_model.nominal.kn_per_n, 0.5,
              kLinearTol);
  EXPECT_NEAR(edited.sensor.strain_model.nominal.kt_per_n / first.sensor.strain_model.nominal.kt_per_n, 0.5,
              kLinearTol);
}

TEST(SensitivitiesTest, BadValuesNameFileLineKeyAndValue) {
  std::string error = ErrorOf("duration_s: 1\nsensor:\n  sensitivities: ansys\n");
  EXPECT_NE(error.find("test.yaml:3"), std::string::npos) << error;
  EXPECT_NE(error.find("sensor.sensitivities"), std::string::npos) << error;
  EXPECT_NE(error.find("ansys"), std::string::npos) << error;
  EXPECT_NE(error.find("fea"), std::string::npos) << error;  // lists the valid names

  error = ErrorOf("sensor:\n  sensitivities: fea\n  fea_config: no_such_unit.yaml\n");
  EXPECT_NE(error.find("test.yaml:3"), std::string::npos) << error;
  EXPECT_NE(error.find("sensor.fea_config"), std::string::npos) << error;
  EXPECT_NE(error.find("no such file"), std::string::npos) << error;
}

TEST(SensitivitiesTest, AUnitWhoseGaugeDoesNotSenseShearIsRefusedAtTheSensitivitiesKey) {
  // A 0.3 mm beam puts the sign change of the shear profile inside the resistors: kt comes out
  // negative, and the strain model cannot use it.
  const TempDir temp("sensitivities_thick");
  const std::filesystem::path& dir = temp.path();
  const std::string text = ShippedFeaConfigWith("beam_thickness_mm: 0.2", "beam_thickness_mm: 0.3");
  ASSERT_FALSE(text.empty());
  std::ofstream(dir / "thick.yaml") << text;
  const std::string error = ErrorOf(
      "duration_s: 1\nsensor:\n  sensitivities: fea\n  fea_config: " + (dir / "thick.yaml").string() + "\n");
  EXPECT_NE(error.find("test.yaml:3"), std::string::npos) << error;
  EXPECT_NE(error.find("sensor.sensitivities"), std::string::npos) << error;
  EXPECT_NE(error.find("kt_per_n"), std::string::npos) << error;
}

}  // namespace
}  // namespace graspbed::testbed
