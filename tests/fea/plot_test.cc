// common/plot: PNG charts written atomically, readable back, with the data drawn.
#include "common/plot.h"

#include <cairo.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <string>

#include "tests/support/temp_dir.h"

namespace graspbed::plot {
namespace {

namespace fs = std::filesystem;
using graspbed::test_support::TempDir;

class PlotTest : public ::testing::Test {
 protected:
  const TempDir temp_dir_{"plot_test"};
  const fs::path dir_ = temp_dir_.path();
};

// Pixels of `path` close to the palette's first colour (0, 0.45, 0.70).
int CountFirstSeriesPixels(const std::string& path, int* width, int* height) {
  cairo_surface_t* image = cairo_image_surface_create_from_png(path.c_str());
  EXPECT_EQ(cairo_surface_status(image), CAIRO_STATUS_SUCCESS) << path;
  *width = cairo_image_surface_get_width(image);
  *height = cairo_image_surface_get_height(image);
  const int stride = cairo_image_surface_get_stride(image);
  const unsigned char* data = cairo_image_surface_get_data(image);
  int count = 0;
  for (int y = 0; y < *height; ++y) {
    for (int x = 0; x < *width; ++x) {
      const uint32_t pixel = *reinterpret_cast<const uint32_t*>(data + y * stride + 4 * x);
      const int r = (pixel >> 16) & 0xff, g = (pixel >> 8) & 0xff, b = pixel & 0xff;
      if (std::abs(r - 0) < 20 && std::abs(g - 115) < 20 && std::abs(b - 178) < 20) ++count;
    }
  }
  cairo_surface_destroy(image);
  return count;
}

Chart SineChart(bool with_series) {
  Chart chart;
  chart.title = "test";
  chart.x_label = "x [mm]";
  chart.y_label = "y [-]";
  Series sine{"sine", {}, {}};
  for (int i = 0; i <= 100; ++i) {
    sine.x.push_back(i * 0.1);
    sine.y.push_back(std::sin(i * 0.1));
  }
  if (with_series) chart.series.push_back(sine);
  chart.series.push_back({"", {0.0, 10.0}, {-1.0, 1.0}, true});  // keeps the ranges equal
  chart.markers = {{5.0, "half"}};
  chart.bands = {{2.0, 3.0, "band"}};
  return chart;
}

TEST_F(PlotTest, WritesAReadablePngWithTheSeriesDrawnAndNoTempFileLeft) {
  const std::string with = (dir_ / "with.png").string();
  const std::string without = (dir_ / "without.png").string();
  WritePng(SineChart(true), with, 640, 400);
  WritePng(SineChart(false), without, 640, 400);
  int width = 0, height = 0;
  const int drawn = CountFirstSeriesPixels(with, &width, &height);
  EXPECT_EQ(width, 640);
  EXPECT_EQ(height, 400);
  // The dashed helper line takes the first colour when the sine is absent: compare the two.
  const int reference = CountFirstSeriesPixels(without, &width, &height);
  EXPECT_GT(drawn, 300);  // a 2-px line across ~530 px of plot width
  EXPECT_GT(drawn, reference);
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().extension(), ".png") << entry.path();
    ++files;
  }
  EXPECT_EQ(files, 2);
}

TEST_F(PlotTest, MultiPanelFigureHasTheGridSize) {
  Figure figure;
  figure.title = "two panels";
  figure.panels = {SineChart(true), SineChart(true), SineChart(false)};
  figure.columns = 2;
  figure.panel_width_px = 300;
  figure.panel_height_px = 200;
  const std::string path = (dir_ / "figure.png").string();
  WritePng(figure, path);
  int width = 0, height = 0;
  EXPECT_GT(CountFirstSeriesPixels(path, &width, &height), 0);
  EXPECT_EQ(width, 600);
  EXPECT_EQ(height, 2 * 200 + 34);
}

TEST_F(PlotTest, BadInputAndUnwritablePathsThrow) {
  Chart chart = SineChart(true);
  chart.series[0].y.pop_back();
  EXPECT_THROW(WritePng(chart, (dir_ / "bad.png").string()), std::invalid_argument);
  EXPECT_THROW(WritePng(SineChart(true), (dir_ / "x.png").string(), 0, 100), std::invalid_argument);
  try {
    WritePng(SineChart(true), (dir_ / "missing" / "x.png").string());
    ADD_FAILURE() << "no error for a missing directory";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("missing/x.png"), std::string::npos) << error.what();
  }
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST(NiceTicksTest, PicksRoundSteps) {
  const std::vector<double> ticks = NiceTicks(0.0, 1.0, 5);
  ASSERT_EQ(ticks.size(), 6u);
  EXPECT_NEAR(ticks[1], 0.2, 1e-12);
  const std::vector<double> strain = NiceTicks(-3.3e-4, 1.2e-3, 6);
  EXPECT_NEAR(strain[1] - strain[0], 5e-4, 1e-15);  // 1.53e-3 / 6 rounds up to 5e-4
  EXPECT_GE(strain.front(), -3.3e-4);
  EXPECT_LE(strain.back(), 1.2e-3);
}

