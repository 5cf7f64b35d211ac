// `sensor.profile`: a scenario picks a realistic readout chain with one key; explicit strain_model
// and readout keys override it; unknown names are refused at file:line:key.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "sensor/sensor_profile.h"
#include "testbed/scenario_config.h"
#include "tests/support/error_of.h"

namespace graspbed::testbed {
namespace {

std::string ErrorOf(const std::string& text) {
  return graspbed::test_support::ErrorOf<std::invalid_argument>(
      [&] { LoadScenarioFromString(text, "test.yaml"); });
}

TEST(SensorProfileConfigTest, IdealIsTheDefaultAndChangesNothing) {
  const ScenarioConfig config = LoadScenarioFromString("duration_s: 1\n", "t.yaml");
  EXPECT_EQ(config.sensor.profile, "ideal");
  EXPECT_EQ(config.sensor.strain_model.noise_ohm, 0.0);
  EXPECT_EQ(config.sensor.strain_model.adc_bits, 0);
  EXPECT_EQ(config.sensor.readout.adc_full_scale_ohm, 0.0);
}

TEST(SensorProfileConfigTest, AProfileSetsTheStrainModelAndTheReadoutWindow) {
  const ScenarioConfig config = LoadScenarioFromString("sensor: {profile: inamp_16bit}\n", "t.yaml");
  const sensor::SensorProfile& profile = sensor::FindSensorProfile("inamp_16bit");
  const sensor::StrainModelConfig expected = sensor::ProfileStrainModel(profile, sensor::UnitConstants{});
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.noise_ohm, expected.noise_ohm);
  EXPECT_EQ(config.sensor.strain_model.adc_bits, 16);
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.r0_spread_fraction, expected.r0_spread_fraction);
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.temperature_coefficient_per_k,
                   expected.temperature_coefficient_per_k);
  EXPECT_DOUBLE_EQ(config.sensor.readout.adc_full_scale_ohm, expected.adc_full_scale_ohm);
  EXPECT_DOUBLE_EQ(config.sensor.readout.adc_min_ohm, expected.adc_min_ohm);
  EXPECT_EQ(config.sensor.readout.baseline_frames, sensor::ReadoutConfig{}.baseline_frames);
}

TEST(SensorProfileConfigTest, TheProfileIsResolvedAgainstTheFeaSensitivities) {
  const ScenarioConfig paper = LoadScenarioFromString("sensor: {profile: inamp_16bit}\n", "t.yaml");
  const ScenarioConfig fea =
      LoadScenarioFromString("sensor: {profile: inamp_16bit, sensitivities: fea}\n", "t.yaml");
  // A board designed for the FEA's 16-65x smaller signal has more gain: a narrower window.
  EXPECT_LT(fea.sensor.strain_model.adc_full_scale_ohm - fea.sensor.strain_model.adc_min_ohm,
            0.2 * (paper.sensor.strain_model.adc_full_scale_ohm - paper.sensor.strain_model.adc_min_ohm));
  EXPECT_LT(fea.sensor.strain_model.nominal.kt_per_n, 0.1 * paper.sensor.strain_model.nominal.kt_per_n);
}

TEST(SensorProfileConfigTest, ExplicitKeysOverrideTheProfile) {
  const ScenarioConfig config = LoadScenarioFromString(
      "sensor:\n  profile: divider_12bit\n  strain_model: {noise_ohm: 0.5, cross_talk_shear_fraction: 0}\n"
      "  readout: {baseline_frames: 50}\n",
      "t.yaml");
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.noise_ohm, 0.5);
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.cross_talk_shear_fraction, 0.0);
  EXPECT_EQ(config.sensor.strain_model.adc_bits, 12);  // still the profile's
  EXPECT_DOUBLE_EQ(config.sensor.strain_model.sensitivity_spread_fraction, 0.05);
  EXPECT_EQ(config.sensor.readout.baseline_frames, 50);
  EXPECT_DOUBLE_EQ(config.sensor.readout.adc_full_scale_ohm, config.sensor.strain_model.adc_full_scale_ohm);
}

TEST(SensorProfileConfigTest, TheResolvedConfigReloadsToTheSameValues) {
  const ScenarioConfig config = LoadScenarioFromString(
      "sensor: {profile: bridge_24bit, sensitivities: fea, strain_model: {noise_ohm: 0.02}}\n", "t.yaml");
  const ScenarioConfig again = LoadScenarioFromString(EmitScenarioYaml(config), "resolved.yaml");
  EXPECT_EQ(again.sensor.profile, "bridge_24bit");
  EXPECT_DOUBLE_EQ(again.sensor.strain_model.noise_ohm, 0.02);
  EXPECT_NEAR(again.sensor.strain_model.adc_min_ohm, config.sensor.strain_model.adc_min_ohm, 1e-6);
  EXPECT_NEAR(again.sensor.readout.adc_full_scale_ohm, config.sensor.readout.adc_full_scale_ohm, 1e-6);
  EXPECT_EQ(EmitScenarioYaml(again), EmitScenarioYaml(config));
}

TEST(SensorProfileConfigTest, UnknownProfileNamesFileLineKeyAndTheValidNames) {
  const std::string error = ErrorOf("duration_s: 1\nsensor:\n  profile: realistic\n");
  EXPECT_NE(error.find("test.yaml:3"), std::string::npos) << error;
  EXPECT_NE(error.find("sensor.profile"), std::string::npos) << error;
  EXPECT_NE(error.find("inamp_16bit"), std::string::npos) << error;
}

TEST(SensorProfileConfigTest, AnAdcWindowUpsideDownIsRefusedAtItsKey) {
  const std::string error =
      ErrorOf("sensor:\n  profile: inamp_16bit\n  strain_model:\n    adc_min_ohm: 20000\n");
  EXPECT_NE(error.find("test.yaml:4"), std::string::npos) << error;
  EXPECT_NE(error.find("adc_min_ohm"), std::string::npos) << error;
}

}  // namespace
}  // namespace graspbed::testbed
