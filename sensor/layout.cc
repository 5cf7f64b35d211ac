#include "sensor/layout.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>
#include <utility>

#include "common/data_dir.h"
#include "common/yaml_map.h"
#include "sensor/raw_frame.h"

namespace graspbed::sensor {
namespace {

using common::NumberRule;
using common::YamlMap;

constexpr double kMmToM = 1e-3;

// 10-point Gauss-Legendre nodes and weights on [-1, 1].
constexpr std::array<double, 5> kGaussNodes = {0.1488743389816312, 0.4333953941292472, 0.6794095682990244,
                                               0.8650633666889845, 0.9739065285171717};
constexpr std::array<double, 5> kGaussWeights = {0.2955242247147529, 0.2692667193099963, 0.2190863625159820,
                                                 0.1494513491505806, 0.0666713443086881};
// Sub-intervals per radian: the integrand is analytic, so 10-point rules on 16 pieces per radian
// are exact to rounding for any sensible aspect ratio.
constexpr int kPiecesPerRadian = 16;

// |d(y, z)/dt| for (y, z) = (a sin t, -b cos t).
double Speed(double a, double b, double t) { return std::hypot(a * std::cos(t), b * std::sin(t)); }

std::string FormatMm(double value_m) {
  std::ostringstream out;
  out << value_m / kMmToM << " mm";
  return out.str();
}

HolderGeometry ReadHolder(const YamlMap& root) {
  HolderGeometry holder;
  if (const auto map = root.GetMap("holder")) {
    holder.major_axis_m =
        map->GetNumber("major_axis_mm", holder.major_axis_m / kMmToM, NumberRule::Positive()) * kMmToM;
    holder.minor_axis_m =
        map->GetNumber("minor_axis_mm", holder.minor_axis_m / kMmToM, NumberRule::Positive()) * kMmToM;
    holder.length_m = map->GetNumber("length_mm", holder.length_m / kMmToM, NumberRule::Positive()) * kMmToM;
    map->RejectUnknownKeys();
  }
  return holder;
}

UnitGeometry ReadUnitGeometry(const YamlMap& root) {
  UnitGeometry unit;
  if (const auto map = root.GetMap("unit")) {
    const auto read = [&](const char* key, double* value_m) {
      *value_m = map->GetNumber(key, *value_m / kMmToM, NumberRule::Positive()) * kMmToM;
    };
    read("beam_length_mm", &unit.beam_length_m);
    read("beam_width_mm", &unit.beam_width_m);
    read("beam_thickness_mm", &unit.beam_thickness_m);
    read("brace_height_mm", &unit.brace_height_m);
    read("mesa_length_mm", &unit.mesa_length_m);
    read("mesa_width_mm", &unit.mesa_width_m);
    read("mesa_height_mm", &unit.mesa_height_m);
    map->RejectUnknownKeys();
  }
  return unit;
}

const std::vector<std::string> kOrientationNames = {"axial", "circumferential"};

BeamOrientation ParseOrientation(const std::string& name) {
  return name == "axial" ? BeamOrientation::kAxial : BeamOrientation::kCircumferential;
}

BeamOrientation Other(BeamOrientation orientation) {
  return orientation == BeamOrientation::kAxial ? BeamOrientation::kCircumferential : BeamOrientation::kAxial;
}

// Where each unit came from in the file, so geometric checks can name the key at fault.
struct UnitSource {
  const YamlMap* map;  // map holding the key
  std::string axial_key;
  std::string arc_key;
};

void ReadGrid(const YamlMap& grid, Layout* layout, std::vector<UnitSource>* sources) {
  const std::vector<double> axial_mm = grid.GetNumberList("axial_positions_mm", {});
  const std::vector<double> arc_mm = grid.GetNumberList("arc_positions_mm", {});
  if (axial_mm.empty()) grid.Fail("axial_positions_mm", "missing required key (list of row positions)");
  if (arc_mm.empty()) grid.Fail("arc_positions_mm", "missing required key (list of column positions)");
  const std::string pattern = grid.RequireString("orientation", {"checkerboard", "axial", "circumferential"});
  BeamOrientation even = BeamOrientation::kAxial;
  if (pattern == "checkerboard") {
    even = ParseOrientation(grid.GetString("even_orientation", "axial", kOrientationNames));
  } else if (grid.Has("even_orientation")) {
    grid.Fail("even_orientation", "only allowed with orientation: checkerboard");
  }
  const size_t count = axial_mm.size() * arc_mm.size();
  if (count > static_cast<size_t>(kMaxUnits)) {
    grid.FailHere("grid of " + std::to_string(axial_mm.size()) + " x " + std::to_string(arc_mm.size()) +
                  " = " + std::to_string(count) + " units; at most " + std::to_string(kMaxUnits));
  }
  for (size_t row = 0; row < axial_mm.size(); ++row) {
    for (size_t column = 0; column < arc_mm.size(); ++column) {
      UnitPose pose;
      pose.row = static_cast<int>(row);
      pose.column = static_cast<int>(column);
      pose.axial_position_m = axial_mm[row] * kMmToM;
      pose.arc_position_m = arc_mm[column] * kMmToM;
      if (pattern == "checkerboard") {
        pose.orientation = (row + column) % 2 == 0 ? even : Other(even);
      } else {
        pose.orientation = ParseOrientation(pattern);
      }
      layout->units.push_back(pose);
      sources->push_back({&grid, "axial_positions_mm", "arc_positions_mm"});
    }
  }
  // Per-unit exceptions to the pattern: {row, column, orientation}.
  for (const YamlMap& override_map : grid.GetMapList("overrides")) {
    const int row = override_map.RequireInt("row", 0, static_cast<int>(axial_mm.size()) - 1);
    const int column = override_map.RequireInt("column", 0, static_cast<int>(arc_mm.size()) - 1);
    const BeamOrientation orientation =
        ParseOrientation(override_map.RequireString("orientation", kOrientationNames));
    override_map.RejectUnknownKeys();
    layout->units[static_cast<size_t>(row) * arc_mm.size() + static_cast<size_t>(column)].orientation =
        orientation;
  }
  grid.RejectUnknownKeys();
}

// Mesa footprint of a unit in (axial, arc) surface coordinates [m].
std::pair<double, double> MesaExtent(const UnitGeometry& unit, BeamOrientation orientation) {
  return orientation == BeamOrientation::kAxial ? std::pair{unit.mesa_length_m, unit.mesa_width_m}
                                                : std::pair{unit.mesa_width_m, unit.mesa_length_m};
}

Layout Load(const YamlMap& root) {
  Layout layout;
  layout.source_file = root.file();
  layout.name = root.RequireString("name");
  layout.holder = ReadHolder(root);
  layout.unit = ReadUnitGeometry(root);

  std::vector<UnitSource> sources;
  const std::optional<YamlMap> grid = root.GetMap("grid");
  const std::vector<YamlMap> unit_maps = root.GetMapList("units");
  if (grid && !unit_maps.empty()) root.FailHere("give either grid or units, not both");
  if (!grid && unit_maps.empty()) {
    root.Fail("units", "missing: give either a grid section or a units list (1.." +
                           std::to_string(kMaxUnits) + " units)");
  }
  if (grid) {
    ReadGrid(*grid, &layout, &sources);
  } else {
    if (unit_maps.size() > static_cast<size_t>(kMaxUnits)) {
      root.Fail("units", std::to_string(unit_maps.size()) + " units; at most " + std::to_string(kMaxUnits));
    }
    for (const YamlMap& map : unit_maps) {
      UnitPose pose;
      pose.row = map.RequireInt("row", 0, kMaxUnits);
      pose.column = map.RequireInt("column", 0, kMaxUnits);
      pose.axial_position_m = map.RequireNumber("axial_mm") * kMmToM;
      pose.arc_position_m = map.RequireNumber("arc_mm") * kMmToM;
      pose.orientation = ParseOrientation(map.RequireString("orientation", kOrientationNames));
      map.RejectUnknownKeys();
      layout.units.push_back(pose);
      sources.push_back({&map, "axial_mm", "arc_mm"});
    }
  }
  root.RejectUnknownKeys();

  // Geometry: every mesa on the palmar half and within the holder's length; no two units sharing a
  // grid cell or overlapping.
  const double half_arc_m = PalmarHalfArcLengthM(layout.holder);
  for (size_t i = 0; i < layout.units.size(); ++i) {
    UnitPose& pose = layout.units[i];
    const UnitSource& source = sources[i];
    const auto [extent_axial_m, extent_arc_m] = MesaExtent(layout.unit, pose.orientation);
    const std::string which = "unit " + std::to_string(i) + " (row " + std::to_string(pose.row) +
                              ", column " + std::to_string(pose.column) + ", " + ToString(pose.orientation) +
                              ")";
    if (std::abs(pose.arc_position_m) + extent_arc_m / 2 > half_arc_m) {
      source.map->Fail(source.arc_key, which + ": mesa at arc " + FormatMm(pose.arc_position_m) + " +- " +
                                           FormatMm(extent_arc_m / 2) +
                                           " leaves the palmar half (|arc| <= " + FormatMm(half_arc_m) + ")");
    }
    if (std::abs(pose.axial_position_m) + extent_axial_m / 2 > layout.holder.length_m / 2) {
      source.map->Fail(source.axial_key, which + ": mesa at x " + FormatMm(pose.axial_position_m) + " +- " +
                                             FormatMm(extent_axial_m / 2) + " leaves the holder (|x| <= " +
                                             FormatMm(layout.holder.length_m / 2) + ")");
    }
    for (size_t j = 0; j < i; ++j) {
      const UnitPose& other = layout.units[j];
      if (other.row == pose.row && other.column == pose.column) {
        source.map->Fail(source.axial_key, which + ": same row and column as unit " + std::to_string(j));
      }
      const auto [other_axial_m, other_arc_m] = MesaExtent(layout.unit, other.orientation);
      if (std::abs(other.axial_position_m - pose.axial_position_m) < (extent_axial_m + other_axial_m) / 2 &&
          std::abs(other.arc_position_m - pose.arc_position_m) < (extent_arc_m + other_arc_m) / 2) {
        source.map->Fail(source.arc_key, which + ": mesa overlaps unit " + std::to_string(j));
      }
    }
    const HolderSurfacePoint point =
        HolderPointAtArc(layout.holder, pose.axial_position_m, pose.arc_position_m);
    pose.position_m = point.position_m;
    pose.inward_normal = point.inward_normal;
    pose.beam_axis = pose.orientation == BeamOrientation::kAxial ? Eigen::Vector3d::UnitX()
                                                                 : point.circumferential_tangent;
  }
  return layout;
}

}  // namespace

double HolderArcLengthM(const HolderGeometry& holder, double angle_rad) {
  const double a = holder.major_axis_m / 2;
  const double b = holder.minor_axis_m / 2;
  const int pieces = std::max(1, static_cast<int>(std::ceil(std::abs(angle_rad) * kPiecesPerRadian)));
  const double width = angle_rad / pieces;
  double sum = 0.0;
  for (int piece = 0; piece < pieces; ++piece) {
    const double middle = (piece + 0.5) * width;
    for (size_t k = 0; k < kGaussNodes.size(); ++k) {
      const double offset = kGaussNodes[k] * width / 2;
      sum += kGaussWeights[k] * (Speed(a, b, middle - offset) + Speed(a, b, middle + offset));
    }
  }
  return sum * width / 2;
}

double PalmarHalfArcLengthM(const HolderGeometry& holder) {
  return HolderArcLengthM(holder, std::numbers::pi / 2);
}

HolderSurfacePoint HolderPointAtArc(const HolderGeometry& holder, double axial_m, double arc_m) {
  const double a = holder.major_axis_m / 2;
  const double b = holder.minor_axis_m / 2;
  // Newton on s(t) - arc = 0 from the circle-of-mean-radius guess; s is monotonic with s' >= min(a, b).
  double t = std::clamp(arc_m / ((a + b) / 2), -std::numbers::pi / 2, std::numbers::pi / 2);
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double step = (HolderArcLengthM(holder, t) - arc_m) / Speed(a, b, t);
    t -= step;
    if (std::abs(step) * std::max(a, b) < 1e-13) break;
  }
  HolderSurfacePoint point;
  point.angle_rad = t;
  point.position_m = {axial_m, a * std::sin(t), -b * std::cos(t)};
  // Inward normal: minus the gradient of y^2/a^2 + z^2/b^2.
  point.inward_normal = Eigen::Vector3d(0.0, -std::sin(t) / a, std::cos(t) / b).normalized();
  point.circumferential_tangent = Eigen::Vector3d(0.0, a * std::cos(t), b * std::sin(t)).normalized();
  return point;
}

const char* ToString(BeamOrientation orientation) {
  return orientation == BeamOrientation::kAxial ? "axial" : "circumferential";
}

Layout LoadLayout(const std::string& path) { return Load(YamlMap::LoadFile(path)); }

Layout LoadLayoutFromString(const std::string& text, const std::string& source_name) {
  return Load(YamlMap::LoadString(text, source_name));
}

std::string DefaultLayoutPath() { return common::DataPath("sensor/layouts/default_20.yaml"); }

}  // namespace graspbed::sensor
