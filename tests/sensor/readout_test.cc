#include "sensor/readout.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <cmath>
#include <string>
#include <vector>

#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/layout.h"
#include "sensor/strain_model.h"
#include "tests/support/error_of.h"
#include "tests/support/temp_dir.h"

namespace graspbed::sensor {
namespace {

using test_support::ErrorOf;
using test_support::TempDir;
using ::testing::HasSubstr;

constexpr double kRelTol = 1e-12;
constexpr int kUnits = 4;

RawFrame Frame(double r1, double r2, uint32_t sequence = 0) {
  RawFrame frame;
  frame.sequence = sequence;
  frame.time_s = sequence * 1e-3;
  frame.unit_count = kUnits;
  for (int u = 0; u < kUnits; ++u) {
    frame.r1_ohm[u] = r1;
    frame.r2_ohm[u] = r2;
  }
  return frame;
}

TEST(ReadoutTest, TaresByAveragingTheFirstFrames) {
  ReadoutConfig config;
  config.baseline_frames = 10;
  Readout readout(config, kUnits, 3400);
  ReadoutFrame out;
  EXPECT_FALSE(readout.tared());
  // Baseline alternates 3390 / 3410: mean 3400 for R1; R2 constant 3300.
  for (int i = 0; i < 10; ++i) {
    RawFrame frame = Frame(i % 2 == 0 ? 3390 : 3410, 3300, static_cast<uint32_t>(i));
    frame.r1_ohm[0] = 3500;
    readout.Process(frame, &out);
    EXPECT_EQ(out.validity[1], UnitValidity::kNotTared);
    EXPECT_EQ(out.dr1_rel[1], 0.0);
    EXPECT_EQ(out.sequence, static_cast<uint32_t>(i));
  }
  EXPECT_TRUE(readout.tared());
  EXPECT_NEAR(readout.baseline_r1_ohm()[1], 3400, 1e-9);
  EXPECT_NEAR(readout.baseline_r1_ohm()[0], 3500, 1e-9);
  readout.Process(Frame(3400 * 1.5, 3300 * 0.9, 10), &out);
  EXPECT_EQ(out.validity[1], UnitValidity::kValid);
  EXPECT_NEAR(out.dr1_rel[1], 0.5, kRelTol);
  EXPECT_NEAR(out.dr2_rel[1], -0.1, kRelTol);
  EXPECT_NEAR(out.dr1_rel[0], 3400 * 1.5 / 3500 - 1, kRelTol);
  EXPECT_EQ(out.sequence, 10u);
  EXPECT_DOUBLE_EQ(out.time_s, 0.01);
  // Reset starts a new tare window.
  readout.Reset();
  EXPECT_FALSE(readout.tared());
  readout.Process(Frame(3400, 3400), &out);
  EXPECT_EQ(out.validity[1], UnitValidity::kNotTared);
  EXPECT_EQ(readout.baseline_frames_seen(), 1);
}

TEST(ReadoutTest, StoredBaselineTaresAtOnce) {
  Readout readout(ReadoutConfig{}, kUnits, 3400);
  const std::vector<double> r1 = {3400, 3410, 3390, 3405};
  const std::vector<double> r2 = {3400, 3395, 3402, 3398};
  readout.SetBaseline(r1, r2);
  EXPECT_TRUE(readout.tared());
  ReadoutFrame out;
  readout.Process(Frame(3410, 3410), &out);
  EXPECT_EQ(out.validity[1], UnitValidity::kValid);
  EXPECT_NEAR(out.dr1_rel[1], 0.0, kRelTol);
  EXPECT_NEAR(out.dr2_rel[1], 3410.0 / 3395 - 1, kRelTol);
  EXPECT_THAT(ErrorOf([&] { readout.SetBaseline(std::vector<double>(3, 3400), r2); }),
              HasSubstr("baseline has 3/4 values for 4 units"));
  EXPECT_THAT(ErrorOf([&] {
                readout.SetBaseline(std::vector<double>{3400, -1, 3400, 3400}, r2);
              }),
              HasSubstr("baseline r1_ohm = -1: must be finite and > 0"));
}

class ReadoutValidityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    readout_.SetBaseline(std::vector<double>(kUnits, 3400), std::vector<double>(kUnits, 3400));
  }
  UnitValidity Validity(double r1, double r2) {
    RawFrame frame = Frame(3400, 3400);
    frame.r1_ohm[2] = r1;
    frame.r2_ohm[2] = r2;
    readout_.Process(frame, &out_);
    EXPECT_EQ(out_.validity[0], UnitValidity::kValid);
    return out_.validity[2];
  }
  ReadoutConfig config_{};
  Readout readout_{config_, kUnits, 3400};
  ReadoutFrame out_;
};

