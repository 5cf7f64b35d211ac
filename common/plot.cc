#include "common/plot.h"

#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include "common/rgb_image.h"

namespace graspbed::plot {
namespace {

struct Rgb {
  double r, g, b;
};

// Colour-blind friendly palette (Okabe-Ito), cycled.
constexpr std::array<Rgb, kPaletteSize> kPalette{{{0.00, 0.45, 0.70},
                                                  {0.84, 0.37, 0.00},
                                                  {0.00, 0.62, 0.45},
                                                  {0.80, 0.47, 0.65},
                                                  {0.90, 0.62, 0.00},
                                                  {0.34, 0.71, 0.91},
                                                  {0.10, 0.10, 0.10},
                                                  {0.94, 0.89, 0.26}}};

constexpr double kMarginLeft = 90.0;
constexpr double kMarginRight = 20.0;
constexpr double kMarginTop = 40.0;
constexpr double kMarginBottom = 55.0;
constexpr double kFontSize = 13.0;
constexpr double kTitleFontSize = 15.0;

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double value) {
    if (!std::isfinite(value)) return;
    lo = std::min(lo, value);
    hi = std::max(hi, value);
  }
  bool Empty() const { return !(lo <= hi); }
};

// Pads an empty or degenerate range so the axis maps it to a non-zero span.
Range Padded(Range range) {
  if (range.Empty()) return {0.0, 1.0};
  if (range.hi - range.lo <= 1e-12 * std::max(1.0, std::abs(range.hi))) {
    const double pad = range.lo == 0.0 ? 1.0 : 0.1 * std::abs(range.lo);
    return {range.lo - pad, range.hi + pad};
  }
  return range;
}

std::string FormatTick(double value, double step) {
  if (std::abs(value) < 1e-9 * step) value = 0.0;  // no "-0" or "1e-17"
  char text[32];
  const double magnitude = std::max(std::abs(value), step);
  if (magnitude >= 1e5 || magnitude < 1e-3) {
    std::snprintf(text, sizeof text, "%.3g", value);
  } else {
    const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
    std::snprintf(text, sizeof text, "%.*f", decimals, value);
  }
  return text;
}

void ValidateChart(const Chart& chart) {
  for (const Series& series : chart.series) {
    if (series.x.size() != series.y.size()) {
      throw std::invalid_argument("plot: series '" + series.name + "' has " +
                                  std::to_string(series.x.size()) + " x values but " +
                                  std::to_string(series.y.size()) + " y values");
    }
  }
}

void ShowText(cairo_t* cr, const std::string& text, double x, double y, double align_x, double align_y) {
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  cairo_move_to(cr, x - align_x * extents.width - extents.x_bearing,
                y - align_y * extents.height - extents.y_bearing);
  cairo_show_text(cr, text.c_str());
}

// Shows `text` turned a quarter turn anticlockwise (reading upwards), centred on (x, y).
void ShowUpwardText(cairo_t* cr, const std::string& text, double x, double y) {
  cairo_save(cr);
  cairo_translate(cr, x, y);
  cairo_rotate(cr, -M_PI / 2);
  ShowText(cr, text, 0.0, 0.0, 0.5, 0.5);
  cairo_restore(cr);
}

// Adds `series` to the path as polylines in pixels (non-finite points break the line), keeping of
// each run of consecutive points in one pixel column only the first, the lowest, the highest and the
// last: the same pixels as a line through every point, for a fraction of the stroke's cost (a 20 s
// run logs 20000 samples for a 700 px wide chart).
template <typename ToPxX, typename ToPxY>
void AddPolyline(cairo_t* cr, const Series& series, ToPxX to_px_x, ToPxY to_px_y) {
  bool pen_down = false;
  // The open column: indices of its first, lowest, highest (by pixel y) and last point.
  bool open = false;
  double column = 0.0;
  std::array<size_t, 4> kept{};  // first, low, high, last
  auto flush = [&] {
    if (!open) return;
    std::array<size_t, 4> order = kept;
    std::sort(order.begin(), order.end());
    for (size_t k = 0; k < order.size(); ++k) {
      if (k > 0 && order[k] == order[k - 1]) continue;
      const double px = to_px_x(series.x[order[k]]);
      const double py = to_px_y(series.y[order[k]]);
      if (pen_down) {
        cairo_line_to(cr, px, py);
      } else {
        cairo_move_to(cr, px, py);
        pen_down = true;
      }
    }
    open = false;
  };
  for (size_t i = 0; i < series.x.size(); ++i) {
    if (!std::isfinite(series.x[i]) || !std::isfinite(series.y[i])) {
      flush();
      pen_down = false;
      continue;
    }
    const double this_column = std::floor(to_px_x(series.x[i]));
    if (open && this_column == column) {
      const double py = to_px_y(series.y[i]);
      if (py < to_px_y(series.y[kept[1]])) kept[1] = i;
      if (py > to_px_y(series.y[kept[2]])) kept[2] = i;
      kept[3] = i;
      continue;
    }
    flush();
    open = true;
    column = this_column;
    kept = {i, i, i, i};
  }
  flush();
}

// ---- charts ---------------------------------------------------------------------------------------

constexpr double kLegendRowPx = 18.0;
constexpr double kLegendSwatchPx = 26.0;
constexpr double kLegendInsetPx = 10.0;  // from the plot area's edges
constexpr double kBarHalfWidth = 0.3;    // of a category's slot of 1 [x units]
constexpr double kBarLabelGapPx = 4.0;   // between a bar's end and its value
constexpr double kSmallestFontPx = 8.0;  // category names and values shrink to fit, down to this
constexpr Rgb kMissingNoteColour{0.35, 0.35, 0.35};

struct Box {
  double x, y, w, h;  // [px]
  bool Overlaps(const Box& o) const { return x < o.x + o.w && o.x < x + w && y < o.y + o.h && o.y < y + h; }
};

// Where the parts of a chart land in its rectangle of the surface.
struct ChartLayout {
  double x0, y0, width, height;     // the chart's rectangle [px]
  double left, right, top, bottom;  // plot area [px]
  Range x_range, y_range;
  std::vector<size_t> listed;  // series named in the legend
  Box legend{0, 0, 0, 0};      // the legend's box [px]; empty when nothing is listed
  double ToPxX(double x) const {
    return left + (x - x_range.lo) / (x_range.hi - x_range.lo) * (right - left);
  }
  double ToPxY(double y) const {
    return bottom - (y - y_range.lo) / (y_range.hi - y_range.lo) * (bottom - top);
  }
  double SlotPx() const { return ToPxX(1.0) - ToPxX(0.0); }  // one category's width in a bar chart
};

void SetRgb(cairo_t* cr, const Rgb& colour) { cairo_set_source_rgb(cr, colour.r, colour.g, colour.b); }

