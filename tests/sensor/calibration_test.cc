#include "sensor/calibration.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "sensor/inversion.h"
#include "sensor/readout.h"
#include "sensor/strain_model.h"
#include "tests/support/error_of.h"
#include "tests/support/temp_dir.h"

namespace graspbed::sensor {
namespace {

using test_support::ErrorOf;
using test_support::TempDir;
using ::testing::HasSubstr;

TEST(CalibrationTest, SaveLoadRoundTripLeavesNoTemporaryFile) {
  TempDir dir;
  Calibration calibration = PaperCalibration(3);
  calibration.units[1] = {95.5, 5.123456789e-4, 4.0e-4, 0.125, -0.0625};
  const std::string path = dir.Path("cal.yaml");
  SaveCalibration(calibration, path);
  const Calibration loaded = LoadCalibration(path, 3);
  ASSERT_EQ(loaded.unit_count(), 3);
  EXPECT_EQ(loaded.units[1].gauge_factor, 95.5);
  EXPECT_EQ(loaded.units[1].kn_per_n, 5.123456789e-4);
  EXPECT_EQ(loaded.units[1].kt_per_n, 4.0e-4);
  EXPECT_EQ(loaded.units[1].fn_offset_n, 0.125);
  EXPECT_EQ(loaded.units[1].ft_offset_n, -0.0625);
  EXPECT_EQ(loaded.units[0].kn_per_n, 5.5e-4);
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "cal.yaml");
  }
  EXPECT_EQ(files, 1);
  EXPECT_THAT(ErrorOf([&] { SaveCalibration(calibration, "/nonexistent/dir/cal.yaml"); }),
              HasSubstr("/nonexistent/dir/cal.yaml: cannot write calibration"));
}

TEST(CalibrationTest, BadFilesNameFileLineAndKey) {
  TempDir dir;
  const auto error = [&](const std::string& text, int units = 2) {
    const std::string path = dir.Write("c.yaml", text);
    return ErrorOf([&] { LoadCalibration(path, units); });
  };
  const std::string file = dir.Path("c.yaml");
  const std::string unit = "  - {gauge_factor: 100, kn_per_n: 5.5e-4, kt_per_n: 4.1e-4}\n";
  EXPECT_NO_THROW(error("units:\n" + unit + unit));
  EXPECT_EQ(error("units:\n" + unit + unit, 20),
            file + ":2: units = [...]: file has 2 units, the layout has 20");
  EXPECT_EQ(error("units:\n" + unit + "  - {gauge_factor: 100, kt_per_n: 4.1e-4}\n"),
            file + ":3: units[1].kn_per_n = null: missing required key");
  EXPECT_EQ(error("units:\n" + unit + "  - {gauge_factor: 100, kn_per_n: -5.5e-4, kt_per_n: 4.1e-4}\n"),
            file + ":3: units[1].kn_per_n = -5.5e-4: must be > 0");
  EXPECT_THAT(error("units:\n" + unit +
                    "  - {gauge_factor: 100, kn_per_n: 5.5e-4, kt_per_n: 4.1e-4, kt_ofset_n: 1}\n"),
              HasSubstr(file + ":3: units[1].kt_ofset_n: unknown key"));
  EXPECT_THAT(error("units:\n  - {gauge_factor: 100\n"), HasSubstr(file + ":"));
  EXPECT_THAT(error("unit:\n" + unit), HasSubstr("units = null: missing required list"));
}

