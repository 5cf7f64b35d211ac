// Plots a person can read, checked on the PNGs read back (image::ReadPng): scorecard.png names the
// controllers under its axis, fills its bars and writes each value above its bar, draws a figure a
// controller does not have as a note (never as a bar or dot at 0) and puts no legend over the bars;
// forces.png colours each unit that carried load in a colour of its own and keeps its legend off the
// lines; compare.png draws one bar per unit with nothing joining neighbouring units.
// Texts are checked without OCR: the ink drawn where a label belongs must be as wide as cairo measures
// the expected text in the charts' font (13 px sans-serif), so "grip_slip" cannot pass for "1".
#include <cairo.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "common/plot.h"
#include "common/rgb_image.h"
#include "sensor/layout.h"
#include "testbed/compare.h"
#include "testbed/run_outputs.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "testbed/scorecard.h"
#include "tests/support/temp_dir.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed::testbed {
namespace {

using graspbed::test_support::TempDir;
using test_support::HeldBoxScenario;

constexpr double kChartFontPx = 13.0;   // plot.cc's kFontSize: tick labels, values, notes, legend
constexpr double kInkWidthTolPx = 3.0;  // antialiased edges and subpixel placement
constexpr int kInkLevel = 170;          // a channel below this is ink (text is black or dark grey)
constexpr int kColourTol = 40;          // per channel [0..255], a line or bar drawn in a colour
constexpr int kWhiteTol = 30;           // background and grid lines (224) are lighter than 255 - this
// The scorecard's panels, in order (testbed/scorecard.cc).
constexpr size_t kFlaggedPanel = 0;
constexpr size_t kLatencyPanel = 1;
constexpr size_t kScorecardPanels = 7;
// HeldBoxScenario: the hand has closed by this time [s]; a loaded unit then carries more than this [N].
constexpr double kAfterCloseS = 0.2;
constexpr double kLoadedN = 0.5;
constexpr int kShownPixels = 20;  // a colour drawn as a line, not a stray antialiased pixel

std::array<int, 3> At(const image::RgbImage& png, int x, int y) {
  const uint8_t* p = png.At(x, y);
  return {p[0], p[1], p[2]};
}

// Text and frame: dark and grey (bars and lines are coloured).
bool IsInk(const std::array<int, 3>& rgb) {
  const int darkest = std::min({rgb[0], rgb[1], rgb[2]});
  return darkest < kInkLevel && std::max({rgb[0], rgb[1], rgb[2]}) - darkest < 40;
}

bool IsBackground(const std::array<int, 3>& rgb) {
  return std::min({rgb[0], rgb[1], rgb[2]}) >= 255 - kWhiteTol &&
         std::max({rgb[0], rgb[1], rgb[2]}) - std::min({rgb[0], rgb[1], rgb[2]}) < 8;
}

bool Near(const std::array<int, 3>& rgb, const plot::Colour& colour, int tol = kColourTol) {
  const std::array<double, 3> want = {colour.r * 255.0, colour.g * 255.0, colour.b * 255.0};
  for (int c = 0; c < 3; ++c) {
    if (std::abs(rgb[static_cast<size_t>(c)] - want[static_cast<size_t>(c)]) > tol) return false;
  }
  return true;
}

// Width of the ink of `text` as cairo draws it in the charts' font [px].
double TextInkWidthPx(const std::string& text, bool italic = false) {
  std::unique_ptr<cairo_surface_t, void (*)(cairo_surface_t*)> surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1), cairo_surface_destroy);
  std::unique_ptr<cairo_t, void (*)(cairo_t*)> cr(cairo_create(surface.get()), cairo_destroy);
  cairo_select_font_face(cr.get(), "sans-serif", italic ? CAIRO_FONT_SLANT_ITALIC : CAIRO_FONT_SLANT_NORMAL,
                         CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr.get(), kChartFontPx);
  cairo_text_extents_t extents;
  cairo_text_extents(cr.get(), text.c_str(), &extents);
  return extents.width;
}

// Width of the ink (columns holding an ink pixel, first to last) in the rectangle [x0, x1) x [y0, y1).
double InkWidthPx(const image::RgbImage& png, double x0, double y0, double x1, double y1) {
  int first = -1;
  int last = -1;
  for (int x = static_cast<int>(x0); x < static_cast<int>(x1); ++x) {
    for (int y = static_cast<int>(y0); y < static_cast<int>(y1); ++y) {
      if (x < 0 || y < 0 || x >= png.width_px || y >= png.height_px || !IsInk(At(png, x, y))) continue;
      if (first < 0) first = x;
      last = x;
      break;
    }
  }
  return first < 0 ? 0.0 : last - first + 1.0;
}

