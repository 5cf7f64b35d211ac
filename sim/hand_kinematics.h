#pragma once
/// Planar kinematics of the prosthetic hand (no MuJoCo): where the index finger's pad and the thumb's
/// tip are for given joint angles, and the angles that put them at a given aperture. The model
/// generator uses it to pose the pre-shape, place the wrist and size the motors; tests use it to
/// check the simulated hand against the geometry.
///
/// Hand frame H (metres): origin at the wrist body, x from the index finger towards the thumb (the
/// pinch direction), z up away from the palm's palmar face, y = z x x. In the pinch H is the world
/// frame. Both digits flex in the H x-z
/// plane at opposition 0. The nominal pinch (a `kNominalWidthM` wide object, pad square to it) is
/// centred on x = 0.

#include <Eigen/Core>

#include "sim/scene_config.h"

namespace graspbed::sim {

/// A point of contact on a digit and the direction it faces, hand frame (x-z plane).
struct DigitContact {
  Eigen::Vector2d point_xz{0.0, 0.0};  ///< contact point [m], (x, z) in H
  /// Angle of the surface's outward normal from H +x, towards -z positive [rad]: 0 faces the thumb
  /// squarely (index pad), pi faces the index (thumb tip).
  double normal_angle_rad = 0.0;
};

/// The hand's fixed design and the kinematics derived from it. Immutable after construction.
class ProstheticKinematics {
 public:
  /// Width of the object for which the pad meets a vertical face squarely (tilt 0) [m].
  static constexpr double kNominalWidthM = 0.05;
  /// Joint ranges [rad]: MCP (the index motor's joint) and the thumb's flexion.
  static constexpr double kMcpMinRad = -0.35;
  static constexpr double kMcpMaxRad = 1.45;
  static constexpr double kThumbMinRad = -0.6;
  static constexpr double kThumbMaxRad = 1.9;
  /// In the nominal pinch the thumb's distal segment leans this far past vertical towards the
  /// index [rad]: its rounded tip meets the object while the thumb comes in from the side, so its
  /// base sits 36 mm along the palm from the index MCP and its tip closes nearly square to the
  /// object (0.07 m up per m across) [rad].
  static constexpr double kThumbLeanRad = 0.3;
  /// The palm's palmar face is at H z = -kPalmDepthM; the MCP sits on it, the thumb base (placed by
  /// the nominal pinch) inside the palm above it.
  static constexpr double kPalmDepthM = 0.024;

  /// `holder_length_m`, `holder_half_depth_m`: the distal phalanx from the layout; `mesa_height_m`:
  /// the pad's mesas stand this far proud of the holder surface. Throws std::invalid_argument if the
  /// finger cannot reach a square pad at the nominal width.
  ProstheticKinematics(const FingerConfig& finger, const ThumbConfig& thumb, double holder_length_m,
                       double holder_half_depth_m, double mesa_height_m);

  /// Index joint positions [m] in H for MCP angle `mcp_rad` (PIP follows at pip_mcp_ratio).
  Eigen::Vector2d Pip(double mcp_rad) const;
  Eigen::Vector2d Dip(double mcp_rad) const;
  /// Absolute angle of the distal phalanx's axis below H -x, towards -z positive [rad] (pi/2 points
  /// straight down).
  double DistalAngle(double mcp_rad) const;
  /// Pad centre (holder axial centre, on the palmar mesa tops) and its normal.
  DigitContact IndexPad(double mcp_rad) const;
  /// Thumb: the tip's contact point towards the index (tip centre offset by the tip radius along
  /// the pinch direction) for flexion `flexion_rad`.
  DigitContact ThumbTip(double flexion_rad) const;
  /// Thumb's IP joint and tip centre [m], H.
  Eigen::Vector2d ThumbIp(double flexion_rad) const;
  Eigen::Vector2d ThumbTipCentre(double flexion_rad) const;

  /// MCP angle at which the pad centre is at H x = `x_m` [rad] (bisection on the monotonic branch);
  /// clamped to the joint range.
  double McpForPadX(double x_m) const;
  /// Thumb flexion at which its contact point is at H x = `x_m` [rad], clamped to the range.
  double ThumbForTipX(double x_m) const;
  /// d(pad x)/d(MCP) and d(thumb contact x)/d(flexion) [m/rad]: the lever arms that turn joint
  /// torque into pinch force along H x.
  double PadLeverArmM(double mcp_rad) const;
  double ThumbLeverArmM(double flexion_rad) const;
  /// Largest pinch aperture the pre-shape can open to [m].
  double MaxApertureM() const;

  /// Design constants, H frame [m].
  const Eigen::Vector2d& mcp_xz() const { return mcp_; }
  const Eigen::Vector2d& thumb_base_xz() const { return thumb_base_; }
  const FingerConfig& finger() const { return finger_; }
  const ThumbConfig& thumb() const { return thumb_; }
  double holder_length_m() const { return holder_length_m_; }
  double pad_depth_m() const { return pad_depth_m_; }

 private:
  FingerConfig finger_;
  ThumbConfig thumb_;
  double holder_length_m_;
  double pad_depth_m_;  ///< holder axis -> mesa tops [m]
  Eigen::Vector2d mcp_{0.0, 0.0};
  Eigen::Vector2d thumb_base_{0.0, 0.0};
};

}  // namespace graspbed::sim
