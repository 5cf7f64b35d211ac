#pragma once
/// Generates the self-contained MJCF of the scene from the sensor layout (the one source of truth for
/// where the units are) and the scene config. The output loads in mj_loadXML and in MuJoCo's own
/// tools (mujoco-simulate, mujoco-testspeed) with no other files.
///
/// Names the rest of sim/ relies on (docs/simulation.md, "One source of truth"), both hand models:
///   bodies  wrist, palm, finger (root of the sensorised digit), holder (its distal phalanx, the
///           holder frame), thumb (root of the thumb), object
///   geoms   unit_0 .. unit_{N-1} (one mesa box per layout unit, layout order, holder frame),
///           holder_shell (the elliptic holder, a convex mesh), thumb_pad, object_geom, table_geom
///           (a plane in the world body)
///   contact one pair per geom pair that can touch (collision="predefined"): object x hand,
///           table x hand, table x object
///   sites   finger_pad (holder centre on the palmar mesa tops), thumb_pad (the thumb's contact face)
///   joints  wrist_x, wrist_y, wrist_z (slides); object_free
///   actuators wrist_x_servo, wrist_y_servo, wrist_z_servo (position); the grip motors (GripMotorNames)
///   equality  the grip brakes (GripBrakeNames), off until the actuator asks for them
/// Prosthetic hand: joints index_mcp, index_pip (coupled: pip_coupling), thumb_opposition (held by
/// thumb_opposition_lock), thumb_flexion; motors index_motor, thumb_motor; brakes index_brake,
/// thumb_brake. Jaw fixture: joints finger_slide, thumb_slide; tendon grip; motor grip_motor;
/// equality digit_coupling and grip_brake.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "sensor/layout.h"
#include "sim/grasp_placement.h"
#include "sim/hand_kinematics.h"
#include "sim/scene_config.h"

namespace graspbed::sim {

/// Where the generated hand stands at the start and how its motors are sized; world frame unless
/// noted.
struct HandPlacement {
  std::array<double, 3> wrist_position_m{};  ///< initial wrist body origin [m]
  /// Pre-shape and expected contact joint angles of the driven joints (prosthetic: index MCP and
  /// thumb flexion [rad]; jaw: finger and thumb slide [m]).
  std::array<double, 2> preshape_joint{};
  std::array<double, 2> contact_joint{};
  double open_gap_m = 0.0;      ///< pre-shape aperture between pad and thumb [m]
  double object_width_m = 0.0;  ///< object extent across the grasp [m]
  /// Stall torque (prosthetic) [N m] or force (jaw) [N] per grip motor.
  std::array<double, 2> stall_effort{};
  /// Pad and thumb lever arms at contact (prosthetic) [m]; 1 for the jaw.
  std::array<double, 2> lever_arm_m{1.0, 1.0};
  /// No-load speed per grip motor [rad/s] (prosthetic: the thumb's scaled so that its tip closes
  /// as fast as the pad, and both digits meet the object together) or [m/s] (jaw).
  std::array<double, 2> no_load_speed{1.0, 1.0};
  /// In a wrap, the pose the kinematics solved (cylinder axis, contact and clearance angles, lever
  /// arms; preshape_joint above is that pre-shape opened further so both digits arrive together).
  std::optional<WrapPose> wrap;
  /// In a prosthetic pinch, the placement chosen from the object's geometry (PlacePinch).
  std::optional<PinchPlacement> pinch;
};

/// Computes the start pose and motor sizing that GenerateMjcf uses. Throws std::invalid_argument
/// naming the keys when the object does not fit the hand (wider than its aperture).
HandPlacement PlaceHand(const sensor::Layout& layout, const SceneConfig& scene);

/// Names of the grip motors and of their brakes for `model`, in the same order.
std::vector<std::string> GripMotorNames(HandModel model);
std::vector<std::string> GripBrakeNames(HandModel model);

/// A plain-text table of the hand's design and of its placement for this scene (joint positions in
/// the hand frame, pre-shape and contact angles, lever arms, motor sizes, pinch height), for docs and
/// for users checking a pre-shape; the numbers are the ones GenerateMjcf uses.
std::string DescribeHand(const sensor::Layout& layout, const SceneConfig& scene);

/// MJCF of the object alone at its start pose (no table, no hand, no gravity): what the grasp
/// placement probes the object's surfaces in.
std::string ObjectOnlyMjcf(const SceneConfig& scene);

/// Full MJCF text of the scene. Throws std::invalid_argument if the layout or scene is invalid
/// (e.g. more units than sensor::kMaxUnits, an object too wide for the hand).
std::string GenerateMjcf(const sensor::Layout& layout, const SceneConfig& scene);

}  // namespace graspbed::sim