// Three controllers: one catches every gross slip, one some, one met none (so it has no detection
// rate and no latency, which the table prints as "-").
Scorecard ThreeControllers() {
  Scorecard scorecard;
  scorecard.set_name = "readable";
  scorecard.set_version = 1;
  scorecard.runs_per_controller = 4;
  ControllerScore catches;
  catches.controller = "grip_slip";
  catches.runs = 4;
  catches.passed = 4;
  catches.gross_slip_events = 4;
  catches.gross_slip_detected = 4;
  catches.gross_detected_pct = 100.0;
  catches.gross_latency_p95_ms = 42.5;
  catches.false_per_min = 9.47;
  catches.false_per_lift = 0.39;
  catches.grip_efficiency_median = 1.31;
  ControllerScore some = catches;
  some.controller = "open_loop";
  some.passed = 2;
  some.gross_slip_detected = 1;
  some.gross_detected_pct = 25.0;
  some.gross_latency_p95_ms = 80.0;
  some.false_per_min = 0.5;
  some.false_per_lift = 0.05;
  some.grip_efficiency_median = 2.1;
  some.drops = 1;
  ControllerScore quiet = catches;
  quiet.controller = "threshold";
  quiet.passed = 3;
  quiet.gross_slip_events = 0;
  quiet.gross_slip_detected = 0;
  quiet.gross_detected_pct = std::nullopt;
  quiet.gross_latency_p95_ms = std::nullopt;
  quiet.false_per_min = 1.25;
  quiet.false_per_lift = 0.12;
  quiet.grip_efficiency_median = 1.05;
  scorecard.scores = {catches, some, quiet};
  return scorecard;
}

struct ScorecardPicture {
  plot::Figure figure;
  image::RgbImage png;
};

ScorecardPicture WriteAndRead(const TempDir& dir) {
  ScorecardPicture picture;
  const Scorecard scorecard = ThreeControllers();
  picture.figure = ScorecardFigure(scorecard);
  WriteScorecardPlot(scorecard, dir.Path("scorecard.png"));
  picture.png = image::ReadPng(dir.Path("scorecard.png"));
  return picture;
}

// Centre of bar k's slot and the width of a slot, the baseline (y = 0) and the end of a bar of `value`.
struct Slot {
  double centre_px, width_px, baseline_px, end_px;
};
Slot SlotOf(const plot::Figure& figure, size_t panel, size_t k, double value) {
  const auto [centre, baseline] = plot::ChartPointPx(figure, panel, k + 1.0, 0.0);
  const double width = plot::ChartPointPx(figure, panel, k + 1.5, 0.0).first -
                       plot::ChartPointPx(figure, panel, k + 0.5, 0.0).first;
  return {centre, width, baseline, plot::ChartPointPx(figure, panel, k + 1.0, value).second};
}

TEST(ReadablePlotsTest, ScorecardNamesTheControllersUnderTheAxis) {
  const TempDir dir("readable_plots");
  const ScorecardPicture picture = WriteAndRead(dir);
  ASSERT_EQ(picture.figure.panels.size(), kScorecardPanels);
  const Scorecard scorecard = ThreeControllers();
  for (size_t panel = 0; panel < kScorecardPanels; ++panel) {
    for (size_t k = 0; k < scorecard.scores.size(); ++k) {
      const Slot slot = SlotOf(picture.figure, panel, k, 0.0);
      // Tick labels hang 8 px under the axis, one 13 px line.
      const double ink =
          InkWidthPx(picture.png, slot.centre_px - 0.5 * slot.width_px + 3, slot.baseline_px + 7,
                     slot.centre_px + 0.5 * slot.width_px - 3, slot.baseline_px + 24);
      EXPECT_NEAR(ink, TextInkWidthPx(scorecard.scores[k].controller), kInkWidthTolPx)
          << "panel " << panel << ": the name " << scorecard.scores[k].controller << " under its bar";
    }
  }
}

