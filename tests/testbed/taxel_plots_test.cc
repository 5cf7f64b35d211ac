// The run's taxel pictures: taxels_fn.png and taxels_ft.png, units x time colour maps of the estimated
// Fn and Ft, written beside the other plots at their fixed size, with a loaded unit's row coloured
// where an unloaded unit's row stays white. The PNGs are read back with image::ReadPng.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>

#include "common/plot.h"
#include "common/rgb_image.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "tests/support/temp_dir.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed::testbed {
namespace {

using graspbed::test_support::TempDir;
using test_support::HeldBoxScenario;
using test_support::kHeldInAirS;
using test_support::Signals;

constexpr int kTaxelWidthPx = 1000;  // plot::Heatmap defaults, used by the runner
constexpr int kTaxelHeightPx = 600;
constexpr int kUnits = 20;        // default_20 layout
constexpr double kLoadedN = 1.0;  // clearly loaded
constexpr int kWhiteTol = 8;      // an unloaded cell is white within this, per channel [0..255]
// The runner's floor of the maps' colour scale (run_outputs.cc): the shear map spans +-max(this, |Ft|).
constexpr double kTaxelScaleFloorN = 0.5;
// A shear of at least this share of the map's largest |Ft| is drawn clearly red or blue.
constexpr double kColouredShareOfScale = 0.3;

// {r, g, b} at pixel (x, y), 0..255.
std::array<int, 3> At(const image::RgbImage& picture, double x, double y) {
  const uint8_t* p = picture.At(static_cast<int>(x), static_cast<int>(y));
  return {p[0], p[1], p[2]};
}

bool IsWhite(const std::array<int, 3>& rgb) {
  return rgb[0] >= 255 - kWhiteTol && rgb[1] >= 255 - kWhiteTol && rgb[2] >= 255 - kWhiteTol;
}

TEST(TaxelPlotsTest, RunWritesFnAndFtMapsWhereALoadedUnitsRowDiffersFromAnUnloadedOne) {
  const TempDir dir("taxel_plots_test");
  const ScenarioConfig config = LoadScenario(dir.Write("held.yaml", HeldBoxScenario(0.6)));
  RunOptions options;
  options.out_dir = dir.Path("out");
  const RunResult result = RunScenario(config, options);
  ASSERT_TRUE(result.completed);
  const Signals signals(options.out_dir + "/signals.csv");

  // A unit loaded in the hold and one that never is (estimate and truth agree on the ideal sensor).
  int loaded = -1;
  int unloaded = -1;
  for (int u = 0; u < kUnits; ++u) {
    const std::string index = std::to_string(u);
    if (loaded < 0 && signals.AtTime("fn_est_n_" + index, kHeldInAirS) > kLoadedN) loaded = u;
    const std::vector<double>& fn = signals.Column("fn_true_n_" + index);
    if (unloaded < 0 && *std::max_element(fn.begin(), fn.end()) == 0.0) unloaded = u;
  }
  ASSERT_GE(loaded, 0);
  ASSERT_GE(unloaded, 0);

  // The cell geometry of the runner's maps: same size, same time range, one row per unit.
  plot::Heatmap geometry;
  geometry.x = {signals.At("time_s", 0), signals.At("time_s", signals.rows() - 1)};
  geometry.values.resize(kUnits);
  for (const char* name : {"taxels_fn.png", "taxels_ft.png"}) {
    const image::RgbImage png = image::ReadPng(options.out_dir + "/" + name);
    EXPECT_EQ(png.width_px, kTaxelWidthPx) << name;
    EXPECT_EQ(png.height_px, kTaxelHeightPx) << name;
    const auto [x_px, loaded_y_px] = plot::HeatmapCellCenterPx(geometry, loaded, kHeldInAirS);
    const double unloaded_y_px = plot::HeatmapCellCenterPx(geometry, unloaded, kHeldInAirS).second;
    const std::array<int, 3> unloaded_rgb = At(png, x_px, unloaded_y_px);
    EXPECT_TRUE(IsWhite(unloaded_rgb)) << name << " unit " << unloaded << ": " << unloaded_rgb[0] << ","
                                       << unloaded_rgb[1] << "," << unloaded_rgb[2];
    if (std::string(name) == "taxels_fn.png") {
      const std::array<int, 3> loaded_rgb = At(png, x_px, loaded_y_px);
      EXPECT_FALSE(IsWhite(loaded_rgb)) << name << " unit " << loaded;
      EXPECT_NE(loaded_rgb, unloaded_rgb) << name;
    }
  }
}

// The shear map colours a unit by its sign: red for +Ft, blue for -Ft. A 3 N pull down, then one up,
// on the held box shears the pad's units well past the map's 0.5 N scale floor, with opposite signs;
// the most sheared unit of each sign is checked where its shear is a good part of the scale (so its
// cell is clearly coloured), and both colours must be checked (the test cannot pass by skipping).
TEST(TaxelPlotsTest, TheShearMapIsRedForPositiveAndBlueForNegativeFt) {
  const TempDir dir("taxel_plots_test");
  std::set<double> signs_checked;
  for (const double pull_n : {-3.0, 3.0}) {
    SCOPED_TRACE(pull_n);
    const std::string name = pull_n < 0.0 ? "down" : "up";
    const ScenarioConfig config = LoadScenario(dir.Write(
        name + ".yaml", HeldBoxScenario(0.6, "  - {at_s: 0.4, action: pull, force_n: [0.0, 0.0, " +
                                                 std::to_string(pull_n) + "]}\n")));
    RunOptions options;
    options.out_dir = dir.Path(name);
    ASSERT_TRUE(RunScenario(config, options).completed);
    const Signals signals(options.out_dir + "/signals.csv");
    double scale_n = kTaxelScaleFloorN;
    for (int u = 0; u < kUnits; ++u) {
      for (const double ft : signals.Column("ft_est_n_" + std::to_string(u))) scale_n = std::max(scale_n, std::abs(ft));
    }
    plot::Heatmap geometry;
    geometry.x = {signals.At("time_s", 0), signals.At("time_s", signals.rows() - 1)};
    geometry.values.resize(kUnits);
    const image::RgbImage png = image::ReadPng(options.out_dir + "/taxels_ft.png");
    for (const double sign : {1.0, -1.0}) {
      int strongest = -1;
      double strongest_n = 0.0;
      for (int u = 0; u < kUnits; ++u) {
        const double ft = sign * signals.AtTime("ft_est_n_" + std::to_string(u), kHeldInAirS);
        if (ft > strongest_n) {
          strongest_n = ft;
          strongest = u;
        }
      }
      std::printf("[ measure ] pull %+.0f N: strongest %cFt at %.2f s: unit %d, %.3f N of a %.3f N scale\n", pull_n,
                  sign > 0 ? '+' : '-', kHeldInAirS, strongest, strongest_n, scale_n);
      if (strongest < 0 || strongest_n < kColouredShareOfScale * scale_n) continue;
      const auto [x_px, y_px] = plot::HeatmapCellCenterPx(geometry, strongest, kHeldInAirS);
      const std::array<int, 3> rgb = At(png, x_px, y_px);
      EXPECT_GT(sign * (rgb[0] - rgb[2]), kWhiteTol)
          << "unit " << strongest << " Ft " << sign * strongest_n << " drawn as " << rgb[0] << "," << rgb[1] << ","
          << rgb[2];
      signs_checked.insert(sign);
    }
  }
  EXPECT_EQ(signs_checked.size(), 2u) << "a clearly loaded unit of each sign";
}

}  // namespace
}  // namespace graspbed::testbed
