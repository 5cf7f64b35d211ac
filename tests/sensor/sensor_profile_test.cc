// Sensor profiles: what each readout chain works out to, and what the strain model then produces at
// rest, measured through the readout and the inversion (docs/sensor.md, "Sensor profiles", quotes
// the table this test prints). Also the readout's own noise estimate against the same signal.
#include "sensor/sensor_profile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/layout.h"
#include "sensor/readout.h"
#include "sensor/strain_model.h"

namespace graspbed::sensor {
namespace {

// The unit FEA's sensitivities for the shipped unit (docs/fea.md; tests/testbed/sensitivities_test
// checks the scenario loader takes them from the analysis).
constexpr double kFeaKn = 3.36e-5;
constexpr double kFeaKt = 6.31e-6;
constexpr int kRestFrames = 4000;
// The measured noise agrees with the chain's figure (noise plus quantisation) to this [-]; 4000
// samples x 40 channels put the statistical error well below it.
constexpr double kNoiseRelTol = 0.10;

Layout DefaultLayout() {
  return LoadLayout(std::string(GRASPBED_SOURCE_DIR) + "/sensor/layouts/default_20.yaml");
}

UnitConstants Constants(bool fea) {
  UnitConstants nominal;
  if (fea) {
    nominal.kn_per_n = kFeaKn;
    nominal.kt_per_n = kFeaKt;
  }
  return nominal;
}

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

// Standard deviation about the least-squares line (the temperature ramp drifts every channel).
double DetrendedStd(const std::vector<double>& values) {
  const double n = static_cast<double>(values.size());
  double k = 0, kk = 0, x = 0, xk = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    k += i;
    kk += static_cast<double>(i) * i;
    x += values[i];
    xk += values[i] * i;
  }
  const double slope = (xk - x * k / n) / (kk - k * k / n);
  const double mean = x / n, mean_k = k / n;
  double sum = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    const double residual = values[i] - mean - slope * (static_cast<double>(i) - mean_k);
    sum += residual * residual;
  }
  return std::sqrt(sum / (n - 2));
}

/// What one profile produces at rest: per-channel noise in Ohm, per-unit noise in N through the
/// inversion (median over units), and the readout's estimate of both from its tare.
struct Measured {
  double r_noise_ohm = 0;
  double fn_noise_n = 0;
  double ft_noise_n = 0;
  double estimated_r_noise_ohm = 0;
  double estimated_fn_noise_n = 0;
  double estimated_ft_noise_n = 0;
};

Measured MeasureAtRest(const StrainModelConfig& model_config, const ReadoutConfig& readout_config) {
  const Layout layout = DefaultLayout();
  const int units = layout.unit_count();
  StrainModel model(layout, model_config, 7);
  Readout readout(readout_config, units, model_config.nominal.r0_ohm);
  const Inversion inversion(layout, NominalCalibration(model_config.nominal, units), InversionConfig{});
  const std::vector<UnitLoad> loads(static_cast<size_t>(units));
  RawFrame raw;
  ReadoutFrame frame;
  TactileState state;
  std::vector<std::vector<double>> r(2 * units), fn(units), ft(units);
  for (int i = 0; i < readout_config.baseline_frames + kRestFrames; ++i) {
    model.Sample(loads, i * 1e-3, &raw);
    readout.Process(raw, &frame);
    inversion.Invert(frame, &state);
    if (i < readout_config.baseline_frames) continue;
    for (int u = 0; u < units; ++u) {
      r[2 * u].push_back(raw.r1_ohm[u]);
      r[2 * u + 1].push_back(raw.r2_ohm[u]);
      fn[u].push_back(state.fn_n[u]);
      ft[u].push_back(state.ft_n[u]);
    }
  }
  EXPECT_TRUE(state.noise_known);
  std::vector<double> r_std, fn_std, ft_std, r_est, fn_est, ft_est;
  for (const auto& channel : r) r_std.push_back(DetrendedStd(channel));
  for (int u = 0; u < units; ++u) {
    fn_std.push_back(DetrendedStd(fn[u]));
    ft_std.push_back(DetrendedStd(ft[u]));
    r_est.push_back(state.r1_noise_ohm[u]);
    r_est.push_back(state.r2_noise_ohm[u]);
    fn_est.push_back(state.fn_noise_n[u]);
    ft_est.push_back(state.ft_noise_n[u]);
  }
  return {Median(r_std), Median(fn_std), Median(ft_std), Median(r_est), Median(fn_est), Median(ft_est)};
}