Rgb SeriesColour(const Chart& chart, size_t s) {
  const std::optional<Colour>& own = chart.series[s].colour;
  return own ? Rgb{own->r, own->g, own->b} : kPalette[s % kPalette.size()];
}

void UseChartFont(cairo_t* cr, double size_px, bool italic = false) {
  cairo_select_font_face(cr, "sans-serif", italic ? CAIRO_FONT_SLANT_ITALIC : CAIRO_FONT_SLANT_NORMAL,
                         CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size_px);
}

// The font size (kFontSize, or smaller down to kSmallestFontPx) at which `text` fits `width_px`.
double FittingFontSize(cairo_t* cr, const std::string& text, double width_px) {
  cairo_set_font_size(cr, kFontSize);
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  if (extents.width <= width_px) return kFontSize;
  return std::max(kSmallestFontPx, kFontSize * width_px / extents.width);
}

Box TextBox(cairo_t* cr, const std::string& text, double x, double y, double align_x, double align_y) {
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  return {x - align_x * extents.width, y - align_y * extents.height, extents.width, extents.height};
}

std::string BarValueText(const Chart& chart, double value) {
  char text[64];
  std::snprintf(text, sizeof text, chart.bar_value_format.c_str(), value);
  return text;
}

// A bar's value, written above its end (below it for a negative value), at `*size_px`.
Box BarValueBox(cairo_t* cr, const Chart& chart, const ChartLayout& layout, size_t k, double* size_px) {
  const double value = *chart.bars[k].value;
  const std::string text = BarValueText(chart, value);
  *size_px = FittingFontSize(cr, text, layout.SlotPx() - 2.0);
  cairo_set_font_size(cr, *size_px);
  const double end = layout.ToPxY(value);
  return value >= 0.0 ? TextBox(cr, text, layout.ToPxX(k + 1.0), end - kBarLabelGapPx, 0.5, 1.0)
                      : TextBox(cr, text, layout.ToPxX(k + 1.0), end + kBarLabelGapPx, 0.5, 0.0);
}

// The note where a bar without a value would stand, just above the baseline, at `*size_px`.
Box MissingNoteBox(cairo_t* cr, const Chart& chart, const ChartLayout& layout, size_t k, double* size_px) {
  UseChartFont(cr, kFontSize, /*italic=*/true);
  *size_px = FittingFontSize(cr, chart.bars[k].missing_note, layout.SlotPx() - 2.0);
  cairo_set_font_size(cr, *size_px);
  const double baseline = layout.ToPxY(std::clamp(0.0, layout.y_range.lo, layout.y_range.hi));
  const Box box =
      TextBox(cr, chart.bars[k].missing_note, layout.ToPxX(k + 1.0), baseline - kBarLabelGapPx, 0.5, 1.0);
  UseChartFont(cr, kFontSize);
  return box;
}

// Data ranges of the chart, padded, with head room: 5 % of the span for lines, and for bars room for
// the tallest bar's value inside the plot area of `plot_height_px`.
void FitRanges(const Chart& chart, double plot_height_px, ChartLayout& layout) {
  Range x_range;
  Range y_range;
  for (const Series& series : chart.series) {
    for (size_t i = 0; i < series.x.size(); ++i) {
      if (std::isfinite(series.x[i]) && std::isfinite(series.y[i])) {
        x_range.Add(series.x[i]);
        y_range.Add(series.y[i]);
      }
    }
  }
  for (const Marker& marker : chart.markers) x_range.Add(marker.x);
  for (const Band& band : chart.bands) {
    x_range.Add(band.x_min);
    x_range.Add(band.x_max);
  }
  if (chart.bars.empty()) {
    if (chart.include_zero_y) y_range.Add(0.0);
    x_range = Padded(x_range);
    y_range = Padded(y_range);
    // A little head room so lines do not run along the frame.
    const double y_pad = 0.05 * (y_range.hi - y_range.lo);
    layout.x_range = x_range;
    layout.y_range = {y_range.lo - y_pad, y_range.hi + y_pad};
    return;
  }
  // Bars: categories 1..N in slots of 1, standing on 0.
  x_range.Add(0.5);
  x_range.Add(static_cast<double>(chart.bars.size()) + 0.5);
  for (const Bar& bar : chart.bars) {
    if (bar.value) y_range.Add(*bar.value);
  }
  y_range.Add(0.0);
  if (!(y_range.hi > y_range.lo)) y_range.hi = y_range.lo + 1.0;
  // Room for a value line (and a gap) above the tallest bar and below the deepest.
  const double text_px = kFontSize + 3.0 * kBarLabelGapPx;
  const double share = std::min(0.5, text_px / std::max(1.0, plot_height_px));
  const double span =
      (y_range.hi - y_range.lo) / (1.0 - (y_range.hi > 0.0) * share - (y_range.lo < 0.0) * share);
  layout.x_range = x_range;
  layout.y_range = {y_range.lo < 0.0 ? y_range.lo - share * span : y_range.lo,
                    y_range.hi > 0.0 ? y_range.hi + share * span : y_range.hi};
}

// Whether the segment (ax, ay)-(bx, by) crosses `box` (Liang-Barsky clipping).
bool SegmentCrosses(const Box& box, double ax, double ay, double bx, double by) {
  double t0 = 0.0;
  double t1 = 1.0;
  const double dx = bx - ax;
  const double dy = by - ay;
  const double p[] = {-dx, dx, -dy, dy};
  const double q[] = {ax - box.x, box.x + box.w - ax, ay - box.y, box.y + box.h - ay};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0.0) {
      if (q[i] < 0.0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0.0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 > t1) return false;
  }
  return true;
}