TEST(NonFiniteTest, NaNPointsBreakTheLineWithoutFailing) {
  Chart chart;
  chart.series = {{"gappy", {0, 1, 2, 3}, {0, NAN, 2, 3}}};
  const TempDir dir("plot_nan_test");
  const fs::path path = dir.path() / "graspbed_plot_nan_test.png";
  EXPECT_NO_THROW(WritePng(chart, path.string(), 200, 150));
  fs::remove(path);
}

// {r, g, b} 0..255 of pixel (x, y) of the PNG at `path`.
std::array<int, 3> PixelAt(const std::string& path, double x, double y) {
  cairo_surface_t* image = cairo_image_surface_create_from_png(path.c_str());
  EXPECT_EQ(cairo_surface_status(image), CAIRO_STATUS_SUCCESS) << path;
  const uint32_t pixel = *reinterpret_cast<const uint32_t*>(
      cairo_image_surface_get_data(image) + static_cast<int>(y) * cairo_image_surface_get_stride(image) +
      4 * static_cast<int>(x));
  cairo_surface_destroy(image);
  return {static_cast<int>((pixel >> 16) & 0xff), static_cast<int>((pixel >> 8) & 0xff),
          static_cast<int>(pixel & 0xff)};
}

// Three rows over 0..10: zero, a step from 0 to 2 at x = 5, and -2 / NaN halves.
Heatmap StepHeatmap(bool signed_scale) {
  Heatmap heatmap;
  heatmap.title = "step";
  heatmap.x_label = "time [s]";
  heatmap.row_label = "unit";
  heatmap.value_label = "F [N]";
  heatmap.row_labels = {"0", "1", "2"};
  heatmap.values.resize(3);
  for (int i = 0; i <= 1000; ++i) {
    const double x = i * 0.01;
    heatmap.x.push_back(x);
    heatmap.values[0].push_back(0.0);
    heatmap.values[1].push_back(x < 5.0 ? 0.0 : 2.0);
    heatmap.values[2].push_back(x < 5.0 ? -2.0 : NAN);
  }
  heatmap.signed_scale = signed_scale;
  heatmap.width_px = 700;
  heatmap.height_px = 300;
  return heatmap;
}

TEST_F(PlotTest, HeatmapColoursEachCellByItsValueOnTheChosenScale) {
  const std::string sequential = (dir_ / "sequential.png").string();
  const std::string diverging = (dir_ / "diverging.png").string();
  const Heatmap heatmap = StepHeatmap(false);
  WritePng(heatmap, sequential);
  WritePng(StepHeatmap(true), diverging);
  int width = 0, height = 0;
  CountFirstSeriesPixels(sequential, &width, &height);
  EXPECT_EQ(width, 700);
  EXPECT_EQ(height, 300);
  const auto at = [&](const std::string& path, int row, double x) {
    const auto [px, py] = HeatmapCellCenterPx(heatmap, row, x);
    return PixelAt(path, px, py);
  };
  const std::array<int, 3> white{255, 255, 255};
  const std::array<int, 3> grey{191, 191, 191};
  // Sequential: 0 white, the maximum dark red, negatives as 0, NaN grey.
  EXPECT_EQ(at(sequential, 0, 7.0), white);
  EXPECT_EQ(at(sequential, 1, 2.0), white);
  const std::array<int, 3> loaded = at(sequential, 1, 7.0);
  EXPECT_GT(loaded[0], 100);
  EXPECT_LT(loaded[1], 30);
  EXPECT_EQ(at(sequential, 2, 2.0), white);
  EXPECT_EQ(at(sequential, 2, 7.0), grey);
  // Signed: 0 white, + red, - blue.
  EXPECT_EQ(at(diverging, 0, 7.0), white);
  const std::array<int, 3> positive = at(diverging, 1, 7.0);
  const std::array<int, 3> negative = at(diverging, 2, 2.0);
  EXPECT_GT(positive[0], positive[2]);
  EXPECT_GT(negative[2], negative[0]);
}

TEST_F(PlotTest, HeatmapWithMismatchedRowsIsRefused) {
  Heatmap heatmap = StepHeatmap(false);
  heatmap.values[1].pop_back();
  EXPECT_THROW(WritePng(heatmap, (dir_ / "bad.png").string()), std::invalid_argument);
  heatmap = StepHeatmap(false);
  heatmap.row_labels.pop_back();
  EXPECT_THROW(WritePng(heatmap, (dir_ / "bad.png").string()), std::invalid_argument);
  EXPECT_TRUE(fs::is_empty(dir_));
}

}  // namespace
}  // namespace graspbed::plot