TEST(ReadablePlotsTest, ScorecardBarsAreFilledAndWriteTheirValues) {
  const TempDir dir("readable_plots");
  const ScorecardPicture picture = WriteAndRead(dir);
  int bars_checked = 0;
  for (size_t panel = 0; panel < kScorecardPanels; ++panel) {
    const plot::Chart& chart = picture.figure.panels[panel];
    for (size_t k = 0; k < chart.bars.size(); ++k) {
      if (!chart.bars[k].value) continue;
      const double value = *chart.bars[k].value;
      const Slot slot = SlotOf(picture.figure, panel, k, value);
      if (value > 0.0) {
        // Filled: the middle of the bar, not only its outline, is the bar's colour.
        const std::array<int, 3> middle = At(picture.png, static_cast<int>(slot.centre_px),
                                             static_cast<int>(0.5 * (slot.baseline_px + slot.end_px)));
        EXPECT_TRUE(Near(middle, plot::PaletteColour(static_cast<int>(k))))
            << "panel " << panel << " bar " << k << " middle " << middle[0] << "," << middle[1] << ","
            << middle[2];
        ++bars_checked;
      }
      char text[64];
      std::snprintf(text, sizeof text, chart.bar_value_format.c_str(), value);
      // The value's one line, 4 px above the bar's end.
      const double ink = InkWidthPx(picture.png, slot.centre_px - 0.5 * slot.width_px + 3, slot.end_px - 18,
                                    slot.centre_px + 0.5 * slot.width_px - 3, slot.end_px - 2);
      EXPECT_NEAR(ink, TextInkWidthPx(text), kInkWidthTolPx)
          << "panel " << panel << ": '" << text << "' above bar " << k;
    }
  }
  EXPECT_GE(bars_checked, 14);
}

TEST(ReadablePlotsTest, ScorecardDrawsAFigureAControllerDoesNotHaveAsANoteNotAsZero) {
  const TempDir dir("readable_plots");
  const ScorecardPicture picture = WriteAndRead(dir);
  constexpr size_t kQuiet = 2;  // no gross slip event
  for (const size_t panel : {kFlaggedPanel, kLatencyPanel}) {
    SCOPED_TRACE(panel);
    const Slot slot = SlotOf(picture.figure, panel, kQuiet, 0.0);
    // No bar, no dot: nothing in the controller's colour in its slot.
    int coloured = 0;
    for (int x = static_cast<int>(slot.centre_px - 0.45 * slot.width_px);
         x < slot.centre_px + 0.45 * slot.width_px; ++x) {
      for (int y = static_cast<int>(slot.baseline_px) - 60; y < slot.baseline_px + 6; ++y) {
        coloured += Near(At(picture.png, x, y), plot::PaletteColour(static_cast<int>(kQuiet)), 20);
      }
    }
    EXPECT_EQ(coloured, 0) << "pixels of a bar or dot at 0";
    // The note, just above the baseline, italic.
    const double ink =
        InkWidthPx(picture.png, slot.centre_px - 0.5 * slot.width_px + 3, slot.baseline_px - 20,
                   slot.centre_px + 0.5 * slot.width_px - 3, slot.baseline_px - 2);
    EXPECT_NEAR(ink, TextInkWidthPx("no events", /*italic=*/true), kInkWidthTolPx);
  }
}

TEST(ReadablePlotsTest, ScorecardHasNoLegendOverTheBars) {
  const TempDir dir("readable_plots");
  const ScorecardPicture picture = WriteAndRead(dir);
  for (size_t panel = 0; panel < kScorecardPanels; ++panel) {
    const plot::Chart& chart = picture.figure.panels[panel];
    for (size_t k = 0; k < ThreeControllers().scores.size(); ++k) {
      const double value = k < chart.bars.size() ? chart.bars[k].value.value_or(0.0) : 0.0;
      const Slot slot = SlotOf(picture.figure, panel, k, value);
      // Above the bar's value (or note), up to the frame: background and grid only. The frame is the
      // first row of ink that runs across the whole slot.
      const int label_top = static_cast<int>(slot.end_px) - 18;
      int y = label_top;
      bool frame = false;
      for (; y > 0 && !frame; --y) {
        frame = true;
        for (int x = static_cast<int>(slot.centre_px - 0.5 * slot.width_px);
             x < slot.centre_px + 0.5 * slot.width_px; ++x) {
          frame = frame && IsInk(At(picture.png, x, y));
        }
      }
      ASSERT_TRUE(frame) << "panel " << panel << " bar " << k << ": no frame above it";
      for (int row = y + 3; row < label_top; ++row) {
        for (int x = static_cast<int>(slot.centre_px - 0.5 * slot.width_px) + 3;
             x < slot.centre_px + 0.5 * slot.width_px - 3; ++x) {
          const std::array<int, 3> rgb = At(picture.png, x, row);
          ASSERT_TRUE(IsBackground(rgb)) << "panel " << panel << " above bar " << k << " at (" << x << ", "
                                         << row << "): " << rgb[0] << "," << rgb[1] << "," << rgb[2];
        }
      }
    }
  }
}