// Whether `box` would hide any drawn data: a line, a dot, a bar, a bar's value or note, a marker
// (its line or label) or a band's label.
bool CoversData(cairo_t* cr, const Chart& chart, const ChartLayout& layout, const Box& box) {
  for (const Series& series : chart.series) {
    bool have_previous = false;
    double px0 = 0.0;
    double py0 = 0.0;
    for (size_t i = 0; i < series.x.size(); ++i) {
      if (!std::isfinite(series.x[i]) || !std::isfinite(series.y[i])) {
        have_previous = false;
        continue;
      }
      const double px = layout.ToPxX(series.x[i]);
      const double py = layout.ToPxY(series.y[i]);
      if (have_previous ? SegmentCrosses(box, px0, py0, px, py) : SegmentCrosses(box, px, py, px, py))
        return true;
      have_previous = true;
      px0 = px;
      py0 = py;
    }
  }
  for (size_t k = 0; k < chart.bars.size(); ++k) {
    double size_px = kFontSize;
    if (chart.bars[k].value) {
      const double centre = layout.ToPxX(k + 1.0);
      const double end = layout.ToPxY(*chart.bars[k].value);
      const double base = layout.ToPxY(0.0);
      const double half = kBarHalfWidth * layout.SlotPx();
      if (box.Overlaps({centre - half, std::min(end, base), 2.0 * half, std::abs(base - end)})) return true;
      if (box.Overlaps(BarValueBox(cr, chart, layout, k, &size_px))) return true;
    } else if (box.Overlaps(MissingNoteBox(cr, chart, layout, k, &size_px))) {
      return true;
    }
  }
  UseChartFont(cr, kFontSize);
  for (const Marker& marker : chart.markers) {
    const double px = layout.ToPxX(marker.x);
    if (SegmentCrosses(box, px, layout.top, px, layout.bottom)) return true;
    if (!marker.label.empty() && box.Overlaps(TextBox(cr, marker.label, px + 3, layout.top + 20, 0.0, 0.0))) {
      return true;
    }
  }
  for (const Band& band : chart.bands) {
    const double middle = 0.5 * (layout.ToPxX(band.x_min) + layout.ToPxX(band.x_max));
    if (!band.label.empty() && box.Overlaps(TextBox(cr, band.label, middle, layout.top + 4, 0.5, 0.0)))
      return true;
  }
  return false;
}

// The legend's size, and its place: a free corner of the plot area, or right of it (which narrows it).
void PlaceLegend(cairo_t* cr, const Chart& chart, ChartLayout& layout) {
  double text_width = 0.0;
  UseChartFont(cr, kFontSize);
  for (size_t s = 0; s < chart.series.size(); ++s) {
    if (chart.series[s].name.empty()) continue;
    layout.listed.push_back(s);
    cairo_text_extents_t extents;
    cairo_text_extents(cr, chart.series[s].name.c_str(), &extents);
    text_width = std::max(text_width, extents.x_advance);
  }
  if (layout.listed.empty()) return;
  const double w = text_width + kLegendSwatchPx + 20;
  const double h = kLegendRowPx * static_cast<double>(layout.listed.size()) + 8;
  if (chart.legend == LegendPlacement::kAuto) {
    const double near_x = layout.left + kLegendInsetPx;
    const double far_x = layout.right - kLegendInsetPx - w;
    const double near_y = layout.top + kLegendInsetPx;
    const double far_y = layout.bottom - kLegendInsetPx - h;
    for (const Box& corner : {Box{near_x, near_y, w, h}, Box{far_x, near_y, w, h}, Box{far_x, far_y, w, h},
                              Box{near_x, far_y, w, h}}) {
      const bool fits = corner.x >= layout.left && corner.y >= layout.top;
      if (fits && !CoversData(cr, chart, layout, corner)) {
        layout.legend = corner;
        return;
      }
    }
  }
  layout.right -= w + kLegendInsetPx;
  layout.legend = {layout.right + kLegendInsetPx, layout.top, w, h};
}

// Plot area, ranges and legend of `chart` in the rectangle (x0, y0, width, height) of the surface.
ChartLayout LayOutChart(cairo_t* cr, const Chart& chart, double x0, double y0, double width, double height) {
  ChartLayout layout;
  layout.x0 = x0;
  layout.y0 = y0;
  layout.width = width;
  layout.height = height;
  layout.left = x0 + kMarginLeft;
  layout.right = x0 + width - kMarginRight;
  layout.top = y0 + kMarginTop;
  layout.bottom = y0 + height - kMarginBottom;
  FitRanges(chart, layout.bottom - layout.top, layout);
  PlaceLegend(cr, chart, layout);
  return layout;
}

void DrawBands(cairo_t* cr, const Chart& chart, const ChartLayout& layout) {
  for (const Band& band : chart.bands) {
    const double a = layout.ToPxX(std::min(band.x_min, band.x_max));
    const double b = layout.ToPxX(std::max(band.x_min, band.x_max));
    cairo_set_source_rgba(cr, 0.2, 0.4, 0.9, 0.12);
    cairo_rectangle(cr, a, layout.top, b - a, layout.bottom - layout.top);
    cairo_fill(cr);
    if (!band.label.empty()) {
      cairo_set_source_rgb(cr, 0.15, 0.3, 0.7);
      ShowText(cr, band.label, 0.5 * (a + b), layout.top + 4, 0.5, 0.0);
    }
  }
}

void DrawTick(cairo_t* cr, double x0, double y0, double x1, double y1) {
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_move_to(cr, x0, y0);
  cairo_line_to(cr, x1, y1);
  cairo_stroke(cr);
}

void DrawGridLine(cairo_t* cr, double x0, double y0, double x1, double y1) {
  cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
  cairo_move_to(cr, x0, y0);
  cairo_line_to(cr, x1, y1);
  cairo_stroke(cr);
}

