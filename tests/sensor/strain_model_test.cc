#include "sensor/strain_model.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/readout.h"
#include "tests/support/error_of.h"
#include "tests/support/temp_dir.h"

namespace graspbed::sensor {
namespace {

using test_support::ErrorOf;
using test_support::TempDir;
using ::testing::HasSubstr;

constexpr double kOhmTol = 1e-6;      // exact model, rounding only
constexpr double kPaperOhmTol = 0.5;  // the paper quotes whole ohms
constexpr double kForceTolN = 1e-9;

Layout DefaultLayout() { return LoadLayout(DefaultLayoutPath()); }

std::vector<UnitLoad> Uniform(const Layout& layout, double fn_n, double ft_n) {
  return std::vector<UnitLoad>(static_cast<size_t>(layout.unit_count()), UnitLoad{fn_n, ft_n, 0.0, 0.0});
}

// Runs `model` through a readout tared on `tare_frames` unloaded frames, then inverts one frame of
// `loads` at `time_s`.
TactileState Estimate(const Layout& layout, StrainModel& model, const std::vector<UnitLoad>& loads,
                      double time_s, int tare_frames = 100, ReadoutConfig readout_config = {}) {
  readout_config.baseline_frames = tare_frames;
  Readout readout(readout_config, layout.unit_count(), model.config().nominal.r0_ohm);
  const Inversion inversion(layout, PaperCalibration(layout.unit_count()), InversionConfig{});
  RawFrame frame;
  ReadoutFrame readout_frame;
  const std::vector<UnitLoad> unloaded = Uniform(layout, 0, 0);
  for (int i = 0; i < tare_frames; ++i) {
    model.Sample(unloaded, i * 1e-3, &frame);
    readout.Process(frame, &readout_frame);
  }
  model.Sample(loads, time_s, &frame);
  readout.Process(frame, &readout_frame);
  TactileState state;
  inversion.Invert(readout_frame, &state);
  return state;
}

TEST(StrainModelTest, PaperWorkedNumbers) {
  const UnitConstants paper;
  const GaugeResistances normal = IdealGaugeResistances(paper, 10, 0);
  EXPECT_NEAR(normal.r1_ohm, 5270, kPaperOhmTol);
  EXPECT_NEAR(normal.r2_ohm, 5270, kPaperOhmTol);
  const GaugeResistances shear = IdealGaugeResistances(paper, 0, 10);
  EXPECT_NEAR(shear.r1_ohm, 4794, kPaperOhmTol);
  EXPECT_NEAR(shear.r2_ohm, 2006, kPaperOhmTol);
  const GaugeResistances both = IdealGaugeResistances(paper, 10, 10);
  EXPECT_NEAR(both.r1_ohm, 6664, kPaperOhmTol);
  EXPECT_NEAR(both.r2_ohm, 3876, kPaperOhmTol);
  // The inversion of the paper's numbers gives 10 N, 10 N back.
  const UnitForces forces = InvertUnit(UnitCalibration{}, 6664.0 / 3400 - 1, 3876.0 / 3400 - 1);
  EXPECT_NEAR(forces.fn_n, 10.0, kForceTolN);
  EXPECT_NEAR(forces.ft_n, 10.0, kForceTolN);
}

TEST(StrainModelTest, SampleMatchesIdealModelForEveryUnit) {
  const Layout layout = DefaultLayout();
  StrainModel model(layout, StrainModelConfig{}, 1);
  std::vector<UnitLoad> loads(20);
  for (int i = 0; i < 20; ++i) loads[i] = {0.5 * i, 0.4 * i - 4.0, 0.0, 0.0};
  RawFrame frame;
  model.Sample(loads, 0.25, &frame);
  EXPECT_EQ(frame.unit_count, 20);
  EXPECT_EQ(frame.sequence, 0u);
  EXPECT_DOUBLE_EQ(frame.time_s, 0.25);
  for (int i = 0; i < 20; ++i) {
    const GaugeResistances ideal = IdealGaugeResistances(UnitConstants{}, loads[i].fn_n, loads[i].ft_n);
    EXPECT_NEAR(frame.r1_ohm[i], ideal.r1_ohm, kOhmTol);
    EXPECT_NEAR(frame.r2_ohm[i], ideal.r2_ohm, kOhmTol);
  }
  model.Sample(loads, 0.26, &frame);
  EXPECT_EQ(frame.sequence, 1u);
  const std::vector<UnitLoad> too_few(3);
  EXPECT_THAT(ErrorOf([&] { model.Sample(too_few, 0, &frame); }), HasSubstr("3 loads for 20 units"));
}

TEST(StrainModelTest, SuperpositionOfNormalAndShear) {
  const UnitConstants paper;
  for (double fn : {0.0, 1.3, 4.0, 7.7, 10.0}) {
    for (double ft : {-10.0, -2.5, 0.0, 3.1, 10.0}) {
      const GaugeResistances both = IdealGaugeResistances(paper, fn, ft);
      const GaugeResistances normal = IdealGaugeResistances(paper, fn, 0);
      const GaugeResistances shear = IdealGaugeResistances(paper, 0, ft);
      EXPECT_NEAR(both.r1_ohm - paper.r0_ohm, (normal.r1_ohm - paper.r0_ohm) + (shear.r1_ohm - paper.r0_ohm),
                  kOhmTol);
      EXPECT_NEAR(both.r2_ohm - paper.r0_ohm, (normal.r2_ohm - paper.r0_ohm) + (shear.r2_ohm - paper.r0_ohm),
                  kOhmTol);
    }
  }
}

TEST(StrainModelTest, SameSeedSameFramesDifferentSeedDifferent) {
  const Layout layout = DefaultLayout();
  StrainModelConfig config;
  config.noise_ohm = 1.0;
  config.r0_spread_fraction = 0.01;
  config.sensitivity_spread_fraction = 0.02;
  StrainModel a(layout, config, 42), b(layout, config, 42), c(layout, config, 43);
  const std::vector<UnitLoad> loads = Uniform(layout, 3.0, 1.0);
  RawFrame fa, fb, fc;
  bool any_difference = false;
  for (int i = 0; i < 50; ++i) {
    a.Sample(loads, i * 1e-3, &fa);
    b.Sample(loads, i * 1e-3, &fb);
    c.Sample(loads, i * 1e-3, &fc);
    for (int u = 0; u < 20; ++u) {
      ASSERT_EQ(fa.r1_ohm[u], fb.r1_ohm[u]);
      ASSERT_EQ(fa.r2_ohm[u], fb.r2_ohm[u]);
      any_difference |= fa.r1_ohm[u] != fc.r1_ohm[u];
    }
  }
  EXPECT_TRUE(any_difference);
  EXPECT_EQ(a.r0_ohm_r1(), b.r0_ohm_r1());
  EXPECT_NE(a.r0_ohm_r1(), c.r0_ohm_r1());
}

TEST(StrainModelTest, R0SpreadVariesChannelsAndTareRemovesIt) {
  const Layout layout = DefaultLayout();
  StrainModelConfig config;
  config.r0_spread_fraction = 0.02;
  StrainModel model(layout, config, 7);
  double sum = 0, sum_sq = 0;
  int count = 0;
  for (const auto* values : {&model.r0_ohm_r1(), &model.r0_ohm_r2()}) {
    for (double r0 : *values) {
      EXPECT_LE(std::abs(r0 / 3400 - 1), 3 * 0.02 + 1e-12);  // clipped at 3 sigma
      sum += r0;
      sum_sq += r0 * r0;
      ++count;
    }
  }
  const double std_dev = std::sqrt(sum_sq / count - (sum / count) * (sum / count));
  EXPECT_GT(std_dev, 0.5 * 0.02 * 3400);
  EXPECT_LT(std_dev, 1.5 * 0.02 * 3400);
  // Unloaded frames read R0 of each channel, not the nominal value.
  RawFrame frame;
  model.Sample(Uniform(layout, 0, 0), 0, &frame);
  EXPECT_NEAR(frame.r1_ohm[5], model.r0_ohm_r1()[5], kOhmTol);
  EXPECT_GT(std::abs(frame.r1_ohm[5] - 3400), 1e-3);
  // dR/R against the tared baseline is spread-free, so the paper inversion is exact.
  const TactileState state = Estimate(layout, model, Uniform(layout, 6.0, -3.0), 0.2);
  for (int u = 0; u < 20; ++u) {
    EXPECT_NEAR(state.fn_n[u], 6.0, kForceTolN);
    EXPECT_NEAR(state.ft_n[u], -3.0, kForceTolN);
  }
}

TEST(StrainModelTest, SensitivitySpreadChangesSignalPerUnit) {
  const Layout layout = DefaultLayout();
  StrainModelConfig config;
  config.sensitivity_spread_fraction = 0.05;
  StrainModel model(layout, config, 3);
  const TactileState state = Estimate(layout, model, Uniform(layout, 5.0, 5.0), 0.2);
  int off_by_half_percent = 0;
  for (int u = 0; u < 20; ++u) {
    // The paper calibration reads F k_true / k_nominal.
    EXPECT_NEAR(state.fn_n[u], 5.0 * model.kn_per_n()[u] / 5.5e-4, 1e-9);
    EXPECT_NEAR(state.ft_n[u], 5.0 * model.kt_per_n()[u] / 4.1e-4, 1e-9);
    off_by_half_percent += std::abs(state.fn_n[u] - 5.0) > 0.025;
  }
  EXPECT_GT(off_by_half_percent, 5);
}

TEST(StrainModelTest, NoiseHasConfiguredStandardDeviationAndScales) {
  const Layout layout = DefaultLayout();
  StrainModelConfig config;
  config.noise_ohm = 2.0;
  StrainModel model(layout, config, 11);
  const std::vector<UnitLoad> loads = Uniform(layout, 4.0, 0.0);
  const double ideal = IdealGaugeResistances(UnitConstants{}, 4.0, 0.0).r1_ohm;
  RawFrame frame;
  double sum = 0, sum_sq = 0;
  constexpr int kFrames = 2000;
  for (int i = 0; i < kFrames; ++i) {
    model.Sample(loads, i * 1e-3, &frame);
    for (int u = 0; u < 20; ++u) {
      const double error = frame.r1_ohm[u] - ideal;
      sum += error;
      sum_sq += error * error;
    }
  }
  const int n = kFrames * 20;
  EXPECT_NEAR(sum / n, 0.0, 0.05);
  EXPECT_NEAR(std::sqrt(sum_sq / n), 2.0, 0.05);
  model.SetNoiseScale(0.0);
  model.Sample(loads, 3.0, &frame);
  EXPECT_NEAR(frame.r1_ohm[0], ideal, kOhmTol);
  model.SetNoiseScale(10.0);
  double sq = 0;
  for (int i = 0; i < 200; ++i) {
    model.Sample(loads, 3.0, &frame);
    sq += std::pow(frame.r1_ohm[0] - ideal, 2);
  }
  EXPECT_NEAR(std::sqrt(sq / 200), 20.0, 3.0);
}

TEST(StrainModelTest, AdcQuantisesAndClipsAtFullScale) {
  const Layout layout = DefaultLayout();
  StrainModelConfig config;
  config.adc_bits = 12;
  config.adc_full_scale_ohm = 8000;
  StrainModel model(layout, config, 1);
  const double lsb = 8000.0 / 4095;
  std::vector<UnitLoad> loads(20);
  for (int u = 0; u < 20; ++u) loads[u] = {0.37 * u, 0.11 * u, 0, 0};
  loads[19] = {30.0, 0.0, 0.0, 0.0};  // 3400 (1 + 1.65) = 9010 Ohm > full scale
  RawFrame frame;
  model.Sample(loads, 0, &frame);
  bool any_rounded = false;
  for (int u = 0; u < 19; ++u) {
    const double ideal = IdealGaugeResistances(UnitConstants{}, loads[u].fn_n, loads[u].ft_n).r1_ohm;
    EXPECT_LE(std::abs(frame.r1_ohm[u] - ideal), lsb / 2 + 1e-9);
    EXPECT_NEAR(std::fmod(frame.r1_ohm[u] / lsb + 0.5, 1.0), 0.5, 1e-6) << "a whole number of LSBs";
    any_rounded |= std::abs(frame.r1_ohm[u] - ideal) > 1e-6;
  }
  EXPECT_TRUE(any_rounded);
  EXPECT_DOUBLE_EQ(frame.r1_ohm[19], 8000.0);
  // The readout, told the ADC range, reports that unit out of range.
  ReadoutConfig readout_config;
  readout_config.adc_full_scale_ohm = 8000;
  const TactileState state = Estimate(layout, model, loads, 0.2, 10, readout_config);
  EXPECT_EQ(state.validity[19], UnitValidity::kOutOfRange);
  EXPECT_EQ(state.validity[0], UnitValidity::kValid);
}

TEST(StrainModelTest, TemperatureDriftScalesR0AndShowsAsApparentNormalForce) {
  const Layout layout = DefaultLayout();
  StrainModelConfig config;
  config.temperature_coefficient_per_k = 1e-3;
  config.temperature_offset_k = 10.0;
  StrainModel model(layout, config, 1);
  RawFrame frame;
  model.Sample(Uniform(layout, 0, 0), 0.0, &frame);
  EXPECT_NEAR(frame.r1_ohm[0], 3400 * 1.01, kOhmTol);
  model.SetTemperatureOffsetK(-10.0);
  model.Sample(Uniform(layout, 0, 0), 0.0, &frame);
  EXPECT_NEAR(frame.r1_ohm[0], 3400.0, kOhmTol);

  config.temperature_offset_k = 0.0;
  config.temperature_ramp_k_per_s = 2.0;
  StrainModel ramp(layout, config, 1);
  EXPECT_DOUBLE_EQ(ramp.TemperatureOffsetK(5.0), 10.0);
  // Tared at t ~ 0..0.1 s (mean dT 0.099 K), read at t = 5 s: dR/R = alpha dT' both channels.
  const TactileState state = Estimate(layout, ramp, Uniform(layout, 0, 0), 5.0);
  const double baseline_factor = 1 + 1e-3 * 2.0 * 0.0495;  // mean of t = 0..0.099 s
  const double drift = (1 + 1e-3 * 10.0) / baseline_factor - 1;
  EXPECT_NEAR(state.fn_n[0], drift / (2 * 100 * 5.5e-4) * 2, 1e-9);
  EXPECT_GT(state.fn_n[0], 0.17);
  EXPECT_NEAR(state.ft_n[0], 0.0, kForceTolN);
}

TEST(StrainModelTest, SaturationClipsTheGaugeAndTheInversionFlagsIt) {
  const Layout layout = DefaultLayout();
  StrainModelConfig config;
  config.saturation_force_n = 11.0;
  StrainModel model(layout, config, 1);
  std::vector<UnitLoad> loads = Uniform(layout, 5.0, 2.0);
  loads[0] = {20.0, 0.0, 0.0, 0.0};
  loads[1] = {11.0, 0.0, 0.0, 0.0};
  loads[2] = {3.0, -25.0, 0.0, 0.0};
  RawFrame frame;
  model.Sample(loads, 0, &frame);
  EXPECT_DOUBLE_EQ(frame.r1_ohm[0], frame.r1_ohm[1]);  // 20 N reads as 11 N
  EXPECT_NEAR(frame.r1_ohm[2], IdealGaugeResistances(UnitConstants{}, 3.0, -11.0).r1_ohm, kOhmTol);
  const TactileState state = Estimate(layout, model, loads, 0.2);
  EXPECT_EQ(state.validity[0], UnitValidity::kOutOfRange);
  EXPECT_NEAR(state.fn_n[0], 11.0, 1e-9);
  EXPECT_EQ(state.validity[2], UnitValidity::kOutOfRange);
  EXPECT_EQ(state.validity[3], UnitValidity::kValid);
  EXPECT_NEAR(state.fn_n[3], 5.0, kForceTolN);
  // Without saturation 20 N stays linear (and is still beyond the rated range).
  StrainModel linear(layout, StrainModelConfig{}, 1);
  const TactileState unclipped = Estimate(layout, linear, loads, 0.2);
  EXPECT_NEAR(unclipped.fn_n[0], 20.0, 1e-9);
  EXPECT_EQ(unclipped.validity[0], UnitValidity::kOutOfRange);
}

TEST(StrainModelTest, CrossTalkFromCrossShearAndOffCentreLoad) {
  const Layout layout = DefaultLayout();
  std::vector<UnitLoad> loads = Uniform(layout, 0, 0);
  loads[0] = {4.0, 0.0, 5.0, 0.0};      // cross-axis shear only
  loads[1] = {10.0, 0.0, 0.0, 0.5e-3};  // normal load 0.5 mm off centre along the beam
  {
    StrainModel ideal(layout, StrainModelConfig{}, 1);
    const TactileState state = Estimate(layout, ideal, loads, 0.2);
    EXPECT_NEAR(state.ft_n[0], 0.0, kForceTolN);
    EXPECT_NEAR(state.ft_n[1], 0.0, kForceTolN);
  }
  StrainModelConfig config;
  config.cross_talk_shear_fraction = 0.1;
  {
    StrainModel model(layout, config, 1);
    const TactileState state = Estimate(layout, model, loads, 0.2);
    EXPECT_NEAR(state.ft_n[0], 0.5, kForceTolN);
    EXPECT_NEAR(state.fn_n[0], 4.0, kForceTolN);
    EXPECT_NEAR(state.ft_n[1], 0.0, kForceTolN);
  }
  config.cross_talk_shear_fraction = 0.0;
  config.cross_talk_offset_per_mm = 0.2;
  {
    StrainModel model(layout, config, 1);
    const TactileState state = Estimate(layout, model, loads, 0.2);
    EXPECT_NEAR(state.ft_n[1], 0.2 * 0.5 * 10.0, kForceTolN);
    EXPECT_NEAR(state.ft_n[0], 0.0, kForceTolN);
  }
}

TEST(StrainModelTest, DeadAndShortedUnitsFromConfigAndAtRuntime) {
  const Layout layout = DefaultLayout();
  StrainModelConfig config;
  config.dead_units = {3};
  config.shorted_units = {4};
  StrainModel model(layout, config, 1);
  RawFrame frame;
  model.Sample(Uniform(layout, 2, 0), 0, &frame);
  EXPECT_EQ(frame.r1_ohm[3], kOpenCircuitOhm);
  EXPECT_EQ(frame.r2_ohm[3], kOpenCircuitOhm);
  EXPECT_EQ(frame.r1_ohm[4], kShortCircuitOhm);
  EXPECT_EQ(frame.r2_ohm[4], kShortCircuitOhm);
  EXPECT_GT(frame.r1_ohm[5], 3400);
  model.SetUnitFault(5, UnitFault::kOpen);
  model.SetUnitFault(3, UnitFault::kNone);
  model.SetBiasOhm(6, 100.0, -50.0);
  model.Sample(Uniform(layout, 0, 0), 0, &frame);
  EXPECT_EQ(frame.r1_ohm[5], kOpenCircuitOhm);
  EXPECT_NEAR(frame.r1_ohm[3], 3400, kOhmTol);
  EXPECT_NEAR(frame.r1_ohm[6], 3500, kOhmTol);
  EXPECT_NEAR(frame.r2_ohm[6], 3350, kOhmTol);
  const TactileState state = Estimate(layout, model, Uniform(layout, 1, 0), 0.2);
  EXPECT_EQ(state.validity[5], UnitValidity::kOpen);
  EXPECT_EQ(state.validity[4], UnitValidity::kShort);
  EXPECT_EQ(state.valid_count, 18);
  // Unit 6's bias is part of its tared baseline, so it reads dR/R = R0 x / (R0 + bias): a bit low.
  const double unit6_fn = 0.5 * (3400.0 / 3500 + 3400.0 / 3350);
  EXPECT_NEAR(state.fn_n[6], unit6_fn, 1e-9);
  EXPECT_NEAR(state.total_fn_n, 17.0 + unit6_fn, 1e-9);
  EXPECT_THAT(ErrorOf([&] { model.SetUnitFault(20, UnitFault::kOpen); }), HasSubstr("unit 20 outside 0..19"));
  StrainModelConfig bad;
  bad.dead_units = {25};
  EXPECT_THAT(ErrorOf([&] { StrainModel m(layout, bad, 1); }), HasSubstr("unit 25 outside 0..19"));
}

TEST(StrainModelConfigTest, LoadsEveryKeyFromYaml) {
  TempDir dir;
  const std::string path = dir.Write("strain.yaml", R"(r0_ohm: 3500
gauge_factor: 90
kn_per_n: 5.0e-4
kt_per_n: 4.0e-4
rated_force_n: 12
r0_spread_fraction: 0.01
sensitivity_spread_fraction: 0.02
noise_ohm: 0.5
adc_bits: 16
adc_full_scale_ohm: 9000
temperature_coefficient_per_k: 2.0e-3
temperature_offset_k: 1.5
temperature_ramp_k_per_s: 0.01
saturation_force_n: 11
cross_talk_shear_fraction: 0.05
cross_talk_offset_per_mm: 0.1
dead_units: [1, 2]
shorted_units: [7]
)");
  const StrainModelConfig config = LoadStrainModelConfig(common::YamlMap::LoadFile(path), 20);
  EXPECT_EQ(config.nominal.r0_ohm, 3500);
  EXPECT_EQ(config.nominal.gauge_factor, 90);
  EXPECT_EQ(config.nominal.kn_per_n, 5.0e-4);
  EXPECT_EQ(config.nominal.kt_per_n, 4.0e-4);
  EXPECT_EQ(config.nominal.rated_force_n, 12);
  EXPECT_EQ(config.r0_spread_fraction, 0.01);
  EXPECT_EQ(config.sensitivity_spread_fraction, 0.02);
  EXPECT_EQ(config.noise_ohm, 0.5);
  EXPECT_EQ(config.adc_bits, 16);
  EXPECT_EQ(config.adc_full_scale_ohm, 9000);
  EXPECT_EQ(config.temperature_coefficient_per_k, 2.0e-3);
  EXPECT_EQ(config.temperature_offset_k, 1.5);
  EXPECT_EQ(config.temperature_ramp_k_per_s, 0.01);
  EXPECT_EQ(config.saturation_force_n, 11);
  EXPECT_EQ(config.cross_talk_shear_fraction, 0.05);
  EXPECT_EQ(config.cross_talk_offset_per_mm, 0.1);
  EXPECT_EQ(config.dead_units, (std::vector<int>{1, 2}));
  EXPECT_EQ(config.shorted_units, (std::vector<int>{7}));
  EXPECT_NO_THROW(config.Validate());
  // Empty section: paper defaults, everything off.
  const StrainModelConfig defaults = LoadStrainModelConfig(common::YamlMap::LoadString("{}", "d.yaml"));
  EXPECT_EQ(defaults.nominal.r0_ohm, 3400);
  EXPECT_EQ(defaults.noise_ohm, 0);
  EXPECT_TRUE(defaults.dead_units.empty());
}

TEST(StrainModelConfigTest, BadInputNamesFileLineAndKey) {
  TempDir dir;
  const auto error = [&](const std::string& text) {
    const std::string path = dir.Write("s.yaml", text);
    return ErrorOf([&] { LoadStrainModelConfig(common::YamlMap::LoadFile(path), 20); });
  };
  const std::string file = dir.Path("s.yaml");
  EXPECT_EQ(error("noise_ohm: 1\nr0_ohm: -3400\n"), file + ":2: r0_ohm = -3400: must be > 0");
  EXPECT_THAT(error("noise_ohm: 1\nnoise_ohms: 2\n"), HasSubstr(file + ":2: noise_ohms: unknown key"));
  EXPECT_EQ(error("dead_units: [3, 20]\n"), file + ":1: dead_units[1] = 20: must be <= 19");
  EXPECT_THAT(error("dead_units: [3]\nshorted_units: [3]\n"),
              HasSubstr(file + ":2: shorted_units = [...]: unit 3 is also in dead_units"));
  EXPECT_EQ(error("adc_bits: 12.5\n"), file + ":1: adc_bits = 12.5: expected a whole number");
  EXPECT_EQ(error("noise_ohm: lots\n"), file + ":1: noise_ohm = lots: expected a number");
  EXPECT_THAT(error("noise_ohm: [1\n"), HasSubstr(file + ":"));
  StrainModelConfig config;
  config.nominal.r0_ohm = -1;
  EXPECT_THAT(ErrorOf([&] { config.Validate(); }), HasSubstr("r0_ohm = -1: must be > 0"));
}

}  // namespace
}  // namespace graspbed::sensor