TEST(SensorProfileTest, IdealIsTodaysDefault) {
  const StrainModelConfig config = ProfileStrainModel(FindSensorProfile("ideal"), UnitConstants{});
  const StrainModelConfig defaults;
  EXPECT_EQ(config.noise_ohm, defaults.noise_ohm);
  EXPECT_EQ(config.adc_bits, 0);
  EXPECT_EQ(config.r0_spread_fraction, 0.0);
  EXPECT_EQ(config.sensitivity_spread_fraction, 0.0);
  EXPECT_EQ(config.temperature_coefficient_per_k, 0.0);
  EXPECT_EQ(config.cross_talk_shear_fraction, 0.0);
  EXPECT_EQ(ProfileReadout(FindSensorProfile("ideal"), UnitConstants{}).adc_full_scale_ohm, 0.0);
  EXPECT_EQ(SensorProfileNames().front(), "ideal");
}

TEST(SensorProfileTest, UnknownNameListsTheValidOnes) {
  try {
    FindSensorProfile("realistic");
    FAIL() << "no error";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("inamp_16bit"), std::string::npos) << error.what();
  }
}

TEST(SensorProfileTest, QuarterBridgeSlopeAndJohnsonNoiseOfA3k4Gauge) {
  ReadoutChain chain;
  chain.excitation_v = 2.5;
  chain.noise_bandwidth_hz = 1.0;
  const ChainDerivation d = DeriveChain(chain, GaugeNonIdeal{}, UnitConstants{});
  // Vex / (4 R0) for a matched bridge; 4 k T R over 1 Hz for R0 = 3.4 kOhm at 300 K is 7.5 nV.
  EXPECT_NEAR(d.slope_v_per_ohm, 2.5 / (4 * 3400), 1e-12);
  EXPECT_NEAR(d.source_ohm, 3400, 1e-9);
  EXPECT_NEAR(d.johnson_uv_rms, 7.50e-3, 0.01e-3);
}