// Grid, ticks and their labels (numbers, or the bars' names under a categorical axis), the zero line,
// the frame, the axis labels and the title.
void DrawAxes(cairo_t* cr, const Chart& chart, const ChartLayout& layout) {
  cairo_set_line_width(cr, 1.0);
  if (chart.bars.empty()) {
    const std::vector<double> x_ticks = NiceTicks(layout.x_range.lo, layout.x_range.hi);
    const double x_step = x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : 1.0;
    for (double tick : x_ticks) {
      const double px = layout.ToPxX(tick);
      DrawGridLine(cr, px, layout.top, px, layout.bottom);
      DrawTick(cr, px, layout.bottom, px, layout.bottom + 5);
      ShowText(cr, FormatTick(tick, x_step), px, layout.bottom + 8, 0.5, 0.0);
    }
  } else {
    for (size_t k = 0; k < chart.bars.size(); ++k) {
      const double px = layout.ToPxX(k + 1.0);
      DrawTick(cr, px, layout.bottom, px, layout.bottom + 5);
      cairo_set_font_size(cr, FittingFontSize(cr, chart.bars[k].label, layout.SlotPx() - 4.0));
      ShowText(cr, chart.bars[k].label, px, layout.bottom + 8, 0.5, 0.0);
      cairo_set_font_size(cr, kFontSize);
    }
  }
  const std::vector<double> y_ticks = NiceTicks(layout.y_range.lo, layout.y_range.hi);
  const double y_step = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : 1.0;
  for (double tick : y_ticks) {
    const double py = layout.ToPxY(tick);
    DrawGridLine(cr, layout.left, py, layout.right, py);
    DrawTick(cr, layout.left - 5, py, layout.left, py);
    ShowText(cr, FormatTick(tick, y_step), layout.left - 8, py, 1.0, 0.5);
  }
  // Zero line when zero is inside the y range: strain plots change sign.
  if (layout.y_range.lo < 0.0 && layout.y_range.hi > 0.0) {
    cairo_set_source_rgb(cr, 0.55, 0.55, 0.55);
    cairo_move_to(cr, layout.left, layout.ToPxY(0.0));
    cairo_line_to(cr, layout.right, layout.ToPxY(0.0));
    cairo_stroke(cr);
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_rectangle(cr, layout.left, layout.top, layout.right - layout.left, layout.bottom - layout.top);
  cairo_stroke(cr);
  ShowText(cr, chart.x_label, 0.5 * (layout.left + layout.right), layout.y0 + layout.height - 6, 0.5, 1.0);
  ShowUpwardText(cr, chart.y_label, layout.x0 + 14, 0.5 * (layout.top + layout.bottom));
  cairo_set_font_size(cr, kTitleFontSize);
  ShowText(cr, chart.title, 0.5 * (layout.left + layout.right), layout.y0 + 10, 0.5, 0.0);
  cairo_set_font_size(cr, kFontSize);
}

void DrawMarkers(cairo_t* cr, const Chart& chart, const ChartLayout& layout) {
  for (const Marker& marker : chart.markers) {
    const double px = layout.ToPxX(marker.x);
    cairo_set_source_rgb(cr, 0.4, 0.4, 0.4);
    const double dash[] = {3.0, 3.0};
    cairo_set_dash(cr, dash, 2, 0);
    cairo_move_to(cr, px, layout.top);
    cairo_line_to(cr, px, layout.bottom);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
    if (!marker.label.empty()) ShowText(cr, marker.label, px + 3, layout.top + 20, 0.0, 0.0);
  }
}

// Filled bars with their values; where a value is missing, no bar but the chart's note (a missing
// figure drawn as 0 would read as a perfect score).
void DrawBars(cairo_t* cr, const Chart& chart, const ChartLayout& layout) {
  const double half = kBarHalfWidth * layout.SlotPx();
  for (size_t k = 0; k < chart.bars.size(); ++k) {
    const double centre = layout.ToPxX(k + 1.0);
    double size_px = kFontSize;
    if (!chart.bars[k].value) {
      const Box note = MissingNoteBox(cr, chart, layout, k, &size_px);
      UseChartFont(cr, size_px, /*italic=*/true);
      SetRgb(cr, kMissingNoteColour);
      ShowText(cr, chart.bars[k].missing_note, note.x, note.y, 0.0, 0.0);
      UseChartFont(cr, kFontSize);
      continue;
    }
    const double end = layout.ToPxY(*chart.bars[k].value);
    const double base = layout.ToPxY(0.0);
    const Colour colour = chart.bar_colour.value_or(PaletteColour(static_cast<int>(k)));
    cairo_set_source_rgb(cr, colour.r, colour.g, colour.b);
    cairo_rectangle(cr, centre - half, std::min(end, base), 2.0 * half, std::abs(base - end));
    cairo_fill(cr);
    const Box label = BarValueBox(cr, chart, layout, k, &size_px);
    cairo_set_source_rgb(cr, 0, 0, 0);
    ShowText(cr, BarValueText(chart, *chart.bars[k].value), label.x, label.y, 0.0, 0.0);
    cairo_set_font_size(cr, kFontSize);
  }
}

void DrawSeries(cairo_t* cr, const Chart& chart, const ChartLayout& layout) {
  const auto to_px_x = [&](double x) { return layout.ToPxX(x); };
  const auto to_px_y = [&](double y) { return layout.ToPxY(y); };
  for (size_t s = 0; s < chart.series.size(); ++s) {
    const Series& series = chart.series[s];
    SetRgb(cr, SeriesColour(chart, s));
    cairo_set_line_width(cr, 2.0);
    const double dash[] = {7.0, 4.0};
    cairo_set_dash(cr, dash, series.dashed ? 2 : 0, 0);
    AddPolyline(cr, series, to_px_x, to_px_y);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
    if (series.markers) {
      for (size_t i = 0; i < series.x.size(); ++i) {
        if (!std::isfinite(series.x[i]) || !std::isfinite(series.y[i])) continue;
        cairo_arc(cr, layout.ToPxX(series.x[i]), layout.ToPxY(series.y[i]), 3.0, 0, 2 * M_PI);
        cairo_fill(cr);
      }
    }
  }
}

void DrawLegend(cairo_t* cr, const Chart& chart, const ChartLayout& layout) {
  if (layout.listed.empty()) return;
  const Box& box = layout.legend;
  cairo_set_source_rgba(cr, 1, 1, 1, 0.85);
  cairo_rectangle(cr, box.x, box.y, box.w, box.h);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.6, 0.6, 0.6);
  cairo_set_line_width(cr, 1.0);
  cairo_stroke(cr);
  for (size_t row = 0; row < layout.listed.size(); ++row) {
    const Series& series = chart.series[layout.listed[row]];
    const double cy = box.y + 4 + kLegendRowPx * (static_cast<double>(row) + 0.5);
    SetRgb(cr, SeriesColour(chart, layout.listed[row]));
    cairo_set_line_width(cr, 2.0);
    const double dash[] = {7.0, 4.0};
    cairo_set_dash(cr, dash, series.dashed ? 2 : 0, 0);
    cairo_move_to(cr, box.x + 6, cy);
    cairo_line_to(cr, box.x + kLegendSwatchPx, cy);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
    cairo_set_source_rgb(cr, 0, 0, 0);
    ShowText(cr, series.name, box.x + kLegendSwatchPx + 8, cy, 0.0, 0.5);
  }
}

// Draws one chart into the rectangle (x0, y0, width, height) of the surface.
void DrawChart(cairo_t* cr, const Chart& chart, double x0, double y0, double width, double height) {
  UseChartFont(cr, kFontSize);
  const ChartLayout layout = LayOutChart(cr, chart, x0, y0, width, height);
  DrawBands(cr, chart, layout);
  DrawAxes(cr, chart, layout);
  // Data clipped to the plot area.
  cairo_save(cr);
  cairo_rectangle(cr, layout.left, layout.top, layout.right - layout.left, layout.bottom - layout.top);
  cairo_clip(cr);
  DrawMarkers(cr, chart, layout);
  DrawBars(cr, chart, layout);
  DrawSeries(cr, chart, layout);
  cairo_restore(cr);
  DrawLegend(cr, chart, layout);
}

struct SurfaceDeleter {
  void operator()(cairo_surface_t* surface) const { cairo_surface_destroy(surface); }
};
struct ContextDeleter {
  void operator()(cairo_t* cr) const { cairo_destroy(cr); }
};

