#pragma once
/// The sensor holder (an elliptic cylinder) and the poses of the sensing units on it, loaded from a
/// layout YAML file. Immutable after loading; the single source of truth for where units are (the
/// MuJoCo model is generated from it).
///
/// Holder frame: origin on the holder axis at the middle of its length; +x along the axis towards
/// the fingertip; +y lateral (the 14 mm major axis); +z dorsal (the 8 mm minor axis), so the palmar
/// midline, where the units are centred, is the line (x, 0, -minor/2).

#include <Eigen/Core>

#include <string>
#include <vector>

namespace graspbed::sensor {

/// Which way a unit's beam (its shear-sensitive axis) runs on the holder surface.
enum class BeamOrientation { kAxial, kCircumferential };

/// Elliptic-cylinder holder, paper section 2.
struct HolderGeometry {
  double major_axis_m = 14e-3;  ///< full lateral width of the cross-section (y) [m]
  double minor_axis_m = 8e-3;   ///< full dorsal-palmar depth of the cross-section (z) [m]
  double length_m = 30e-3;      ///< axial length of the holder (x) [m]
};

/// Dimensions of one sensing unit (paper Fig. 2), used by the model and the FEA.
struct UnitGeometry {
  double beam_length_m = 3e-3;  ///< along the beam axis [m]
  double beam_width_m = 2e-3;   ///< across the beam axis [m]
  double beam_thickness_m = 0.2e-3;
  double brace_height_m = 3e-3;
  double mesa_length_m = 1.0e-3;  ///< mesa along the beam axis [m] (not in the paper; chosen)
  double mesa_width_m = 2e-3;     ///< mesa across the beam axis [m]
  double mesa_height_m = 0.5e-3;  ///< mesa thickness above the beam [m]
};

/// Where one unit sits and how it is oriented. Vectors are unit length, holder frame.
struct UnitPose {
  int row = 0;                    ///< index along the axis (0 = most proximal)
  int column = 0;                 ///< index around the circumference (0 = most towards -y)
  double axial_position_m = 0.0;  ///< x of the unit centre [m]
  double arc_position_m = 0.0;    ///< arc length from the palmar midline, + towards +y [m]
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();      ///< unit centre on the holder surface [m]
  Eigen::Vector3d inward_normal = Eigen::Vector3d::UnitZ();  ///< into the holder; +Fn pushes along it
  Eigen::Vector3d beam_axis = Eigen::Vector3d::UnitX();      ///< +Ft direction, tangent to the surface
  BeamOrientation orientation = BeamOrientation::kAxial;
};

/// A complete layout: holder, unit geometry and every unit's pose, in layout order (the order of
/// R1/R2 in frames and of geoms unit_0..unit_N-1 in the model).
struct Layout {
  std::string name;
  std::string source_file;  ///< file it was loaded from ("" if built in code)
  HolderGeometry holder;
  UnitGeometry unit;
  std::vector<UnitPose> units;

  int unit_count() const { return static_cast<int>(units.size()); }
};

/// Loads and validates a layout file; throws common::ConfigError naming file, line and key.
/// Format: docs/sensor.md ("Layout files"); lengths in the file are in millimetres.
Layout LoadLayout(const std::string& path);

/// Like LoadLayout, from YAML text; `source_name` stands for the file name in messages.
Layout LoadLayoutFromString(const std::string& text, const std::string& source_name);

/// A point on the holder's elliptic surface with its local frame, holder frame.
struct HolderSurfacePoint {
  double angle_rad = 0.0;  ///< ellipse parameter t: (y, z) = (a sin t, -b cos t); 0 on the palmar midline
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();                ///< on the surface [m]
  Eigen::Vector3d inward_normal = Eigen::Vector3d::UnitZ();            ///< unit, perpendicular to the surface
  Eigen::Vector3d circumferential_tangent = Eigen::Vector3d::UnitY();  ///< unit, towards +y at the midline
};

/// Arc length [m] along the holder cross-section from the palmar midline (t = 0) to parameter
/// `angle_rad` (signed, + towards +y). Gauss-Legendre quadrature, error far below 1 nm.
double HolderArcLengthM(const HolderGeometry& holder, double angle_rad);

/// Arc length [m] of the palmar half from the midline to either side (a quarter of the perimeter).
double PalmarHalfArcLengthM(const HolderGeometry& holder);

/// The surface point at signed arc length `arc_m` from the palmar midline and axial position
/// `axial_m` (Newton on the arc length, converged to < 1 nm). |arc_m| must not exceed
/// PalmarHalfArcLengthM(holder).
HolderSurfacePoint HolderPointAtArc(const HolderGeometry& holder, double axial_m, double arc_m);

/// "axial" / "circumferential".
const char* ToString(BeamOrientation orientation);

/// Path of the shipped default layout (sensor/layouts/default_20.yaml under common::DataDir()).
std::string DefaultLayoutPath();

}  // namespace graspbed::sensor