// Builds a log from the real pipeline: a strain model with per-unit sensitivity spread, zero
// offsets via a bias, noise, then the readout; then checks the fit recovers the truth.
TEST(CalibrationTest, FitRecoversKnownSensitivitiesAndOffsetsFromNoisyData) {
  const Layout layout = LoadLayout(DefaultLayoutPath());
  StrainModelConfig config;
  config.sensitivity_spread_fraction = 0.1;
  config.noise_ohm = 1.0;  // about 0.02 N of noise per reading
  StrainModel model(layout, config, 99);
  Readout readout(ReadoutConfig{}, 20, 3400);
  readout.SetBaseline(model.r0_ohm_r1(), model.r0_ohm_r2());
  // A preload bias after the tare, as a zero offset the fit must find: +20 Ohm on both channels of
  // every unit is Fn_offset = 20/3400 / (G kn) per unit.
  for (int u = 0; u < 20; ++u) model.SetBiasOhm(u, 20.0, 20.0);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> fn_dist(0.0, 10.0), ft_dist(-10.0, 10.0);
  std::vector<CalibrationSample> samples;
  RawFrame frame;
  ReadoutFrame out;
  for (int i = 0; i < 200; ++i) {
    std::vector<UnitLoad> loads(20);
    for (auto& load : loads) load = {fn_dist(rng), ft_dist(rng), 0, 0};
    model.Sample(loads, i * 1e-3, &frame);
    readout.Process(frame, &out);
    for (int u = 0; u < 20; ++u)
      samples.push_back({u, loads[u].fn_n, loads[u].ft_n, out.dr1_rel[u], out.dr2_rel[u], 0});
  }
  const CalibrationFit fit = FitCalibration(samples, 20);
  constexpr double kSensitivityRelTol = 2e-3;
  constexpr double kOffsetTolN = 0.01;
  for (int u = 0; u < 20; ++u) {
    const UnitCalibration& c = fit.calibration.units[u];
    EXPECT_NEAR(c.kn_per_n / model.kn_per_n()[u], 1.0, kSensitivityRelTol) << "unit " << u;
    EXPECT_NEAR(c.kt_per_n / model.kt_per_n()[u], 1.0, kSensitivityRelTol) << "unit " << u;
    // Bias b on both channels: dR/R = b / R0 each, so s = b / R0 -> offset = s / (G kn).
    const double expected_fn_offset =
        0.5 * (20.0 / model.r0_ohm_r1()[u] + 20.0 / model.r0_ohm_r2()[u]) / (100 * model.kn_per_n()[u]);
    EXPECT_NEAR(c.fn_offset_n, expected_fn_offset, kOffsetTolN);
    EXPECT_NEAR(
        c.ft_offset_n,
        0.5 * (20.0 / model.r0_ohm_r1()[u] - 20.0 / model.r0_ohm_r2()[u]) / (100 * model.kt_per_n()[u]),
        kOffsetTolN);
    EXPECT_LT(fit.reports[u].rms_fn_residual_n, 0.05);
    EXPECT_LT(std::abs(fit.reports[u].fn_from_ft_coupling), 0.01);
  }
  // The spread is large enough that the paper's constants would be visibly wrong.
  int off = 0;
  for (int u = 0; u < 20; ++u) off += std::abs(model.kn_per_n()[u] / 5.5e-4 - 1) > 0.02;
  EXPECT_GT(off, 5);
  // With the fitted calibration the inversion reads the true load.
  const Inversion inversion(layout, fit.calibration, InversionConfig{});
  model.SetNoiseScale(0.0);
  std::vector<UnitLoad> loads(20, UnitLoad{6.0, -4.0, 0, 0});
  model.Sample(loads, 1.0, &frame);
  readout.Process(frame, &out);
  TactileState state;
  inversion.Invert(out, &state);
  for (int u = 0; u < 20; ++u) {
    EXPECT_NEAR(state.fn_n[u], 6.0, 0.03);
    EXPECT_NEAR(state.ft_n[u], -4.0, 0.03);
  }
}

TEST(CalibrationTest, FitReportsCrossCoupling) {
  std::vector<CalibrationSample> samples;
  for (double fn : {0.0, 5.0, 10.0}) {
    for (double ft : {-5.0, 0.0, 5.0}) {
      // 2% of Ft leaks into the mean (normal) channel.
      const double s = 100 * 5.5e-4 * (fn + 0.02 * ft);
      const double d = 100 * 4.1e-4 * ft;
      samples.push_back({0, fn, ft, s + d, s - d, 0});
    }
  }
  const CalibrationFit fit = FitCalibration(samples, 1);
  EXPECT_NEAR(fit.calibration.units[0].kn_per_n, 5.5e-4, 1e-12);
  EXPECT_NEAR(fit.reports[0].fn_from_ft_coupling, 0.02, 1e-9);
  EXPECT_NEAR(fit.reports[0].ft_from_fn_coupling, 0.0, 1e-9);
  // Fn never varied independently of Ft: the fit refuses.
  std::vector<CalibrationSample> degenerate = {
      {0, 1, 1, 0.1, 0.0, 0}, {0, 2, 2, 0.2, 0.0, 0}, {0, 3, 3, 0.3, 0.0, 0}};
  EXPECT_THAT(ErrorOf([&] { FitCalibration(degenerate, 1); }),
              HasSubstr("unit 0 has 3 samples without independent"));
  EXPECT_THAT(ErrorOf([&] { FitCalibration(samples, 2); }), HasSubstr("unit 1 has 0 samples"));
}