// Renders with `draw` onto a white width x height image and writes it to `path` atomically.
template <typename DrawFn>
void Render(int width_px, int height_px, const std::string& path, DrawFn draw) {
  if (width_px <= 0 || height_px <= 0) {
    throw std::invalid_argument("plot: image size " + std::to_string(width_px) + "x" +
                                std::to_string(height_px) + " for " + path + ": must be positive");
  }
  std::unique_ptr<cairo_surface_t, SurfaceDeleter> surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_px, height_px));
  std::unique_ptr<cairo_t, ContextDeleter> cr(cairo_create(surface.get()));
  cairo_set_source_rgb(cr.get(), 1, 1, 1);
  cairo_paint(cr.get());
  draw(cr.get());
  cairo_surface_flush(surface.get());
  if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error("plot: drawing " + path +
                             " failed: " + cairo_status_to_string(cairo_status(cr.get())));
  }
  // CAIRO_FORMAT_RGB24: one native-endian uint32 per pixel, 0x00RRGGBB.
  image::RgbImage picture;
  picture.width_px = width_px;
  picture.height_px = height_px;
  picture.rgb.resize(static_cast<size_t>(width_px) * height_px * 3);
  const unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  uint8_t* out = picture.rgb.data();
  for (int row = 0; row < height_px; ++row) {
    const auto* in = reinterpret_cast<const uint32_t*>(data + static_cast<size_t>(row) * stride);
    for (int column = 0; column < width_px; ++column, out += 3) {
      out[0] = static_cast<uint8_t>(in[column] >> 16);
      out[1] = static_cast<uint8_t>(in[column] >> 8);
      out[2] = static_cast<uint8_t>(in[column]);
    }
  }
  image::WritePng(picture, path);
}

// ---- heat maps ------------------------------------------------------------------------------------

constexpr double kHeatmapMarginLeft = 150.0;   // row labels and the rotated row title
constexpr double kHeatmapMarginRight = 110.0;  // colour bar, its ticks and label
constexpr double kHeatmapMarginTop = 52.0;     // title and marker labels
constexpr double kHeatmapMarginBottom = 55.0;
constexpr double kColourBarWidth = 18.0;
constexpr Rgb kMissingColour{0.75, 0.75, 0.75};

struct HeatmapGeometry {
  double left, right, top, bottom;
  double x_lo, x_hi;
  int rows;
  double row_height() const { return (bottom - top) / std::max(1, rows); }
  double ToPxX(double x) const { return left + (x - x_lo) / (x_hi - x_lo) * (right - left); }
};

HeatmapGeometry GeometryOf(const Heatmap& heatmap) {
  HeatmapGeometry g;
  g.left = kHeatmapMarginLeft;
  g.right = heatmap.width_px - kHeatmapMarginRight;
  g.top = kHeatmapMarginTop;
  g.bottom = heatmap.height_px - kHeatmapMarginBottom;
  Range range;
  for (double x : heatmap.x) range.Add(x);
  range = Padded(range);
  g.x_lo = range.lo;
  g.x_hi = range.hi;
  g.rows = static_cast<int>(heatmap.values.size());
  return g;
}

void ValidateHeatmap(const Heatmap& heatmap, const std::string& path) {
  if (heatmap.width_px <= kHeatmapMarginLeft + kHeatmapMarginRight + 10 ||
      heatmap.height_px <= kHeatmapMarginTop + kHeatmapMarginBottom + 10) {
    throw std::invalid_argument("plot: heat map size " + std::to_string(heatmap.width_px) + "x" +
                                std::to_string(heatmap.height_px) + " for " + path +
                                ": too small for its margins");
  }
  if (heatmap.row_labels.size() != heatmap.values.size()) {
    throw std::invalid_argument("plot: heat map for " + path + " has " +
                                std::to_string(heatmap.values.size()) + " rows but " +
                                std::to_string(heatmap.row_labels.size()) + " row labels");
  }
  for (size_t row = 0; row < heatmap.values.size(); ++row) {
    if (heatmap.values[row].size() != heatmap.x.size()) {
      throw std::invalid_argument("plot: heat map row '" + heatmap.row_labels[row] + "' has " +
                                  std::to_string(heatmap.values[row].size()) + " values but there are " +
                                  std::to_string(heatmap.x.size()) + " x values");
    }
  }
  for (size_t i = 1; i < heatmap.x.size(); ++i) {
    if (!(heatmap.x[i] >= heatmap.x[i - 1])) {
      throw std::invalid_argument("plot: heat map x values for " + path + " must be increasing");
    }
  }
}

Rgb Interpolate(const Rgb* stops, size_t count, double t) {
  t = std::clamp(t, 0.0, 1.0) * static_cast<double>(count - 1);
  const size_t i = std::min(static_cast<size_t>(t), count - 2);
  const double f = t - static_cast<double>(i);
  return {stops[i].r + f * (stops[i + 1].r - stops[i].r), stops[i].g + f * (stops[i + 1].g - stops[i].g),
          stops[i].b + f * (stops[i + 1].b - stops[i].b)};
}

// White to dark red (ColorBrewer YlOrRd-like) for 0..1; blue-white-red (RdBu-like) for -1..1.
Rgb ColourOf(double value, double value_max, bool signed_scale) {
  static constexpr Rgb kSequential[] = {
      {1.00, 1.00, 1.00}, {1.00, 0.93, 0.63}, {0.99, 0.70, 0.30}, {0.94, 0.23, 0.13}, {0.50, 0.00, 0.15}};
  static constexpr Rgb kDiverging[] = {
      {0.02, 0.19, 0.38}, {0.26, 0.58, 0.76}, {1.00, 1.00, 1.00}, {0.84, 0.38, 0.30}, {0.40, 0.00, 0.12}};
  if (!std::isfinite(value)) return kMissingColour;
  if (signed_scale) return Interpolate(kDiverging, std::size(kDiverging), 0.5 + 0.5 * value / value_max);
  return Interpolate(kSequential, std::size(kSequential), value / value_max);
}

double ScaleOf(const Heatmap& heatmap) {
  if (heatmap.value_max > 0.0 && std::isfinite(heatmap.value_max)) return heatmap.value_max;
  double largest = 0.0;
  for (const std::vector<double>& row : heatmap.values) {
    for (double value : row) {
      if (std::isfinite(value)) largest = std::max(largest, heatmap.signed_scale ? std::abs(value) : value);
    }
  }
  return largest > 0.0 ? largest : 1.0;
}

