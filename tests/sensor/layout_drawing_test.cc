#include "sensor/layout_drawing.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

#include "common/rgb_image.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::sensor {
namespace {

using test_support::SourcePath;
using test_support::TempDir;

// The number texts of a drawing, by the text: where they stand [mm].
const plot::Text* NumberText(const plot::Drawing& drawing, int unit) {
  for (const plot::Text& text : drawing.texts) {
    if (text.bold && text.text == std::to_string(unit)) return &text;
  }
  return nullptr;
}

bool SameColour(const plot::Colour& a, const plot::Colour& b) { return a.r == b.r && a.g == b.g && a.b == b.b; }

// Each unit of the layout is numbered in layout order at its place on the unrolled surface, its mesa
// in its orientation's colour, and its arrow points along its beam in the sense of its +Ft.
void ExpectDrawingFollows(const Layout& layout) {
  const plot::Drawing drawing = LayoutDrawing(layout);
  int mesas = 0;
  for (const plot::Shape& shape : drawing.shapes) mesas += shape.filled && shape.line_width_px == 0.0;
  EXPECT_EQ(mesas, layout.unit_count());
  for (int i = 0; i < layout.unit_count(); ++i) {
    SCOPED_TRACE("unit " + std::to_string(i));
    const UnitPose& pose = layout.units[static_cast<size_t>(i)];
    const plot::Text* number = NumberText(drawing, i);
    ASSERT_NE(number, nullptr);
    EXPECT_NEAR(number->x, pose.axial_position_m * 1e3, 1e-9);
    EXPECT_NEAR(number->y, pose.arc_position_m * 1e3, 1e-9);
    // The mesa centred on the unit, in its colour and along its beam.
    const plot::Shape* mesa = nullptr;
    const plot::Shape* arrow = nullptr;
    for (const plot::Shape& shape : drawing.shapes) {
      double cx = 0.0, cy = 0.0;
      for (const auto& [x, y] : shape.points) cx += x / shape.points.size(), cy += y / shape.points.size();
      if (shape.filled && shape.line_width_px == 0.0 && std::hypot(cx - number->x, cy - number->y) < 1e-6)
        mesa = &shape;
      if (shape.arrow_head && std::hypot(shape.points.front().first - number->x,
                                         shape.points.front().second - number->y) < 1.0)
        arrow = &shape;
    }
    ASSERT_NE(mesa, nullptr);
    ASSERT_NE(arrow, nullptr);
    const bool axial = pose.orientation == BeamOrientation::kAxial;
    EXPECT_TRUE(SameColour(mesa->fill, axial ? kAxialBeamColour : kCircumferentialBeamColour));
    const double dx = arrow->points.back().first - arrow->points.front().first;
    const double dy = arrow->points.back().second - arrow->points.front().second;
    if (axial) {
      EXPECT_EQ(dy, 0.0);
      EXPECT_GT(dx * pose.beam_axis.x(), 0.0) << "the arrow points along +Ft";
    } else {
      EXPECT_EQ(dx, 0.0);
      const HolderSurfacePoint point = HolderPointAtArc(layout.holder, pose.axial_position_m, pose.arc_position_m);
      EXPECT_GT(dy * pose.beam_axis.dot(point.circumferential_tangent), 0.0) << "the arrow points along +Ft";
    }
  }
}

TEST(LayoutDrawingTest, NumbersEveryUnitOfTheDefaultLayoutWhereItSits) {
  ExpectDrawingFollows(LoadLayout(SourcePath("sensor/layouts/default_20.yaml")));
}

TEST(LayoutDrawingTest, FollowsAnotherLayoutFile) {
  const Layout paper = LoadLayout(SourcePath("sensor/layouts/paper_3x3.yaml"));
  ExpectDrawingFollows(paper);
  EXPECT_EQ(NumberText(LayoutDrawing(paper), 9), nullptr) << "nine units, numbered 0 to 8";
}

TEST(LayoutDrawingTest, ThePictureShowsEachMesaInItsColourAtItsPlace) {
  const Layout layout = LoadLayout(SourcePath("sensor/layouts/default_20.yaml"));
  const plot::Drawing drawing = LayoutDrawing(layout);
  const TempDir dir("layout_drawing");
  const std::string path = dir.Path("layout.png");
  plot::WritePng(drawing, path);
  const image::RgbImage picture = image::ReadPng(path);
  ASSERT_EQ(picture.width_px, drawing.width_px);
  std::set<int> checked;
  for (int i = 0; i < layout.unit_count(); ++i) {
    const UnitPose& pose = layout.units[static_cast<size_t>(i)];
    const bool axial = pose.orientation == BeamOrientation::kAxial;
    // Off the number, inside the mesa: 0.7 mm from its centre across the beam (the mesa is 2 mm
    // across and 1 mm along), where the arrow along the beam does not run either.
    const double x_mm = pose.axial_position_m * 1e3 + (axial ? 0.0 : 0.7);
    const double y_mm = pose.arc_position_m * 1e3 + (axial ? 0.7 : 0.0);
    const auto [px, py] = DrawingPointPx(drawing, x_mm, y_mm);
    const uint8_t* rgb = &picture.rgb[(static_cast<size_t>(std::lround(py)) * picture.width_px +
                                       static_cast<size_t>(std::lround(px))) * 3];
    const plot::Colour expected = axial ? kAxialBeamColour : kCircumferentialBeamColour;
    EXPECT_NEAR(rgb[0], 255 * expected.r, 2) << "unit " << i;
    EXPECT_NEAR(rgb[1], 255 * expected.g, 2) << "unit " << i;
    EXPECT_NEAR(rgb[2], 255 * expected.b, 2) << "unit " << i;
    checked.insert(i);
  }
  EXPECT_EQ(checked.size(), 20u);
}

}  // namespace
}  // namespace graspbed::sensor