// forces.png of a held box: the chart the runner draws, rebuilt from the same signals (its first
// panel lays out alone: a titled one-column figure of the default panel size, as sim_run.cc writes).
struct ForcesPicture {
  plot::Figure figure;
  image::RgbImage png;
  std::vector<int> loaded;  // units that carried load (kCarriedLoadShare of the largest peak)
  std::vector<std::pair<double, double>> peaks;  // (time [s], Fn [N]) of each loaded unit's peak
  sensor::Layout layout;
};

ForcesPicture RunHeldBox(const TempDir& dir) {
  ForcesPicture picture;
  const ScenarioConfig config = LoadScenario(dir.Write("held.yaml", HeldBoxScenario(0.6)));
  picture.layout = sensor::LoadLayout(ResolveLayoutPath(config));
  RunOptions options;
  options.out_dir = dir.Path("out");
  options.on_signals = [&](const common::SignalLog& log) {
    const std::vector<double> time = log.ColumnValues("time_s");
    picture.figure.title = "forces";
    picture.figure.columns = 1;
    picture.figure.panels = {internal::PerUnitFnChart(log, time, picture.layout)};
    std::vector<double> peak_n;
    std::vector<double> peak_s;
    for (int u = 0; u < picture.layout.unit_count(); ++u) {
      const std::vector<double> fn = log.ColumnValues("fn_est_n_" + std::to_string(u));
      size_t at = 0;
      for (size_t i = 0; i < fn.size(); ++i) {
        if (std::isfinite(fn[i]) && fn[i] > fn[at]) at = i;
      }
      peak_n.push_back(fn.empty() ? 0.0 : fn[at]);
      peak_s.push_back(fn.empty() ? 0.0 : time[at]);
    }
    const double largest = *std::max_element(peak_n.begin(), peak_n.end());
    for (int u = 0; u < picture.layout.unit_count(); ++u) {
      if (peak_n[static_cast<size_t>(u)] > 0.0 &&
          peak_n[static_cast<size_t>(u)] >= internal::kCarriedLoadShare * largest) {
        picture.loaded.push_back(u);
        picture.peaks.emplace_back(peak_s[static_cast<size_t>(u)], peak_n[static_cast<size_t>(u)]);
      }
    }
  };
  EXPECT_TRUE(RunScenario(config, options).completed);
  picture.png = image::ReadPng(options.out_dir + "/forces.png");
  return picture;
}

// The colour drawn nearest (x, y) among `colours`, within 2 px: its index, -1 for none.
int ColourNear(const image::RgbImage& png, double x, double y, const std::vector<plot::Colour>& colours) {
  for (int radius = 0; radius <= 2; ++radius) {
    for (int dy = -radius; dy <= radius; ++dy) {
      for (int dx = -radius; dx <= radius; ++dx) {
        const std::array<int, 3> rgb = At(png, static_cast<int>(x) + dx, static_cast<int>(y) + dy);
        for (size_t c = 0; c < colours.size(); ++c) {
          if (Near(rgb, colours[c], 12)) return static_cast<int>(c);
        }
      }
    }
  }
  return -1;
}

TEST(ReadablePlotsTest, ForcesColourEachLoadedUnitApartAndNameItAsTheLayoutPictureDoes) {
  const TempDir dir("readable_plots");
  const ForcesPicture picture = RunHeldBox(dir);
  ASSERT_GE(picture.loaded.size(), 2u) << "a held box loads several units";
  ASSERT_LE(picture.loaded.size(), static_cast<size_t>(plot::kPaletteSize));
  const plot::Chart& chart = picture.figure.panels[0];
  for (size_t i = 0; i < picture.loaded.size(); ++i) {
    const int unit = picture.loaded[i];
    const sensor::UnitPose& pose = picture.layout.units[static_cast<size_t>(unit)];
    const std::string name = "unit " + std::to_string(unit) + " (row " + std::to_string(pose.row) +
                             ", column " + std::to_string(pose.column) + ")";
    EXPECT_TRUE(std::any_of(chart.series.begin(), chart.series.end(),
                            [&](const plot::Series& s) { return s.name == name; }))
        << name << " in the legend";
  }
  // Read back: where the loaded units' lines run (above 0.5 N, after the close), one palette colour
  // per loaded unit, none shared (eight colours cycled over 20 units gave units 2, 10 and 18 one green).
  const double x0 = plot::ChartPointPx(picture.figure, 0, kAfterCloseS, 0.0).first;
  const double x1 = plot::ChartPointPx(picture.figure, 0, chart.series[0].x.back(), 0.0).first;
  const double y0 = plot::ChartPointPx(picture.figure, 0, 0.0, kLoadedN).second;
  double largest_n = 0.0;
  for (const auto& peak : picture.peaks) largest_n = std::max(largest_n, peak.second);
  const double y_top = plot::ChartPointPx(picture.figure, 0, 0.0, largest_n).second - 3.0;
  std::set<int> shown;
  for (int c = 0; c < plot::kPaletteSize; ++c) {
    int pixels = 0;
    for (int x = static_cast<int>(x0); x < x1; ++x) {
      for (int y = static_cast<int>(y_top); y < y0; ++y)
        pixels += Near(At(picture.png, x, y), plot::PaletteColour(c), 12);
    }
    if (pixels >= kShownPixels) shown.insert(c);
  }
  std::set<int> expected;
  for (size_t i = 0; i < picture.loaded.size(); ++i) expected.insert(static_cast<int>(i));
  EXPECT_EQ(shown, expected) << "palette colours drawn where " << picture.loaded.size()
                             << " loaded units run";
}