// The value one pixel column of a row shows: the mean of its finite samples (samples [*first, end)
// fall in it; *first moves on to end), the nearest sample when none falls in it, NaN when all are missing.
double ColumnValue(const Heatmap& heatmap, const HeatmapGeometry& g, int row, int column, int columns,
                   size_t* first) {
  const std::vector<double>& x = heatmap.x;
  const std::vector<double>& values = heatmap.values[static_cast<size_t>(row)];
  const double bin_hi = g.x_lo + (g.x_hi - g.x_lo) * (column + 1) / columns;
  size_t end = *first;
  while (end < x.size() && (x[end] < bin_hi || column == columns - 1)) ++end;
  double sum = 0.0;
  int count = 0;
  bool missing = false;
  for (size_t i = *first; i < end; ++i) {
    if (std::isfinite(values[i])) {
      sum += values[i];
      ++count;
    } else {
      missing = true;
    }
  }
  double value = std::numeric_limits<double>::quiet_NaN();
  if (count > 0) {
    value = sum / count;
  } else if (!missing && !x.empty()) {
    // No sample in this pixel column (sparse data): the nearest one.
    const double centre = g.x_lo + (g.x_hi - g.x_lo) * (column + 0.5) / columns;
    const size_t after = std::min(*first, x.size() - 1);
    const size_t before = after > 0 ? after - 1 : 0;
    value = values[std::abs(x[before] - centre) <= std::abs(x[after] - centre) ? before : after];
  }
  *first = end;
  return value;
}

// Cells: one image pixel per (row, pixel column), scaled up without smoothing.
void DrawHeatmapCells(cairo_t* cr, const Heatmap& heatmap, const HeatmapGeometry& g, double scale) {
  const int columns = std::max(1, static_cast<int>(std::lround(g.right - g.left)));
  const int rows = std::max(1, g.rows);
  std::unique_ptr<cairo_surface_t, void (*)(cairo_surface_t*)> cells(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, columns, rows), cairo_surface_destroy);
  cairo_surface_flush(cells.get());
  unsigned char* data = cairo_image_surface_get_data(cells.get());
  const int stride = cairo_image_surface_get_stride(cells.get());
  const auto channel = [](double c) {
    return static_cast<uint32_t>(std::lround(std::clamp(c, 0.0, 1.0) * 255.0));
  };
  for (int row = 0; row < g.rows; ++row) {
    size_t first = 0;
    for (int column = 0; column < columns; ++column) {
      const Rgb colour =
          ColourOf(ColumnValue(heatmap, g, row, column, columns, &first), scale, heatmap.signed_scale);
      *reinterpret_cast<uint32_t*>(data + row * stride + 4 * column) =
          (channel(colour.r) << 16) | (channel(colour.g) << 8) | channel(colour.b);
    }
  }
  cairo_surface_mark_dirty(cells.get());
  cairo_save(cr);
  cairo_translate(cr, g.left, g.top);
  cairo_scale(cr, (g.right - g.left) / columns, (g.bottom - g.top) / rows);
  cairo_set_source_surface(cr, cells.get(), 0, 0);
  cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
  cairo_rectangle(cr, 0, 0, columns, rows);
  cairo_fill(cr);
  cairo_restore(cr);
}

// Thin separators between rows, so neighbouring units stay apart.
void DrawRowSeparators(cairo_t* cr, const HeatmapGeometry& g) {
  cairo_set_line_width(cr, 1.0);
  cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
  for (int row = 1; row < g.rows; ++row) {
    const double y = std::round(g.top + row * g.row_height()) + 0.5;
    cairo_move_to(cr, g.left, y);
    cairo_line_to(cr, g.right, y);
    cairo_stroke(cr);
  }
}

// Frame, x ticks, row labels (every k-th when rows are thin).
void DrawHeatmapAxes(cairo_t* cr, const Heatmap& heatmap, const HeatmapGeometry& g) {
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_rectangle(cr, g.left, g.top, g.right - g.left, g.bottom - g.top);
  cairo_stroke(cr);
  cairo_set_font_size(cr, kFontSize);
  const std::vector<double> x_ticks = NiceTicks(g.x_lo, g.x_hi);
  const double x_step = x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : 1.0;
  for (double tick : x_ticks) {
    const double px = g.ToPxX(tick);
    cairo_move_to(cr, px, g.bottom);
    cairo_line_to(cr, px, g.bottom + 5);
    cairo_stroke(cr);
    ShowText(cr, FormatTick(tick, x_step), px, g.bottom + 8, 0.5, 0.0);
  }
  ShowText(cr, heatmap.x_label, 0.5 * (g.left + g.right), heatmap.height_px - 6, 0.5, 1.0);
  const double label_size = std::clamp(g.row_height() * 0.8, 7.0, kFontSize);
  cairo_set_font_size(cr, label_size);
  const int label_every = std::max(1, static_cast<int>(std::ceil((label_size + 2.0) / g.row_height())));
  for (int row = 0; row < g.rows; row += label_every) {
    ShowText(cr, heatmap.row_labels[static_cast<size_t>(row)], g.left - 6,
             g.top + (row + 0.5) * g.row_height(), 1.0, 0.5);
  }
  cairo_set_font_size(cr, kFontSize);
  ShowUpwardText(cr, heatmap.row_label, 14, 0.5 * (g.top + g.bottom));
}

// Markers: dashed lines over the cells, labels above them.
void DrawHeatmapMarkers(cairo_t* cr, const Heatmap& heatmap, const HeatmapGeometry& g) {
  for (const Marker& marker : heatmap.markers) {
    if (!(marker.x >= g.x_lo && marker.x <= g.x_hi)) continue;
    const double px = g.ToPxX(marker.x);
    const double dash[] = {4.0, 3.0};
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    cairo_set_dash(cr, dash, 2, 0);
    cairo_move_to(cr, px, g.top);
    cairo_line_to(cr, px, g.bottom);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
    if (!marker.label.empty()) ShowText(cr, marker.label, px, g.top - 3, 0.0, 1.0);
  }
}