TEST_F(ReadoutValidityTest, OpenShortImplausibleOutOfRange) {
  EXPECT_EQ(Validity(5270, 5270), UnitValidity::kValid);
  EXPECT_EQ(Validity(kOpenCircuitOhm, 3400), UnitValidity::kOpen);
  EXPECT_EQ(Validity(3400, 2e6), UnitValidity::kOpen);
  EXPECT_EQ(Validity(kShortCircuitOhm, 3400), UnitValidity::kShort);
  EXPECT_EQ(Validity(3400, 0.5), UnitValidity::kShort);
  EXPECT_EQ(Validity(kShortCircuitOhm, kOpenCircuitOhm), UnitValidity::kOpen);
  EXPECT_EQ(Validity(100, 3400), UnitValidity::kImplausible);    // far below any strain
  EXPECT_EQ(Validity(20000, 3400), UnitValidity::kImplausible);  // > 3 R0
  EXPECT_EQ(Validity(std::nan(""), 3400), UnitValidity::kImplausible);
  EXPECT_EQ(Validity(3400 * 0.75, 3400 * 0.75), UnitValidity::kImplausible);  // pulled: mean dR/R -0.25
  EXPECT_EQ(Validity(3400 * 2.6, 3400), UnitValidity::kOutOfRange);           // dR/R 1.6 > 1.5
  EXPECT_NEAR(out_.dr1_rel[2], 1.6, kRelTol);
  // Frame for another unit count: every unit implausible.
  RawFrame wrong = Frame(3400, 3400);
  wrong.unit_count = 3;
  readout_.Process(wrong, &out_);
  EXPECT_EQ(out_.validity[0], UnitValidity::kImplausible);
  EXPECT_EQ(out_.unit_count, kUnits);
}

TEST(ReadoutTest, AdcFullScaleAndBadBaselines) {
  ReadoutConfig config;
  config.adc_full_scale_ohm = 8000;
  config.baseline_frames = 4;
  Readout readout(config, kUnits, 3400);
  ReadoutFrame out;
  for (int i = 0; i < 4; ++i) {
    RawFrame frame = Frame(3400, 3400);
    frame.r1_ohm[1] = kOpenCircuitOhm;  // open through the whole tare window
    frame.r1_ohm[2] = 4600;             // baseline 35% above nominal
    readout.Process(frame, &out);
    EXPECT_EQ(out.validity[1], UnitValidity::kOpen);
    EXPECT_EQ(out.validity[0], UnitValidity::kNotTared);
  }
  RawFrame frame = Frame(3400, 3400);
  frame.r1_ohm[3] = 8000;
  frame.r1_ohm[2] = 4600;
  readout.Process(frame, &out);
  EXPECT_EQ(out.validity[0], UnitValidity::kValid);
  EXPECT_EQ(out.validity[1], UnitValidity::kImplausible);  // recovered, but never tared
  EXPECT_EQ(out.validity[2], UnitValidity::kImplausible);  // bad tare
  EXPECT_EQ(out.validity[3], UnitValidity::kOutOfRange);   // ADC at full scale
}

TEST(ReadoutConfigTest, LoadsAndRejectsBadInput) {
  TempDir dir;
  const std::string good =
      dir.Write("r.yaml", "baseline_frames: 50\nadc_full_scale_ohm: 9000\nmax_abs_dr_rel: 1.2\n");
  const ReadoutConfig config = LoadReadoutConfig(common::YamlMap::LoadFile(good));
  EXPECT_EQ(config.baseline_frames, 50);
  EXPECT_EQ(config.adc_full_scale_ohm, 9000);
  EXPECT_EQ(config.max_abs_dr_rel, 1.2);
  const std::string bad = dir.Write("b.yaml", "baseline_frames: 50\nbaseline_frame: 0\n");
  EXPECT_THAT(ErrorOf([&] { LoadReadoutConfig(common::YamlMap::LoadFile(bad)); }),
              HasSubstr(dir.Path("b.yaml") + ":2: baseline_frame: unknown key"));
  const std::string zero = dir.Write("z.yaml", "baseline_frames: 0\n");
  EXPECT_EQ(ErrorOf([&] { LoadReadoutConfig(common::YamlMap::LoadFile(zero)); }),
            dir.Path("z.yaml") + ":1: baseline_frames = 0: must be >= 1");
  EXPECT_THAT(ErrorOf([] { Readout readout(ReadoutConfig{}, 0, 3400); }),
              HasSubstr("unit count 0 outside 1..64"));
  EXPECT_THAT(ErrorOf([] { Readout readout(ReadoutConfig{}, 4, -3400); }),
              HasSubstr("nominal_r0_ohm = -3400: must be finite and > 0"));
}

