#pragma once
/// Where the prosthetic hand's pinch meets the object, chosen from the object's geometry
/// (docs/simulation.md, "How a placement is chosen"). One function per grasp, callable without
/// building the scene: the model generator poses the hand from its result and `graspbed model
/// --kinematics` prints it.
///
/// World frame unless noted; the hand approaches with its pinch along world x (the hand frame H is
/// the world's, shifted to the wrist).

#include <array>
#include <string>

#include "sim/hand_kinematics.h"
#include "sim/scene_config.h"

namespace graspbed::sim {

/// How the pinch meets the object.
enum class PinchKind {
  /// Faces: a level pinch line through the centre of mass's vertical, at the height where the two
  /// surfaces it crosses are closest to parallel (a box, an upright cylinder, a cup, a glass, a
  /// bottle's neck, a mesh); the pad meets its face at the pad's centre.
  kFaces,
  /// Round: a section round in the pinch's plane (a ball, an egg at its equator, a banana across
  /// its middle) pinched through its centre: the pad's normal and the thumb tip on one line through
  /// it (ProstheticKinematics::RoundPinch).
  kRound,
};

/// "faces" / "round".
const char* ToString(PinchKind kind);

/// A pinch placement.
struct PinchPlacement {
  PinchKind kind = PinchKind::kFaces;  ///< how the pinch meets the object
  /// The pinch line: world y (the centre of mass's) and z of the contacts' midpoint [m].
  double line_y_m = 0.0;
  double height_m = 0.0;
  /// World x midway between the two contacts [m].
  double centre_x_m = 0.0;
  /// Distance between the two contacts along the pinch [m].
  double width_m = 0.0;
  /// Each contact surface's normal from the pinch axis [rad]: the finger's side, the thumb's. 0 is
  /// square to the pinch; the squeeze pushes the object out of a grasp whose angles reach atan(mu).
  std::array<double, 2> face_angle_rad{};
  /// Round: the pad's contact from its centre towards the tip [m] (moved tipwards in steps from 0
  /// until the fingertip clears the table and the posture is in the joints' ranges with the links
  /// clear); faces: 0.
  double along_pad_m = 0.0;
  /// Round: the posture solved (hand frame H); faces: unused.
  RoundPinchPose round;
  /// One line: what was chosen and why, for `graspbed model --kinematics`.
  std::string reason;
};

/// Where a faces pinch puts the middle between its contacts, hand frame H x [m]: the hand's pinch
/// centre (0), or with hand.pinch_square_pad half the width beyond the pad in its square posture.
double PinchCentreX(const SceneConfig& scene, const ProstheticKinematics& kin, double width_m);

/// The pinch placement for `scene`'s object. Boxes and upright cylinders keep the pinch the hand
/// has always made (13 mm below the top, or the pad's lowest height); the library's other shapes and
/// meshes are probed (MuJoCo's ray casts on the object alone).
/// @throws std::invalid_argument naming the object and why when this hand cannot pinch it: the
///   pinch line through its centre of mass misses it, every height meets faces outside the friction
///   cone, a phalanx would meet it above the pad, or its round section cannot be pinched through its
///   centre above the table.
PinchPlacement PlacePinch(const SceneConfig& scene, const ProstheticKinematics& kin);

}  // namespace graspbed::sim