// Colour bar with its scale.
void DrawColourBar(cairo_t* cr, const Heatmap& heatmap, const HeatmapGeometry& g, double scale) {
  const double bar_left = g.right + 16;
  const double value_lo = heatmap.signed_scale ? -scale : 0.0;
  const auto bar_y = [&](double value) {
    return g.bottom - (value - value_lo) / (scale - value_lo) * (g.bottom - g.top);
  };
  for (int py = static_cast<int>(g.top); py < static_cast<int>(g.bottom); ++py) {
    const double value = value_lo + (g.bottom - (py + 0.5)) / (g.bottom - g.top) * (scale - value_lo);
    const Rgb colour = ColourOf(value, scale, heatmap.signed_scale);
    cairo_set_source_rgb(cr, colour.r, colour.g, colour.b);
    cairo_rectangle(cr, bar_left, py, kColourBarWidth, 1.0);
    cairo_fill(cr);
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_rectangle(cr, bar_left, g.top, kColourBarWidth, g.bottom - g.top);
  cairo_stroke(cr);
  const std::vector<double> value_ticks = NiceTicks(value_lo, scale, 5);
  const double value_step = value_ticks.size() > 1 ? value_ticks[1] - value_ticks[0] : 1.0;
  for (double tick : value_ticks) {
    const double py = bar_y(tick);
    cairo_move_to(cr, bar_left + kColourBarWidth, py);
    cairo_line_to(cr, bar_left + kColourBarWidth + 4, py);
    cairo_stroke(cr);
    ShowText(cr, FormatTick(tick, value_step), bar_left + kColourBarWidth + 6, py, 0.0, 0.5);
  }
  ShowUpwardText(cr, heatmap.value_label, heatmap.width_px - 12, 0.5 * (g.top + g.bottom));
}

void DrawHeatmap(cairo_t* cr, const Heatmap& heatmap) {
  const HeatmapGeometry g = GeometryOf(heatmap);
  const double scale = ScaleOf(heatmap);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  DrawHeatmapCells(cr, heatmap, g, scale);
  DrawRowSeparators(cr, g);
  DrawHeatmapAxes(cr, heatmap, g);
  DrawHeatmapMarkers(cr, heatmap, g);
  DrawColourBar(cr, heatmap, g, scale);
  cairo_set_font_size(cr, kTitleFontSize);
  ShowText(cr, heatmap.title, 0.5 * heatmap.width_px, 8.0, 0.5, 0.0);
}

}  // namespace

void WritePng(const Heatmap& heatmap, const std::string& path) {
  ValidateHeatmap(heatmap, path);
  Render(heatmap.width_px, heatmap.height_px, path, [&](cairo_t* cr) { DrawHeatmap(cr, heatmap); });
}

std::pair<double, double> HeatmapCellCenterPx(const Heatmap& heatmap, int row, double x) {
  const HeatmapGeometry g = GeometryOf(heatmap);
  return {g.ToPxX(x), g.top + (row + 0.5) * g.row_height()};
}

std::vector<double> NiceTicks(double lo, double hi, int target_count) {
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return {lo};
  const double raw_step = (hi - lo) / std::max(1, target_count);
  const double power = std::pow(10.0, std::floor(std::log10(raw_step)));
  double step = power;
  for (double factor : {1.0, 2.0, 5.0, 10.0}) {
    step = factor * power;
    if (step >= raw_step) break;
  }
  std::vector<double> ticks;
  const double first = std::ceil(lo / step - 1e-9) * step;
  for (double tick = first; tick <= hi + 1e-9 * step; tick += step) ticks.push_back(tick);
  return ticks;
}

void WritePng(const Chart& chart, const std::string& path, int width_px, int height_px) {
  ValidateChart(chart);
  Render(width_px, height_px, path,
         [&](cairo_t* cr) { DrawChart(cr, chart, 0.0, 0.0, width_px, height_px); });
}

namespace {

// A figure's grid of panels: its size and where each panel's rectangle starts [px].
struct FigureGeometry {
  int columns = 1;
  int title_px = 0;
  int width = 0;
  int height = 0;
  std::pair<double, double> PanelOrigin(const Figure& figure, size_t i) const {
    const int row = static_cast<int>(i) / columns;
    const int column = static_cast<int>(i) % columns;
    return {static_cast<double>(column * figure.panel_width_px),
            static_cast<double>(title_px + row * figure.panel_height_px)};
  }
};

FigureGeometry GeometryOf(const Figure& figure) {
  FigureGeometry g;
  const int count = std::max<int>(1, static_cast<int>(figure.panels.size()));
  g.columns = std::min(std::max(1, figure.columns), count);
  const int rows = (count + g.columns - 1) / g.columns;
  g.title_px = figure.title.empty() ? 0 : 34;
  g.width = g.columns * figure.panel_width_px;
  g.height = rows * figure.panel_height_px + g.title_px;
  return g;
}

}  // namespace

void WritePng(const Figure& figure, const std::string& path) {
  for (const Chart& chart : figure.panels) ValidateChart(chart);
  if (figure.columns <= 0) {
    throw std::invalid_argument("plot: figure for " + path + " has " + std::to_string(figure.columns) +
                                " columns: must be positive");
  }
  if (figure.panel_width_px <= 0 || figure.panel_height_px <= 0) {
    throw std::invalid_argument("plot: panel size for " + path + " must be positive");
  }
  const FigureGeometry g = GeometryOf(figure);
  Render(g.width, g.height, path, [&](cairo_t* cr) {
    if (!figure.title.empty()) {
      cairo_set_source_rgb(cr, 0, 0, 0);
      cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
      cairo_set_font_size(cr, 17.0);
      ShowText(cr, figure.title, 0.5 * g.width, 8.0, 0.5, 0.0);
    }
    for (size_t i = 0; i < figure.panels.size(); ++i) {
      const auto [x0, y0] = g.PanelOrigin(figure, i);
      DrawChart(cr, figure.panels[i], x0, y0, figure.panel_width_px, figure.panel_height_px);
    }
  });
}

std::pair<double, double> ChartPointPx(const Figure& figure, size_t panel, double x, double y) {
  const Chart& chart = figure.panels.at(panel);
  const FigureGeometry g = GeometryOf(figure);
  const auto [x0, y0] = g.PanelOrigin(figure, panel);
  // The layout measures texts (the legend's width decides whether it fits inside): a scratch surface.
  std::unique_ptr<cairo_surface_t, SurfaceDeleter> surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1));
  std::unique_ptr<cairo_t, ContextDeleter> cr(cairo_create(surface.get()));
  UseChartFont(cr.get(), kFontSize);
  const ChartLayout layout =
      LayOutChart(cr.get(), chart, x0, y0, figure.panel_width_px, figure.panel_height_px);
  return {layout.ToPxX(x), layout.ToPxY(y)};
}

Colour PaletteColour(int index) {
  const int size = static_cast<int>(kPalette.size());
  const Rgb& colour = kPalette[static_cast<size_t>(((index % size) + size) % size)];
  return {colour.r, colour.g, colour.b};
}