// The loader and Validate() once held min_plausible_fraction and min_mean_dr_rel to different
// bounds (0.999 vs < 1, -1e-9 vs < 0); one field table now gives both the same rule and message.
TEST(ReadoutConfigTest, LoadingAndValidatingApplyTheSameRules) {
  TempDir dir;
  const auto load_error = [&](const std::string& text) {
    const std::string path = dir.Write("r.yaml", text);
    return ErrorOf([&] { LoadReadoutConfig(common::YamlMap::LoadFile(path)); });
  };
  ReadoutConfig config;
  config.min_plausible_fraction = 0.9995;
  EXPECT_EQ(ErrorOf([&] { config.Validate(); }), "readout.min_plausible_fraction = 0.9995: must be <= 0.999");
  EXPECT_EQ(load_error("min_plausible_fraction: 0.9995\n"),
            dir.Path("r.yaml") + ":1: min_plausible_fraction = 0.9995: must be <= 0.999");
  config = ReadoutConfig{};
  config.min_mean_dr_rel = 0.0;
  EXPECT_EQ(ErrorOf([&] { config.Validate(); }), "readout.min_mean_dr_rel = 0: must be <= -1e-09");
  EXPECT_EQ(load_error("min_mean_dr_rel: 0\n"),
            dir.Path("r.yaml") + ":1: min_mean_dr_rel = 0: must be <= -1e-09");
  // A cross-field rule: at the blamed key's line when the file sets it, else as a default.
  config = ReadoutConfig{};
  config.open_circuit_ohm = 0.5;
  EXPECT_EQ(ErrorOf([&] { config.Validate(); }),
            "readout.open_circuit_ohm = 0.5: must be > short_circuit_ohm");
  EXPECT_EQ(load_error("short_circuit_ohm: 10\nopen_circuit_ohm: 5\n"),
            dir.Path("r.yaml") + ":2: open_circuit_ohm = 5: must be > short_circuit_ohm");
  EXPECT_EQ(load_error("short_circuit_ohm: 2e6\n"),
            dir.Path("r.yaml") + ":1: short_circuit_ohm = 2e6: must be <= 1e+06");
}

TEST(ReadoutConfigTest, EmittedConfigLoadsBackTheSame) {
  ReadoutConfig config;
  config.baseline_frames = 37;
  config.min_plausible_fraction = 0.123456789;
  config.adc_full_scale_ohm = 6000;
  config.adc_min_ohm = 1500;
  TempDir dir;
  const std::string path = dir.Write("r.yaml", ReadoutConfigFields().EmitYaml(config));
  const ReadoutConfig again = LoadReadoutConfig(common::YamlMap::LoadFile(path));
  EXPECT_EQ(again.baseline_frames, 37);
  EXPECT_EQ(again.min_plausible_fraction, 0.123456789);
  EXPECT_EQ(again.adc_min_ohm, 1500);
  EXPECT_EQ(ReadoutConfigFields().EmitYaml(again), ReadoutConfigFields().EmitYaml(config));
}

// The readout's noise estimate (TactileState::r1_noise_ohm .. ft_noise_n) against noise injected by
// the strain model: within 10 %, from the default 100-frame tare (median over the 40 channels) and
// from a 1000-frame tare (every channel).
constexpr double kNoiseEstimateRelTol = 0.10;

struct NoiseRun {
  std::vector<double> r_noise_ohm, fn_noise_n, ft_noise_n;
  bool known = false;
};

NoiseRun EstimateNoise(const StrainModelConfig& model_config, int baseline_frames) {
  const Layout layout = LoadLayout(std::string(GRASPBED_SOURCE_DIR) + "/sensor/layouts/default_20.yaml");
  const int units = layout.unit_count();
  StrainModel model(layout, model_config, 11);
  ReadoutConfig config;
  config.baseline_frames = baseline_frames;
  Readout readout(config, units, model_config.nominal.r0_ohm);
  const Inversion inversion(layout, NominalCalibration(model_config.nominal, units), InversionConfig{});
  const std::vector<UnitLoad> loads(static_cast<size_t>(units));
  RawFrame raw;
  ReadoutFrame frame;
  TactileState state;
  for (int i = 0; i <= baseline_frames; ++i) {
    model.Sample(loads, i * 1e-3, &raw);
    readout.Process(raw, &frame);
    inversion.Invert(frame, &state);
  }
  NoiseRun run;
  run.known = state.noise_known;
  for (int u = 0; u < units; ++u) {
    run.r_noise_ohm.push_back(state.r1_noise_ohm[u]);
    run.r_noise_ohm.push_back(state.r2_noise_ohm[u]);
    run.fn_noise_n.push_back(state.fn_noise_n[u]);
    run.ft_noise_n.push_back(state.ft_noise_n[u]);
  }
  return run;
}