TEST(CalibrationLogTest, ReadsRelativeAndOhmColumns) {
  TempDir dir;
  const std::string relative =
      dir.Write("rel.csv", "# bench log\nunit,fn_n,ft_n,dr1_rel,dr2_rel\n0,0,0,0,0\n0,10,10,0.96,0.14\n");
  const std::vector<CalibrationSample> a = LoadCalibrationLog(relative, 1);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[1].line, 4);
  EXPECT_EQ(a[1].dr1_rel, 0.96);
  // Resistances, in any column order, referred to the zero-load rows (mean 3400).
  const std::string ohm = dir.Write("ohm.csv",
                                    "r1_ohm, r2_ohm, unit, fn_n, ft_n\n3399,3401,0,0,0\n3401,3399,0,0,0\n"
                                    "6664,3876,0,10,10\n");
  const std::vector<CalibrationSample> b = LoadCalibrationLog(ohm, 1);
  ASSERT_EQ(b.size(), 3u);
  EXPECT_NEAR(b[2].dr1_rel, 0.96, 1e-12);
  EXPECT_NEAR(b[2].dr2_rel, 0.14, 1e-12);
}

TEST(CalibrationLogTest, BadLogsNameFileLineAndColumn) {
  TempDir dir;
  const auto error = [&](const std::string& text) {
    const std::string path = dir.Write("log.csv", text);
    return ErrorOf([&] { LoadCalibrationLog(path, 2); });
  };
  const std::string file = dir.Path("log.csv");
  EXPECT_EQ(error("unit,fn_n,ft_n,dr1_rel,dr2_rel\n0,1,x,0.1,0.1\n"),
            file + ":2: ft_n = x: expected a number");
  EXPECT_EQ(error("unit,fn_n,ft_n,dr1_rel,dr2_rel\n0,1,1,0.1\n"), file + ":2: expected 5 columns, got 4");
  EXPECT_EQ(error("unit,fn_n,ft_n,dr1_rel,dr2_rel\n2,1,1,0.1,0.1\n"),
            file + ":2: unit = 2: must be a unit index 0..1");
  EXPECT_THAT(error("unit,fn_n,ft_n,dr1_rel,dr2_rl\n"),
              HasSubstr(file + ":1: header column 'dr2_rl': unknown column"));
  EXPECT_THAT(error("unit,fn_n,dr1_rel,dr2_rel\n"), HasSubstr(file + ":1: header: missing column 'ft_n'"));
  EXPECT_EQ(error("unit,fn_n,ft_n,r1_ohm,r2_ohm\n0,0,0,3400,3400\n1,5,0,-3,3400\n"),
            file + ":3: r1_ohm = -3: must be > 0");
  EXPECT_EQ(error("unit,fn_n,ft_n,r1_ohm,r2_ohm\n0,0,0,3400,3400\n1,5,0,3500,3400\n"),
            file + ":3: unit = 1: no zero-load row (fn_n = ft_n = 0) to refer r1_ohm, r2_ohm to");
  EXPECT_EQ(error("unit,fn_n,ft_n,dr1_rel,dr2_rel\n0,nan,1,0.1,0.1\n"),
            file + ":2: fn_n = nan: must be finite");
  EXPECT_THAT(ErrorOf([] { LoadCalibrationLog("/nonexistent/log.csv", 2); }), HasSubstr("cannot open file"));
}

}  // namespace
}  // namespace graspbed::sensor