TEST(ReadablePlotsTest, ForcesLegendCoversNoLine) {
  const TempDir dir("readable_plots");
  const ForcesPicture picture = RunHeldBox(dir);
  const plot::Chart& chart = picture.figure.panels[0];
  std::vector<plot::Colour> colours;
  for (const plot::Series& series : chart.series) colours.push_back(*series.colour);
  // Every point of every line, a few pixels apart, shows a line's colour: none lies under a legend.
  int checked = 0;
  for (const plot::Series& series : chart.series) {
    double last_x = -1e9;
    for (size_t i = 0; i < series.x.size(); ++i) {
      const auto [x, y] = plot::ChartPointPx(picture.figure, 0, series.x[i], series.y[i]);
      if (!std::isfinite(series.y[i]) || x - last_x < 4.0) continue;
      last_x = x;
      ++checked;
      ASSERT_GE(ColourNear(picture.png, x, y, colours), 0)
          << series.name << " at " << series.x[i] << " s, " << series.y[i] << " N is hidden";
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(ReadablePlotsTest, CompareDrawsOneBarPerUnitAndJoinsNone) {
  const TempDir dir("readable_plots");
  RunComparison comparison;
  comparison.run_a = "a";
  comparison.run_b = "b";
  comparison.aligned_on = "start";
  comparison.time_s = {0.0, 1.0};
  comparison.grip_a_n = {0.0, 1.0};
  comparison.grip_b_n = {0.0, 1.1};
  for (int u = 0; u < 20; ++u) {
    UnitResidual unit;
    unit.unit = u;
    unit.fn_rms_n = u % 2 == 0 ? 0.4 : 0.05;  // neighbours far apart: a line between them would cross the gap
    comparison.units.push_back(unit);
  }
  const plot::Figure figure = ComparisonFigure(comparison);
  WriteComparisonPlot(comparison, dir.Path("compare.png"));
  const image::RgbImage png = image::ReadPng(dir.Path("compare.png"));
  constexpr size_t kUnitsPanel = 2;
  for (size_t k = 0; k + 1 < comparison.units.size(); ++k) {
    // Between two bars, from the lower bar's value to the higher's: background and grid only.
    const double gap_x = plot::ChartPointPx(figure, kUnitsPanel, k + 1.5, 0.0).first;
    const double low = plot::ChartPointPx(figure, kUnitsPanel, k + 1.5, 0.07).second;
    const double high = plot::ChartPointPx(figure, kUnitsPanel, k + 1.5, 0.38).second;
    for (int y = static_cast<int>(high); y < low; ++y) {
      const std::array<int, 3> rgb = At(png, static_cast<int>(gap_x), y);
      ASSERT_TRUE(IsBackground(rgb)) << "between units " << k << " and " << k + 1 << " at y " << y << ": "
                                     << rgb[0] << "," << rgb[1] << "," << rgb[2];
    }
    // The bar itself, filled.
    const auto [x, y] = plot::ChartPointPx(figure, kUnitsPanel, k + 1.0, 0.5 * comparison.units[k].fn_rms_n);
    EXPECT_TRUE(
        Near(At(png, static_cast<int>(x), static_cast<int>(y)), *figure.panels[kUnitsPanel].bar_colour))
        << k;
  }
}

}  // namespace
}  // namespace graspbed::testbed
