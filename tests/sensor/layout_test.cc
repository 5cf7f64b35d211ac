#include "sensor/layout.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tests/support/error_of.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::sensor {
namespace {

using test_support::ErrorOf;
using test_support::SourcePath;
using test_support::TempDir;
using ::testing::HasSubstr;

constexpr double kArcTolM = 1e-7;        // required accuracy is 1 um; we check 0.1 um
constexpr double kOnSurfaceTol = 1e-12;  // residual of y^2/a^2 + z^2/b^2 = 1
constexpr double kUnitVectorTol = 1e-12;
constexpr double kPitchM = 5e-3;

// Ellipse parameter t of a surface point, (y, z) = (a sin t, -b cos t).
double AngleOf(const HolderGeometry& holder, const Eigen::Vector3d& position_m) {
  const double a = holder.major_axis_m / 2;
  const double b = holder.minor_axis_m / 2;
  return std::atan2(position_m.y() / a, -position_m.z() / b);
}

// Independent arc length: a fine polyline between parameters t0 and t1 (error ~1e-12 m here).
double PolylineArcM(const HolderGeometry& holder, double t0, double t1) {
  const double a = holder.major_axis_m / 2;
  const double b = holder.minor_axis_m / 2;
  constexpr int kSegments = 200000;
  double length = 0.0;
  double y = a * std::sin(t0), z = -b * std::cos(t0);
  for (int i = 1; i <= kSegments; ++i) {
    const double t = t0 + (t1 - t0) * i / kSegments;
    const double y1 = a * std::sin(t), z1 = -b * std::cos(t);
    length += std::hypot(y1 - y, z1 - z);
    y = y1;
    z = z1;
  }
  return length;
}

TEST(LayoutTest, DefaultLayoutIsFiveByFourCheckerboard) {
  const Layout layout = LoadLayout(DefaultLayoutPath());
  EXPECT_EQ(layout.name, "default_20");
  ASSERT_EQ(layout.unit_count(), 20);
  const double axial_mm[] = {-10, -5, 0, 5, 10};
  const double arc_mm[] = {-7.5, -2.5, 2.5, 7.5};
  for (int i = 0; i < 20; ++i) {
    const UnitPose& pose = layout.units[i];
    EXPECT_EQ(pose.row, i / 4);
    EXPECT_EQ(pose.column, i % 4);
    EXPECT_DOUBLE_EQ(pose.axial_position_m, axial_mm[pose.row] * 1e-3);
    EXPECT_DOUBLE_EQ(pose.arc_position_m, arc_mm[pose.column] * 1e-3);
    const BeamOrientation expected =
        (pose.row + pose.column) % 2 == 0 ? BeamOrientation::kAxial : BeamOrientation::kCircumferential;
    EXPECT_EQ(pose.orientation, expected) << "unit " << i;
  }
}

TEST(LayoutTest, ArcPitchIsFiveMillimetresByArcLength) {
  const Layout layout = LoadLayout(DefaultLayoutPath());
  const double a = layout.holder.major_axis_m / 2;
  for (int row = 0; row < 5; ++row) {
    // Arc from the palmar midline, measured independently of the loader's quadrature.
    for (int column = 0; column < 4; ++column) {
      const UnitPose& pose = layout.units[row * 4 + column];
      const double t = AngleOf(layout.holder, pose.position_m);
      EXPECT_NEAR(std::copysign(PolylineArcM(layout.holder, 0.0, std::abs(t)), t), pose.arc_position_m,
                  kArcTolM);
    }
    for (int column = 0; column + 1 < 4; ++column) {
      const double t0 = AngleOf(layout.holder, layout.units[row * 4 + column].position_m);
      const double t1 = AngleOf(layout.holder, layout.units[row * 4 + column + 1].position_m);
      EXPECT_NEAR(PolylineArcM(layout.holder, t0, t1), kPitchM, kArcTolM)
          << "row " << row << " col " << column;
      // The chord is shorter than the arc: placing by arc length matters on this curvature.
      const double chord =
          (layout.units[row * 4 + column + 1].position_m - layout.units[row * 4 + column].position_m).norm();
      EXPECT_LT(chord, kPitchM - 1e-5);
    }
  }
  // Rows: 5 mm along the axis.
  for (int row = 0; row + 1 < 5; ++row) {
    EXPECT_NEAR(layout.units[(row + 1) * 4].position_m.x() - layout.units[row * 4].position_m.x(), kPitchM,
                1e-15);
  }
  EXPECT_GT(a, 0.0);
}

TEST(LayoutTest, PosesLieOnTheEllipseWithInwardUnitNormals) {
  for (const std::string& file : {std::string("default_20.yaml"), std::string("paper_3x3.yaml")}) {
    const Layout layout = LoadLayout(SourcePath("sensor/layouts/" + file));
    const double a = layout.holder.major_axis_m / 2;
    const double b = layout.holder.minor_axis_m / 2;
    for (const UnitPose& pose : layout.units) {
      const Eigen::Vector3d& p = pose.position_m;
      EXPECT_NEAR(p.y() * p.y() / (a * a) + p.z() * p.z() / (b * b), 1.0, kOnSurfaceTol);
      EXPECT_LT(p.z(), 0.0) << "palmar half";
      EXPECT_NEAR(pose.inward_normal.norm(), 1.0, kUnitVectorTol);
      EXPECT_NEAR(pose.beam_axis.norm(), 1.0, kUnitVectorTol);
      // Perpendicular to the ellipse: orthogonal to the tangent d(y, z)/dt and to the axis.
      const double t = AngleOf(layout.holder, p);
      const Eigen::Vector3d tangent(0.0, a * std::cos(t), b * std::sin(t));
      EXPECT_NEAR(pose.inward_normal.dot(tangent.normalized()), 0.0, kUnitVectorTol);
      EXPECT_NEAR(pose.inward_normal.x(), 0.0, kUnitVectorTol);
      // Inward: a small step along the normal lands inside the ellipse.
      const Eigen::Vector3d inside = p + 1e-4 * pose.inward_normal;
      EXPECT_LT(inside.y() * inside.y() / (a * a) + inside.z() * inside.z() / (b * b), 1.0);
      // Beam axis lies in the surface; axial -> +x, circumferential -> tangent towards +y.
      EXPECT_NEAR(pose.beam_axis.dot(pose.inward_normal), 0.0, kUnitVectorTol);
      if (pose.orientation == BeamOrientation::kAxial) {
        EXPECT_TRUE(pose.beam_axis.isApprox(Eigen::Vector3d::UnitX()));
      } else {
        EXPECT_NEAR(pose.beam_axis.x(), 0.0, kUnitVectorTol);
        EXPECT_GT(pose.beam_axis.y(), 0.0);
      }
    }
  }
}

TEST(LayoutTest, PaperLayoutSplitsFiveAxialFourCircumferential) {
  const Layout layout = LoadLayout(SourcePath("sensor/layouts/paper_3x3.yaml"));
  ASSERT_EQ(layout.unit_count(), 9);
  int axial = 0;
  for (const UnitPose& pose : layout.units) {
    const bool corner_or_centre = (pose.row != 1 && pose.column != 1) || (pose.row == 1 && pose.column == 1);
    EXPECT_EQ(pose.orientation == BeamOrientation::kAxial, corner_or_centre)
        << pose.row << "," << pose.column;
    axial += pose.orientation == BeamOrientation::kAxial;
  }
  EXPECT_EQ(axial, 5);
  EXPECT_EQ(layout.unit_count() - axial, 4);
  // Centre unit on the palmar midline, normal straight up (+z).
  EXPECT_TRUE(layout.units[4].position_m.isApprox(Eigen::Vector3d(0, 0, -4e-3)));
  EXPECT_TRUE(layout.units[4].inward_normal.isApprox(Eigen::Vector3d::UnitZ()));
}

TEST(LayoutTest, ArcLengthOfACircleIsRadiusTimesAngle) {
  HolderGeometry circle;
  circle.major_axis_m = circle.minor_axis_m = 10e-3;
  EXPECT_NEAR(HolderArcLengthM(circle, 1.0), 5e-3, 1e-16);
  EXPECT_NEAR(PalmarHalfArcLengthM(circle), 5e-3 * std::numbers::pi / 2, 1e-16);
  const HolderSurfacePoint point = HolderPointAtArc(circle, 0.0, 5e-3);
  EXPECT_NEAR(point.angle_rad, 1.0, 1e-12);
}

TEST(LayoutTest, GridOverridesAndExplicitUnitsAgree) {
  TempDir dir;
  const Layout grid = LoadLayout(dir.Write("g.yaml", R"(name: g
grid:
  axial_positions_mm: [-5, 0, 5]
  arc_positions_mm: [-5, 0, 5]
  orientation: axial
  overrides:
    - {row: 0, column: 1, orientation: circumferential}
)"));
  ASSERT_EQ(grid.unit_count(), 9);
  EXPECT_EQ(grid.units[1].orientation, BeamOrientation::kCircumferential);
  EXPECT_EQ(grid.units[0].orientation, BeamOrientation::kAxial);
  const Layout paper = LoadLayout(SourcePath("sensor/layouts/paper_3x3.yaml"));
  EXPECT_TRUE(grid.units[4].position_m.isApprox(paper.units[4].position_m));
  EXPECT_TRUE(grid.units[0].inward_normal.isApprox(paper.units[0].inward_normal));
}

class LayoutErrorTest : public ::testing::Test {
 protected:
  std::string Error(const std::string& text) {
    const std::string path = dir_.Write("bad.yaml", text);
    return ErrorOf([&] { LoadLayout(path); });
  }
  std::string File() const { return dir_.Path("bad.yaml"); }
  TempDir dir_;
};

TEST_F(LayoutErrorTest, MalformedYamlNamesFileAndLine) {
  EXPECT_THAT(Error("name: x\ngrid:\n  axial_positions_mm: [1, 2\n  orientation: axial\n"),
              HasSubstr(File() + ":"));
  EXPECT_THAT(Error("name: x\ngrid: {a: 1\n"), HasSubstr("YAML syntax error"));
}

TEST_F(LayoutErrorTest, UnknownKeyNamesFileLineAndKey) {
  const std::string error = Error(
      "name: x\ngrid:\n  axial_positions_mm: [0]\n  arc_positions_mm: [0]\n  orientaton: axial\n  "
      "orientation: axial\n");
  EXPECT_THAT(error, HasSubstr(File() + ":5: grid.orientaton: unknown key"));
  EXPECT_THAT(
      Error("name: x\nholder: {major_axis: 14}\nunits:\n  - {row: 0, column: 0, axial_mm: 0, arc_mm: 0, "
            "orientation: axial}\n"),
      HasSubstr(File() + ":2: holder.major_axis: unknown key"));
}

TEST_F(LayoutErrorTest, MissingKeysNameFileLineAndKey) {
  EXPECT_THAT(Error("grid:\n  axial_positions_mm: [0]\n  arc_positions_mm: [0]\n  orientation: axial\n"),
              HasSubstr(File() + ":1: name = null: missing required key"));
  EXPECT_THAT(Error("name: x\nunits:\n  - {row: 0, column: 0, axial_mm: 0, orientation: axial}\n"),
              HasSubstr(File() + ":3: units[0].arc_mm = null: missing required key"));
  EXPECT_THAT(Error("name: x\ngrid:\n  axial_positions_mm: [0]\n  arc_positions_mm: [0]\n"),
              HasSubstr("grid.orientation = null: missing required key"));
  EXPECT_THAT(Error("name: x\n"), HasSubstr("units = null: missing"));
}

TEST_F(LayoutErrorTest, GeometryChecksNameTheKey) {
  // 8.5 mm of arc with a 2 mm wide mesa leaves the 8.8 mm palmar half.
  EXPECT_THAT(
      Error("name: x\nunits:\n  - {row: 0, column: 0, axial_mm: 0, arc_mm: 8.5, orientation: axial}\n"),
      HasSubstr(File() + ":3: units[0].arc_mm = 8.5: unit 0 (row 0, column 0, axial): mesa at arc 8.5 mm"));
  EXPECT_THAT(
      Error("name: x\nunits:\n  - {row: 0, column: 0, axial_mm: 15, arc_mm: 0, orientation: axial}\n"),
      HasSubstr("units[0].axial_mm = 15: unit 0"));
  EXPECT_THAT(
      Error("name: x\nholder: {major_axis_mm: -14}\nunits:\n  - {row: 0, column: 0, axial_mm: 0, arc_mm: 0, "
            "orientation: axial}\n"),
      HasSubstr(File() + ":2: holder.major_axis_mm = -14: must be > 0"));
  EXPECT_THAT(
      Error("name: x\nunit: {beam_length_mm: 0}\nunits:\n  - {row: 0, column: 0, axial_mm: 0, arc_mm: 0, "
            "orientation: axial}\n"),
      HasSubstr("unit.beam_length_mm = 0: must be > 0"));
  EXPECT_THAT(Error("name: x\nunits:\n  - {row: 0, column: 0, axial_mm: 0, arc_mm: 0, orientation: axial}\n"
                    "  - {row: 0, column: 1, axial_mm: 0.5, arc_mm: 0.5, orientation: axial}\n"),
              HasSubstr("units[1].arc_mm = 0.5: unit 1 (row 0, column 1, axial): mesa overlaps unit 0"));
  EXPECT_THAT(
      Error("name: x\nunits:\n  - {row: 0, column: 0, axial_mm: 0, arc_mm: 0, orientation: diagonal}\n"),
      HasSubstr("units[0].orientation = diagonal: unknown name; valid names: axial, circumferential"));
}

TEST_F(LayoutErrorTest, UnitCountLimits) {
  // 9 x 8 = 72 units > 64.
  EXPECT_THAT(Error("name: x\ngrid:\n  axial_positions_mm: [-12, -9, -6, -3, 0, 3, 6, 9, 12]\n"
                    "  arc_positions_mm: [-7, -5, -3, -1, 1, 3, 5, 7]\n  orientation: axial\n"),
              HasSubstr(File() + ":3: grid: grid of 9 x 8 = 72 units; at most 64"));
  EXPECT_THAT(Error("name: x\nunits: []\n"), HasSubstr("units = [...]: missing"));
  EXPECT_THAT(
      Error("name: x\ngrid:\n  axial_positions_mm: [0]\n  arc_positions_mm: [0]\n  orientation: axial\n"
            "units:\n  - {row: 0, column: 0, axial_mm: 0, arc_mm: 0, orientation: axial}\n"),
      HasSubstr("give either grid or units, not both"));
  EXPECT_THAT(ErrorOf([] { LoadLayout("/nonexistent/layout.yaml"); }),
              HasSubstr("/nonexistent/layout.yaml: cannot open file"));
}

}  // namespace
}  // namespace graspbed::sensor
