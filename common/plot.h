#pragma once
/// Small PNG chart writer (cairo): named series, axes with ticks and labels, a title, a legend that
/// never covers data, optional vertical markers and shaded x-bands, or bar charts over named categories;
/// several charts can share one image as panels. Also
/// heat maps (rows x time colour maps with a colour bar) and scale drawings (polygons, arrows and texts in
/// data units, e.g. a sensor layout in millimetres).
/// Files are written atomically (temporary file + rename), so a reader never sees half a PNG.

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace graspbed::plot {

/// A colour, each channel 0..1.
struct Colour {
  double r = 0.0;
  double g = 0.0;
  double b = 0.0;
};

/// Number of distinct colours charts give their series before they repeat (an Okabe-Ito palette).
inline constexpr int kPaletteSize = 8;

/// The `index`-th colour of the charts' palette (index modulo kPaletteSize): the colour a series
/// without its own colour gets from its position in Chart::series, and bar `index` of a bar chart.
Colour PaletteColour(int index);

/// One named line. x and y have the same length; non-finite points break the line.
struct Series {
  std::string name;       ///< legend text; empty = not listed in the legend
  std::vector<double> x;  ///< abscissae, in the chart's x unit
  std::vector<double> y;  ///< ordinates, in the chart's y unit
  bool dashed = false;    ///< draw dashed instead of solid
  bool markers = false;   ///< draw a small dot at every point
  std::optional<Colour> colour =
      std::nullopt;  ///< nullopt: the palette colour of the series' position in the chart
};

/// A vertical line across the plot area at `x`, labelled at its top.
struct Marker {
  double x = 0.0;
  std::string label;
};

/// A shaded vertical band between x_min and x_max (e.g. where a resistor sits), labelled at its top.
struct Band {
  double x_min = 0.0;
  double x_max = 0.0;
  std::string label;
};

/// One bar of a bar chart: a named category on the x axis and its value.
struct Bar {
  std::string label;  ///< the category's name, written under the axis (e.g. a controller)
  std::optional<double> value =
      std::nullopt;  ///< height [chart's y unit]; nullopt: no value (no bar: missing_note)
  /// Written where the bar would stand when it has no value: why there is none (e.g. "no events").
  std::string missing_note = "no value";
};

/// Where a chart's legend (one line per named series) goes; it never covers data.
enum class LegendPlacement {
  kAuto,     ///< inside the plot area, in the first corner (top left, top right, bottom right, bottom
             ///< left) where it covers no line, dot, bar or marker label; right of the plot area when none
  kOutside,  ///< right of the plot area, which narrows to make room
};

/// One chart: axes, series and decorations. Axis ranges come from the data unless fixed here.
/// A chart with bars is a bar chart: its x axis is categorical, bar k (0-based) centred on x = k + 1
/// and named by its label; each bar is filled (in PaletteColour(k) unless bar_colour is set) and has its
/// value written above it.
/// Series, markers and bands may be added in the same x coordinates.
struct Chart {
  std::string title;
  std::string x_label;  ///< with its unit, e.g. "x [mm]"; for bars, what the categories are
  std::string y_label;  ///< with its unit
  std::vector<Series> series;
  std::vector<Marker> markers;
  std::vector<Band> bands;
  std::vector<Bar> bars;
  std::string bar_value_format = "%.3g";  ///< printf format of a bar's value, e.g. "%.1f ms"
  std::optional<Colour> bar_colour =
      std::nullopt;             ///< one colour for every bar; nullopt: PaletteColour(k) for bar k
  bool include_zero_y = false;  ///< stretch the y range to contain 0 (bar charts always do)
  LegendPlacement legend = LegendPlacement::kAuto;
};

/// Several charts laid out in a grid of `columns` columns, row by row, with an optional overall title.
struct Figure {
  std::string title;
  std::vector<Chart> panels;
  int columns = 1;
  int panel_width_px = 800;   ///< size of one panel [px]
  int panel_height_px = 500;  ///< size of one panel [px]
};

/// A rows x x colour map ("heat map"): one row per channel (e.g. a sensing unit, top to bottom), the
/// colour of a cell the channel's value there, a colour bar with its scale, optional markers.
struct Heatmap {
  std::string title;
  std::string x_label;                      ///< with its unit, e.g. "time [s]"
  std::string row_label;                    ///< what the rows are, e.g. "unit (row, column)"
  std::string value_label;                  ///< colour bar label with its unit, e.g. "Fn [N]"
  std::vector<std::string> row_labels;      ///< one per row, top to bottom
  std::vector<double> x;                    ///< sample abscissae shared by all rows, increasing
  std::vector<std::vector<double>> values;  ///< values[row][sample]; non-finite cells are grey
  /// false: sequential scale from white at 0 to dark red at value_max (values below 0 as 0);
  /// true: signed scale, blue at -value_max, white at 0, red at +value_max.
  bool signed_scale = false;
  double value_max = 0.0;  ///< end of the colour scale; <= 0: the largest |value| in the data
  std::vector<Marker> markers;
  int width_px = 1000;  ///< image size [px]
  int height_px = 600;
};

/// Writes `heatmap` as a PNG at `path` (temp file + rename). Each pixel column shows the mean of the
/// samples that fall in it (the nearest sample when none does). Throws std::invalid_argument for a
/// row count that does not match the labels, a row whose length differs from x, decreasing x or a
/// non-positive size; std::runtime_error when the file cannot be written (naming the path).
void WritePng(const Heatmap& heatmap, const std::string& path);

/// Centre of the cell of row `row` at abscissa `x` in the image WritePng(heatmap) draws [px]
/// (first: column from the left, second: row from the top). For tests that read the image back.
std::pair<double, double> HeatmapCellCenterPx(const Heatmap& heatmap, int row, double x);

/// Writes `chart` as a width x height PNG at `path` (temp file + rename). Throws std::invalid_argument
/// for mismatched series lengths or a non-positive size, std::runtime_error when the file cannot be
/// written (naming the path).
void WritePng(const Chart& chart, const std::string& path, int width_px = 800, int height_px = 500);

/// Writes a multi-panel figure as one PNG at `path` (temp file + rename); same errors as above.
void WritePng(const Figure& figure, const std::string& path);

/// The pixel (column from the left, row from the top) where WritePng(figure) puts the data point
/// (x, y) of panel `panel` (bar k of a bar chart stands at x = k + 1). For tests that read the image
/// back. Throws std::out_of_range for a panel the figure does not have.
std::pair<double, double> ChartPointPx(const Figure& figure, size_t panel, double x, double y);

/// A polygon or polyline of a Drawing, in its data units.
struct Shape {
  std::vector<std::pair<double, double>> points;  ///< vertices (x, y) [data units]
  bool closed = true;                             ///< join the last vertex to the first
  bool filled = false;                            ///< fill with `fill` (closed shapes only)
  Colour fill;                                    ///< fill colour
  Colour stroke;                                  ///< outline colour
  double line_width_px = 1.0;                     ///< outline width [px]; 0: no outline
  bool dashed = false;                            ///< dashed outline
  bool arrow_head = false;                        ///< an arrow head at the last vertex (open shapes)
};

/// A text of a Drawing, anchored at a point in data units.
struct Text {
  double x = 0.0;  ///< anchor [data units]
  double y = 0.0;  ///< anchor [data units]
  std::string text;
  double size_px = 13.0;  ///< font size [px]
  bool bold = false;
  Colour colour;
  double align_x = 0.5;  ///< 0: anchor at the text's left, 0.5 centre, 1 right
  double align_y = 0.5;  ///< 0: anchor at the text's top, 0.5 middle, 1 bottom
};

/// A scale drawing: shapes and texts in data units (e.g. mm) with one scale on both axes, framed by
/// axes with ticks, under a title and optional notes (one line each, below the plot area).
struct Drawing {
  std::string title;
  std::vector<std::string> notes;  ///< lines of text under the drawing
  std::string x_label;             ///< with its unit
  std::string y_label;             ///< with its unit
  double x_min = 0.0;              ///< the data range shown [data units]; the wider of the two
  double x_max = 1.0;              ///< ranges decides the scale, the other is centred
  double y_min = 0.0;
  double y_max = 1.0;
  bool x_reversed = false;    ///< x grows to the left (e.g. to show a surface as seen from its other side)
  std::vector<Shape> shapes;  ///< drawn in order, under the texts
  std::vector<Text> texts;
  int width_px = 1000;  ///< image size [px]
  int height_px = 700;
};

/// Writes `drawing` as a PNG at `path` (temp file + rename). Throws std::invalid_argument for an
/// empty or inverted range, a shape with no vertex or a non-positive size; std::runtime_error when
/// the file cannot be written (naming the path).
void WritePng(const Drawing& drawing, const std::string& path);

/// The pixel (column from the left, row from the top) where WritePng(drawing) puts the data point
/// (x, y). For tests that read the image back.
std::pair<double, double> DrawingPointPx(const Drawing& drawing, double x, double y);

/// "Nice" tick positions (steps of 1, 2 or 5 times a power of ten) covering [lo, hi], about
/// `target_count` of them. Exposed for tests.
std::vector<double> NiceTicks(double lo, double hi, int target_count = 6);

}  // namespace graspbed::plot