TEST(SensorProfileTest, EveryProfileProducesItsStatedNoiseForBothSensitivitySources) {
  std::printf(
      "| profile | kn, kt source | gain | ADC window [Ohm] | LSB at R0 [Ohm] | chain noise [Ohm] "
      "| measured R noise [Ohm] | Fn noise [mN] | Ft noise [mN] | tare estimate R / Fn / Ft |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  double previous_noise_ohm[2] = {1e9, 1e9};
  for (const std::string& name : SensorProfileNames()) {
    const SensorProfile& profile = FindSensorProfile(name);
    if (profile.ideal) continue;
    for (int fea = 0; fea < 2; ++fea) {
      SCOPED_TRACE(name + (fea ? " fea" : " paper"));
      const UnitConstants nominal = Constants(fea != 0);
      const ChainDerivation d = DeriveChain(profile.chain, profile.gauge, nominal);
      const StrainModelConfig model_config = ProfileStrainModel(profile, nominal);
      ReadoutConfig readout_config = ProfileReadout(profile, nominal);
      readout_config.baseline_frames = 1000;
      const Measured m = MeasureAtRest(model_config, readout_config);

      // The window holds the whole range the chain was designed for.
      EXPECT_LE(d.window_low_ohm, d.range_low_ohm);
      EXPECT_GE(d.window_high_ohm, std::min(d.range_high_ohm, 4 * nominal.r0_ohm));
      // What the strain model produces is the chain's noise plus the model ADC's quantisation
      // (uniform: step^2 / 12; a step well above the noise makes that approximate, so only when
      // the noise dithers it).
      const double step_ohm = (model_config.adc_full_scale_ohm - model_config.adc_min_ohm) /
                              (std::ldexp(1.0, model_config.adc_bits) - 1);
      const double expected_ohm = std::sqrt(d.noise_ohm * d.noise_ohm + step_ohm * step_ohm / 12);
      if (d.noise_ohm > 0.5 * step_ohm) {
        EXPECT_NEAR(m.r_noise_ohm, expected_ohm, kNoiseRelTol * expected_ohm);
      }
      // Eq. 4 with uncorrelated channels: std(Fn) = std(R) / R0 / sqrt(2) / (G kn).
      const double per_ohm = 1.0 / nominal.r0_ohm / std::sqrt(2.0) / nominal.gauge_factor;
      EXPECT_NEAR(m.fn_noise_n, m.r_noise_ohm * per_ohm / nominal.kn_per_n, kNoiseRelTol * m.fn_noise_n);
      EXPECT_NEAR(m.ft_noise_n, m.r_noise_ohm * per_ohm / nominal.kt_per_n, kNoiseRelTol * m.ft_noise_n);
      // The readout's estimate from its 1000-frame tare (2.2 % standard error per channel).
      EXPECT_NEAR(m.estimated_r_noise_ohm, m.r_noise_ohm, kNoiseRelTol * m.r_noise_ohm);
      EXPECT_NEAR(m.estimated_fn_noise_n, m.fn_noise_n, kNoiseRelTol * m.fn_noise_n);
      EXPECT_NEAR(m.estimated_ft_noise_n, m.ft_noise_n, kNoiseRelTol * m.ft_noise_n);
      // Better parts, less noise.
      EXPECT_LT(d.noise_ohm, previous_noise_ohm[fea]);
      previous_noise_ohm[fea] = d.noise_ohm;
      std::printf(
          "| %s | %s | %g | %.1f .. %.1f | %.3g | %.3g | %.3g | %.3g | %.3g | %.3g Ohm / %.3g / %.3g mN |\n",
          name.c_str(), fea ? "fea" : "paper", d.gain, d.window_low_ohm, d.window_high_ohm, d.lsb_at_r0_ohm,
          d.noise_ohm, m.r_noise_ohm, 1e3 * m.fn_noise_n, 1e3 * m.ft_noise_n, m.estimated_r_noise_ohm,
          1e3 * m.estimated_fn_noise_n, 1e3 * m.estimated_ft_noise_n);
    }
  }
}

TEST(SensorProfileTest, ChainNoiseBudgetPrinted) {
  // The parts of each chain's noise, referred to the gauge input (docs/sensor.md quotes these).
  std::printf(
      "| profile | kn, kt source | source R [Ohm] | Johnson [uV] | amplifier [uV] | ADC [uV] "
      "| slope [uV/Ohm] | range needed [Ohm] |\n|---|---|---|---|---|---|---|---|\n");
  for (const std::string& name : SensorProfileNames()) {
    const SensorProfile& profile = FindSensorProfile(name);
    if (profile.ideal) continue;
    for (int fea = 0; fea < 2; ++fea) {
      const ChainDerivation d = DeriveChain(profile.chain, profile.gauge, Constants(fea != 0));
      std::printf("| %s | %s | %.0f | %.3g | %.3g | %.3g | %.1f | %.0f .. %.0f |\n", name.c_str(),
                  fea ? "fea" : "paper", d.source_ohm, d.johnson_uv_rms, d.amplifier_uv_rms, d.adc_uv_rms,
                  1e6 * d.slope_v_per_ohm, d.range_low_ohm, d.range_high_ohm);
      EXPECT_GT(d.noise_ohm, 0.0);
    }
  }
}

}  // namespace
}  // namespace graspbed::sensor