namespace {

// ---- scale drawings -------------------------------------------------------------------------------

constexpr double kDrawingMarginLeft = 80.0;
constexpr double kDrawingMarginRight = 30.0;
constexpr double kDrawingMarginTop = 48.0;
constexpr double kDrawingMarginBottom = 55.0;
constexpr double kDrawingNoteLinePx = 19.0;

// Where a Drawing's data lands in its image: one scale for both axes, the narrower range centred.
struct DrawingGeometry {
  double left, right, top, bottom;  // plot area [px]
  double x_lo, y_lo;                // data at the bottom-left corner (bottom-right when x is reversed)
  double scale;                     // px per data unit
  bool x_reversed;
  double ToPxX(double x) const { return x_reversed ? right - (x - x_lo) * scale : left + (x - x_lo) * scale; }
  double ToPxY(double y) const { return bottom - (y - y_lo) * scale; }
};

DrawingGeometry GeometryOf(const Drawing& drawing) {
  DrawingGeometry g;
  g.left = kDrawingMarginLeft;
  g.right = drawing.width_px - kDrawingMarginRight;
  g.top = kDrawingMarginTop;
  g.bottom = drawing.height_px - kDrawingMarginBottom - kDrawingNoteLinePx * drawing.notes.size();
  g.x_reversed = drawing.x_reversed;
  const double x_span = drawing.x_max - drawing.x_min;
  const double y_span = drawing.y_max - drawing.y_min;
  g.scale = std::min((g.right - g.left) / x_span, (g.bottom - g.top) / y_span);
  g.x_lo = 0.5 * (drawing.x_min + drawing.x_max) - 0.5 * (g.right - g.left) / g.scale;
  g.y_lo = 0.5 * (drawing.y_min + drawing.y_max) - 0.5 * (g.bottom - g.top) / g.scale;
  return g;
}

void ValidateDrawing(const Drawing& drawing, const std::string& path) {
  const auto bad = [&](const std::string& what) {
    throw std::invalid_argument("plot: drawing for " + path + ": " + what);
  };
  if (!(drawing.x_min < drawing.x_max) || !(drawing.y_min < drawing.y_max)) bad("empty or inverted range");
  if (drawing.width_px <= kDrawingMarginLeft + kDrawingMarginRight + 10) bad("width too small");
  if (drawing.height_px <= kDrawingMarginTop + kDrawingMarginBottom + 10 + kDrawingNoteLinePx * drawing.notes.size())
    bad("height too small for its notes");
  for (const Shape& shape : drawing.shapes) {
    if (shape.points.empty()) bad("a shape with no vertex");
  }
}

void SetColour(cairo_t* cr, const Colour& colour) { cairo_set_source_rgb(cr, colour.r, colour.g, colour.b); }

void DrawShape(cairo_t* cr, const DrawingGeometry& g, const Shape& shape) {
  cairo_new_path(cr);
  for (const auto& [x, y] : shape.points) cairo_line_to(cr, g.ToPxX(x), g.ToPxY(y));
  if (shape.closed) cairo_close_path(cr);
  if (shape.filled && shape.closed) {
    SetColour(cr, shape.fill);
    cairo_fill_preserve(cr);
  }
  if (shape.line_width_px > 0.0) {
    SetColour(cr, shape.stroke);
    cairo_set_line_width(cr, shape.line_width_px);
    const double dash[] = {6.0, 4.0};
    cairo_set_dash(cr, dash, shape.dashed ? 2 : 0, 0.0);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
  }
  cairo_new_path(cr);
  if (shape.arrow_head && !shape.closed && shape.points.size() >= 2) {
    const auto& [x1, y1] = shape.points[shape.points.size() - 2];
    const auto& [x2, y2] = shape.points.back();
    const double tip_x = g.ToPxX(x2);
    const double tip_y = g.ToPxY(y2);
    const double angle = std::atan2(tip_y - g.ToPxY(y1), tip_x - g.ToPxX(x1));
    const double length = 4.0 + 3.0 * shape.line_width_px;
    SetColour(cr, shape.stroke);
    cairo_move_to(cr, tip_x, tip_y);
    cairo_line_to(cr, tip_x - length * std::cos(angle - 0.45), tip_y - length * std::sin(angle - 0.45));
    cairo_line_to(cr, tip_x - length * std::cos(angle + 0.45), tip_y - length * std::sin(angle + 0.45));
    cairo_close_path(cr);
    cairo_fill(cr);
  }
}

void DrawDrawing(cairo_t* cr, const Drawing& drawing) {
  const DrawingGeometry g = GeometryOf(drawing);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, kFontSize);
  // Frame and ticks of the whole plot area (the narrower range was widened to keep one scale).
  const double x_hi = g.x_lo + (g.right - g.left) / g.scale;
  const double y_hi = g.y_lo + (g.bottom - g.top) / g.scale;
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, g.left, g.top, g.right - g.left, g.bottom - g.top);
  cairo_stroke(cr);
  const std::vector<double> x_ticks = NiceTicks(g.x_lo, x_hi, 10);
  const std::vector<double> y_ticks = NiceTicks(g.y_lo, y_hi, 8);
  const double x_step = x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : 1.0;
  const double y_step = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : 1.0;
  for (double tick : x_ticks) {
    cairo_move_to(cr, g.ToPxX(tick), g.bottom);
    cairo_line_to(cr, g.ToPxX(tick), g.bottom + 5);
    cairo_stroke(cr);
    ShowText(cr, FormatTick(tick, x_step), g.ToPxX(tick), g.bottom + 8, 0.5, 0.0);
  }
  for (double tick : y_ticks) {
    cairo_move_to(cr, g.left - 5, g.ToPxY(tick));
    cairo_line_to(cr, g.left, g.ToPxY(tick));
    cairo_stroke(cr);
    ShowText(cr, FormatTick(tick, y_step), g.left - 8, g.ToPxY(tick), 1.0, 0.5);
  }
  ShowText(cr, drawing.x_label, 0.5 * (g.left + g.right), g.bottom + 28, 0.5, 0.0);
  ShowUpwardText(cr, drawing.y_label, 18, 0.5 * (g.top + g.bottom));
  for (size_t i = 0; i < drawing.notes.size(); ++i) {
    ShowText(cr, drawing.notes[i], g.left, g.bottom + 52 + kDrawingNoteLinePx * i, 0.0, 0.0);
  }
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
  cairo_set_font_size(cr, kTitleFontSize);
  ShowText(cr, drawing.title, 0.5 * drawing.width_px, 12.0, 0.5, 0.0);

  cairo_save(cr);
  cairo_rectangle(cr, g.left, g.top, g.right - g.left, g.bottom - g.top);
  cairo_clip(cr);
  for (const Shape& shape : drawing.shapes) DrawShape(cr, g, shape);
  for (const Text& text : drawing.texts) {
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           text.bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, text.size_px);
    SetColour(cr, text.colour);
    ShowText(cr, text.text, g.ToPxX(text.x), g.ToPxY(text.y), text.align_x, text.align_y);
  }
  cairo_restore(cr);
}

}  // namespace

void WritePng(const Drawing& drawing, const std::string& path) {
  ValidateDrawing(drawing, path);
  Render(drawing.width_px, drawing.height_px, path, [&](cairo_t* cr) { DrawDrawing(cr, drawing); });
}

std::pair<double, double> DrawingPointPx(const Drawing& drawing, double x, double y) {
  const DrawingGeometry g = GeometryOf(drawing);
  return {g.ToPxX(x), g.ToPxY(y)};
}

}  // namespace graspbed::plot
