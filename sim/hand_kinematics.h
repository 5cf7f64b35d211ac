#pragma once
/// Planar kinematics of the prosthetic hand (no MuJoCo): where the index finger's pad and the thumb's
/// tip are for given joint angles, and the angles that put them at a given aperture. The model
/// generator uses it to pose the pre-shape, place the wrist and size the motors; tests use it to
/// check the simulated hand against the geometry.
///
/// Hand frame H (metres): origin at the wrist body, x from the index finger towards the thumb (the
/// pinch direction), z up away from the palm's palmar face, y = z x x. In the pinch H is parallel to
/// the world frame; in a wrap it is turned palm-sideways (H y along world z). Both digits flex in the
/// H x-z plane at opposition 0. The nominal pinch (a `kNominalWidthM` wide object, pad square to it)
/// is centred on x = 0.

#include <Eigen/Core>

#include "sim/scene_config.h"

namespace graspbed::sim {

/// A point of contact on a digit and the direction it faces, hand frame (x-z plane).
struct DigitContact {
  Eigen::Vector2d point_xz{0.0, 0.0};  ///< contact point [m], (x, z) in H
  /// Angle of the surface's outward normal from H +x, towards +z (the palm) positive [rad]: 0 faces the thumb
  /// squarely (index pad), pi faces the index (thumb tip).
  double normal_angle_rad = 0.0;
};

/// A wrap of an upright cylinder (its axis along H y) against the palm: where the cylinder sits in
/// the hand and the driven joints' angles that meet it and that open around it.
struct WrapPose {
  Eigen::Vector2d centre_xz{0.0, 0.0};  ///< cylinder axis [m], (x, z) in H
  double index_contact_rad = 0.0;       ///< MCP at which the pad touches it (pad_contact_along_m) [rad]
  double thumb_contact_rad = 0.0;       ///< thumb flexion at which the thumb first touches it [rad]
  /// MCP opened until the middle phalanx and the holder clear it by the clearance (the proximal
  /// phalanx's root sits beside it whatever the opening) [rad].
  double index_preshape_rad = 0.0;
  double thumb_preshape_rad = 0.0;      ///< thumb flexion opened likewise [rad]
  /// Where along the pad it touches, from the pad's centre towards the tip [m] (<= 0: towards the
  /// DIP, so that the middle phalanx meets the cylinder too).
  double pad_contact_along_m = 0.0;
  /// Clearance of the proximal and middle phalanges when the pad touches [m]: at most 1 mm (the links
  /// close on the cylinder with the pad) where the pad's contact can move far enough towards the DIP,
  /// more otherwise; never below -0.5 mm (overlapping it).
  double index_link_clearance_m = 0.0;
  /// Forces [N] per motor torque [N m] turned into the cylinder at contact: the pad's travel along
  /// its own normal per radian of MCP (the PIP follows through the linkage), and the thumb's
  /// contact point's travel towards the cylinder's axis per radian of flexion [m/rad].
  double pad_lever_arm_m = 0.0;
  double thumb_lever_arm_m = 0.0;
};

/// A pinch of a round section (a ball, an egg at its equator, a banana across its middle) through
/// its centre: the pad's normal and the thumb tip's centre on one line through the section's centre,
/// so the two contact forces are collinear and squeeze nothing out of the grasp.
struct RoundPinchPose {
  double mcp_rad = 0.0;                 ///< index MCP at contact [rad]
  double thumb_rad = 0.0;               ///< thumb flexion at contact [rad]
  Eigen::Vector2d centre_xz{0.0, 0.0};  ///< the section's centre [m], (x, z) in H
  /// The pad's contact point, `along_pad_m` from the pad's centre towards the tip, and the thumb's [m].
  Eigen::Vector2d pad_contact_xz{0.0, 0.0};
  Eigen::Vector2d thumb_contact_xz{0.0, 0.0};
  /// The line's angle from H +x, towards +z positive [rad]: 0 is a level pinch.
  double line_angle_rad = 0.0;
  /// Lowest point of the holder's rounded tip and of the thumb's tip, H z [m].
  double lowest_z_m = 0.0;
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
  /// Link radii [m]: the index's proximal and middle phalanx capsules, the thumb's proximal capsule
  /// (and its base sphere); the holder's rounded tip reaches this far beyond the holder.
  static constexpr double kProximalRadiusM = 0.0055;
  static constexpr double kMiddleRadiusM = 0.004;
  static constexpr double kThumbProximalRadiusM = 0.0075;
  static constexpr double kTipCapLengthM = 0.005;

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
  /// The pad's palmar mesa tops `along_m` from its centre towards the tip, and its normal.
  DigitContact IndexPadAt(double mcp_rad, double along_m) const;
  /// The pinch of a round section of `radius_m` through its centre, the pad touching it `along_m`
  /// from its centre towards the tip (Newton's method from the square pad). Throws
  /// std::invalid_argument when no posture in the joints' ranges does it.
  RoundPinchPose RoundPinch(double radius_m, double along_m) const;
  /// Thumb: the tip's contact point towards the index (tip centre offset by the tip radius along
  /// the pinch direction) for flexion `flexion_rad`.
  DigitContact ThumbTip(double flexion_rad) const;
  /// Thumb's IP joint and tip centre [m], H.
  Eigen::Vector2d ThumbIp(double flexion_rad) const;
  Eigen::Vector2d ThumbTipCentre(double flexion_rad) const;

  /// MCP angle at which the distal phalanx points straight down, the pad square to a vertical face
  /// (the nominal pinch) [rad].
  double SquarePadMcpRad() const;
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

  /// Smallest distance between the index (proximal and middle capsules, the holder as a capsule
  /// of the pad's depth) and a circle of `radius_m` about `centre_xz` in the H x-z plane [m];
  /// negative when they overlap. `links_only` leaves the holder out.
  double IndexClearanceM(double mcp_rad, const Eigen::Vector2d& centre_xz, double radius_m,
                         bool links_only = false) const;
  /// The same for the thumb (base sphere, proximal and distal capsules) [m].
  double ThumbClearanceM(double flexion_rad, const Eigen::Vector2d& centre_xz, double radius_m) const;
  /// The wrap of a cylinder of `radius_m`: the pad touches it when its surface is `palm_gap_m` from
  /// the palmar face (the pad then presses it against the palm), as near the pad's centre as brings
  /// the middle phalanx within 1 mm of it, at most at the first mesa row; both digits open until the
  /// links that sweep round it clear it by `clearance_m`. Throws std::invalid_argument when the
  /// cylinder cannot be wrapped (too small or too large for the finger to meet it with its pad,
  /// or out of the thumb's reach).
  WrapPose Wrap(double radius_m, double palm_gap_m, double clearance_m) const;

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
