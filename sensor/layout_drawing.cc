#include "sensor/layout_drawing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace graspbed::sensor {
namespace {

constexpr double kMmPerM = 1e3;
constexpr plot::Colour kBlack{0.0, 0.0, 0.0};
constexpr plot::Colour kGrey{0.45, 0.45, 0.45};
constexpr plot::Colour kHolderFill{0.93, 0.93, 0.93};
constexpr plot::Colour kWhite{1.0, 1.0, 1.0};

/// A rectangle centred on (x, y) [mm], `along` long in the direction (dx, dy) and `across` wide.
plot::Shape Rectangle(double x, double y, double dx, double dy, double along, double across) {
  const double ax = 0.5 * along * dx, ay = 0.5 * along * dy;      // half the length, along
  const double cx = -0.5 * across * dy, cy = 0.5 * across * dx;   // half the width, across
  plot::Shape shape;
  shape.points = {{x - ax - cx, y - ay - cy}, {x + ax - cx, y + ay - cy}, {x + ax + cx, y + ay + cy},
                  {x - ax + cx, y - ay + cy}};
  return shape;
}

plot::Text Label(double x, double y, std::string text, double size_px, plot::Colour colour = kBlack) {
  plot::Text label;
  label.x = x;
  label.y = y;
  label.text = std::move(text);
  label.size_px = size_px;
  label.colour = colour;
  return label;
}

std::string Millimetres(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", std::round(metres * kMmPerM * 100.0) / 100.0);
  return text;
}

}  // namespace

plot::Drawing LayoutDrawing(const Layout& layout) {
  const double half_length_mm = 0.5 * layout.holder.length_m * kMmPerM;
  const double half_arc_mm = PalmarHalfArcLengthM(layout.holder) * kMmPerM;
  plot::Drawing drawing;
  drawing.title = "layout " + layout.name + ": " + std::to_string(layout.unit_count()) +
                  " units on the holder's palmar surface, unrolled, seen from the palm";
  drawing.x_label = "x, along the holder axis [mm] (distal, the fingertip, to the left)";
  drawing.y_label = "arc length from the palmar midline [mm] (+y up)";
  drawing.x_reversed = true;
  drawing.x_min = -half_length_mm - 1.0;
  drawing.x_max = half_length_mm + 5.0;  // room for the column names beyond the distal edge (the left)
  drawing.y_min = -half_arc_mm - 1.0;
  drawing.y_max = half_arc_mm + 3.0;     // room for the row names
  drawing.width_px = 1100;
  drawing.height_px = 880;

  plot::Shape holder = Rectangle(0.0, 0.0, 1.0, 0.0, 2.0 * half_length_mm, 2.0 * half_arc_mm);
  holder.filled = true;
  holder.fill = kHolderFill;
  holder.stroke = kGrey;
  drawing.shapes.push_back(holder);
  plot::Shape midline;
  midline.points = {{-half_length_mm, 0.0}, {half_length_mm, 0.0}};
  midline.closed = false;
  midline.dashed = true;
  midline.stroke = kGrey;
  drawing.shapes.push_back(midline);
  drawing.texts.push_back(Label(-half_length_mm + 0.3, 0.15, "palmar midline", 12.0, kGrey));
  drawing.texts.back().align_x = 1.0;  // ends at the holder's proximal edge (the right: x is reversed)
  drawing.texts.back().align_y = 1.0;

  const UnitGeometry& unit = layout.unit;
  std::map<int, std::pair<double, int>> row_x_mm, column_arc_mm;  // index -> (sum, count)
  for (int i = 0; i < layout.unit_count(); ++i) {
    const UnitPose& pose = layout.units[static_cast<size_t>(i)];
    const double x = pose.axial_position_m * kMmPerM;
    const double y = pose.arc_position_m * kMmPerM;
    const bool axial = pose.orientation == BeamOrientation::kAxial;
    // +Ft's sense along the beam, in the unrolled plane: +x, or +arc where the surface's
    // circumferential tangent (towards +y at the midline) points the same way as the beam axis.
    const HolderSurfacePoint point = HolderPointAtArc(layout.holder, pose.axial_position_m, pose.arc_position_m);
    const double sense = axial ? (pose.beam_axis.x() >= 0.0 ? 1.0 : -1.0)
                               : (pose.beam_axis.dot(point.circumferential_tangent) >= 0.0 ? 1.0 : -1.0);
    const double dx = axial ? sense : 0.0;
    const double dy = axial ? 0.0 : sense;

    plot::Shape beam = Rectangle(x, y, dx, dy, unit.beam_length_m * kMmPerM, unit.beam_width_m * kMmPerM);
    beam.stroke = kGrey;
    drawing.shapes.push_back(beam);
    plot::Shape mesa = Rectangle(x, y, dx, dy, unit.mesa_length_m * kMmPerM, unit.mesa_width_m * kMmPerM);
    mesa.filled = true;
    mesa.fill = axial ? kAxialBeamColour : kCircumferentialBeamColour;
    mesa.line_width_px = 0.0;
    drawing.shapes.push_back(mesa);
    const double from = 0.5 * unit.mesa_length_m * kMmPerM;
    const double to = 0.5 * unit.beam_length_m * kMmPerM + 0.9;
    plot::Shape arrow;
    arrow.points = {{x + from * dx, y + from * dy}, {x + to * dx, y + to * dy}};
    arrow.closed = false;
    arrow.arrow_head = true;
    arrow.line_width_px = 1.5;
    drawing.shapes.push_back(arrow);
    plot::Text number = Label(x, y, std::to_string(i), 15.0, kWhite);
    number.bold = true;
    drawing.texts.push_back(number);

    auto& row = row_x_mm[pose.row];
    row.first += x;
    ++row.second;
    auto& column = column_arc_mm[pose.column];
    column.first += y;
    ++column.second;
  }
  for (const auto& [row, sum] : row_x_mm) {
    drawing.texts.push_back(Label(sum.first / sum.second, half_arc_mm + 1.6, "row " + std::to_string(row), 13.0));
  }
  for (const auto& [column, sum] : column_arc_mm) {
    plot::Text name = Label(half_length_mm + 0.6, sum.first / sum.second, "column " + std::to_string(column), 13.0);
    name.align_x = 1.0;  // ends just beyond the distal edge, in the room left of the holder
    drawing.texts.push_back(name);
  }

  const std::string file = layout.source_file.empty() ? std::string("none (built in code)")
                                                      : std::filesystem::path(layout.source_file).filename().string();
  drawing.notes = {
      "blue mesa: beam along the holder axis (axial); orange: beam around it (circumferential); arrow: +Ft",
      "holder frame: origin on the axis at mid-length; x to the fingertip, y lateral, z dorsal (away from you)",
      "white numbers: layout order (R1/R2 in a frame, the _N of signals.csv columns, geom unit_N)",
      "holder " + Millimetres(layout.holder.major_axis_m) + " x " + Millimetres(layout.holder.minor_axis_m) +
          " mm, " + Millimetres(layout.holder.length_m) + " mm long; beam " + Millimetres(unit.beam_length_m) +
          " x " + Millimetres(unit.beam_width_m) + " mm, mesa " + Millimetres(unit.mesa_length_m) + " x " +
          Millimetres(unit.mesa_width_m) + " mm (along the beam x across it); file " + file,
  };
  return drawing;
}

}  // namespace graspbed::sensor