double MedianOf(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

TEST(ReadoutNoiseTest, EstimateMatchesTheInjectedNoise) {
  StrainModelConfig model_config;
  model_config.noise_ohm = 0.5;
  // Uncorrelated channels: std(Fn) = noise / R0 / sqrt(2) / (G kn), std(Ft) likewise with kt.
  const double fn_expected = 0.5 / 3400 / std::sqrt(2.0) / (100 * 5.5e-4);
  const double ft_expected = 0.5 / 3400 / std::sqrt(2.0) / (100 * 4.1e-4);
  const NoiseRun short_tare = EstimateNoise(model_config, 100);
  EXPECT_TRUE(short_tare.known);
  EXPECT_NEAR(MedianOf(short_tare.r_noise_ohm), 0.5, kNoiseEstimateRelTol * 0.5);
  EXPECT_NEAR(MedianOf(short_tare.fn_noise_n), fn_expected, kNoiseEstimateRelTol * fn_expected);
  EXPECT_NEAR(MedianOf(short_tare.ft_noise_n), ft_expected, kNoiseEstimateRelTol * ft_expected);
  const NoiseRun long_tare = EstimateNoise(model_config, 1000);
  for (double value : long_tare.r_noise_ohm) EXPECT_NEAR(value, 0.5, kNoiseEstimateRelTol * 0.5);
  for (double value : long_tare.fn_noise_n)
    EXPECT_NEAR(value, fn_expected, kNoiseEstimateRelTol * fn_expected);
  for (double value : long_tare.ft_noise_n)
    EXPECT_NEAR(value, ft_expected, kNoiseEstimateRelTol * ft_expected);
  std::printf(
      "noise estimate, 0.5 Ohm injected: 100-frame tare median %.4f Ohm (Fn %.3f mN, Ft %.3f mN; "
      "expected %.3f, %.3f); 1000-frame tare range %.4f .. %.4f Ohm\n",
      MedianOf(short_tare.r_noise_ohm), 1e3 * MedianOf(short_tare.fn_noise_n),
      1e3 * MedianOf(short_tare.ft_noise_n), 1e3 * fn_expected, 1e3 * ft_expected,
      *std::min_element(long_tare.r_noise_ohm.begin(), long_tare.r_noise_ohm.end()),
      *std::max_element(long_tare.r_noise_ohm.begin(), long_tare.r_noise_ohm.end()));
}

TEST(ReadoutNoiseTest, DriftDuringTheTareIsNotNoise) {
  StrainModelConfig model_config;
  model_config.noise_ohm = 0.1;
  // 1.5e-3 /K x 2 K/s: R0 drifts 10 Ohm/s, 1 Ohm over the tare, ten times the noise.
  model_config.temperature_coefficient_per_k = 1.5e-3;
  model_config.temperature_ramp_k_per_s = 2.0;
  const NoiseRun run = EstimateNoise(model_config, 100);
  EXPECT_NEAR(MedianOf(run.r_noise_ohm), 0.1, kNoiseEstimateRelTol * 0.1);
}

TEST(ReadoutNoiseTest, CorrelatedNoiseCountsInFnNotFt) {
  // A common-mode disturbance on both channels (same draw) is all Fn: check the covariance term by
  // feeding frames directly.
  ReadoutConfig config;
  config.baseline_frames = 2000;
  Readout readout(config, kUnits, 3400);
  ReadoutFrame out;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < config.baseline_frames; ++i) {
    const double common = 0.5 * normal(rng);
    readout.Process(Frame(3400 + common, 3400 + common, static_cast<uint32_t>(i)), &out);
  }
  ASSERT_TRUE(readout.noise_known());
  EXPECT_NEAR(readout.sum_noise_rel()[0], 0.5 / 3400, kNoiseEstimateRelTol * 0.5 / 3400);
  EXPECT_LT(readout.diff_noise_rel()[0], 1e-9);
}

TEST(ReadoutNoiseTest, AStoredBaselineCarriesNoNoiseFigure) {
  Readout readout(ReadoutConfig{}, kUnits, 3400);
  const std::vector<double> baseline(kUnits, 3400.0);
  readout.SetBaseline(baseline, baseline);
  ReadoutFrame out;
  readout.Process(Frame(3400, 3400), &out);
  EXPECT_FALSE(out.noise_known);
  EXPECT_EQ(out.r1_noise_ohm[0], 0.0);
}

}  // namespace
}  // namespace graspbed::sensor
