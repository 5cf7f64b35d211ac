#pragma once
/// SceneConfig: everything that shapes the simulated world besides the sensor layout: the object to
/// grasp, the hand and its grip motor, the wrist servo, contact and solver options. Plain structs with
/// in-class defaults (the default scene is a 10 N-class pinch of a 50 mm box), a YAML loader and
/// Validate(). Docs: docs/simulation.md.
///
/// World frame: z up, the table top is the plane z = 0, the object starts centred at x = y = 0.
/// The hand closes along world x: the sensorised finger sits at -x and moves towards +x, the thumb
/// sits at +x and moves towards -x; the finger's palmar side (holder -z) faces world +x.

#include <array>
#include <limits>
#include <string>

#include "common/yaml_map.h"

namespace graspbed::sim {

/// Shape of the graspable object.
enum class ObjectShape { kBox, kCylinder, kSphere };

/// "box" / "cylinder" / "sphere".
const char* ToString(ObjectShape shape);

/// The object on the table.
struct ObjectConfig {
  ObjectShape shape = ObjectShape::kBox;
  /// Box: full edge lengths x, y, z [m]. Cylinder: {diameter, unused, height} (axis along world z).
  /// Sphere: {diameter, unused, unused}.
  std::array<double, 3> size_m = {0.05, 0.05, 0.08};
  double mass_kg = 0.1;      ///< [kg], inertia from a uniform solid of that shape
  /// Coulomb friction coefficient of every contact with the object (the object's geom has contact
  /// priority, so its friction and compliance govern its contacts with the fingers and the table).
  double friction = 0.8;
  double torsional_friction = 0.0;  ///< MuJoCo torsional friction [m] (only with condim >= 4)
  /// Contact compliance (MuJoCo solref, standard form): time constant [s] and damping ratio [-].
  /// The time constant must be >= 2 x timestep. Smaller = stiffer object.
  double solref_timeconst_s = 0.002;
  double solref_dampratio = 1.0;
  /// MuJoCo solimp: dmin, dmax [-], width [m], midpoint, power.
  std::array<double, 5> solimp = {0.95, 0.99, 0.0005, 0.5, 2.0};
  /// Initial centre position [m], world frame. z < 0 means "resting on the table" (z = half height).
  std::array<double, 3> initial_position_m = {0.0, 0.0, -1.0};
  /// Initial rotation about world z [rad].
  double initial_yaw_rad = 0.0;
  /// Grip force above which the object counts as crushed (scored by scenarios, not simulated) [N].
  double crush_limit_n = 0.0;  ///< 0 = not fragile

  /// Height of the object's centre above its lowest point when standing upright [m].
  double RestHalfHeightM() const;
};

/// The single grip motor, driving both digits through the linkage. The digits close in parallel
/// (the holder keeps its orientation), so the motor's output is a force on the grip tendon whose
/// length is the closure of finger + thumb; pinch force = tendon force at rest.
struct MotorConfig {
  /// Tendon force at stall, effort 1 [N]; equals the static fingertip pinch force. >= 15 N so the
  /// 10 N sensor range can be exceeded.
  double stall_force_n = 20.0;
  /// Closing speed of the gap at effort 1 with no load [m/s]; the force falls linearly with speed
  /// (DC motor: F = stall (effort - v / no_load_speed)), so the digits do not slam into objects.
  double no_load_speed_m_s = 0.12;
  /// Reflected rotor + gearbox inertia on each digit's slide [kg].
  double armature_kg = 0.05;
  /// Viscous friction on each digit's slide [N s/m].
  double damping_n_s_m = 1.0;
};

/// The hand: geometry of the digits around the object and the wrist servo that scripts move.
struct HandConfig {
  /// Gap between the finger's mesa tops and the thumb pad when fully open [m].
  double open_gap_m = 0.09;
  /// Mass of the palm (with the wrist carriage) [kg], of each digit [kg].
  double palm_mass_kg = 0.3;
  double digit_mass_kg = 0.03;
  /// Friction of hand geoms (used only against geoms without priority, e.g. the table).
  double friction = 1.0;
  /// Initial wrist position [m], world frame; NaN entries: chosen so the holder centre is level with
  /// the object's centre and the digits straddle it (pre-grasp pose).
  std::array<double, 3> initial_wrist_position_m = {std::numeric_limits<double>::quiet_NaN(),
                                                    std::numeric_limits<double>::quiet_NaN(),
                                                    std::numeric_limits<double>::quiet_NaN()};
  /// Wrist position servo per axis: stiffness [N/m] and damping [N s/m]. Gravity on the hand is
  /// compensated in the servo target, the held object's weight is not (it sags by m g / stiffness).
  double wrist_stiffness_n_m = 20000.0;
  double wrist_damping_n_s_m = 400.0;
  MotorConfig motor;
};

/// Solver and contact options (MuJoCo <option>); defaults chosen for grasping, docs/simulation.md.
struct PhysicsConfig {
  double timestep_s = 0.0005;       ///< physics step [s]
  bool elliptic_cones = true;       ///< elliptic friction cones (pyramidal drops held objects)
  double impratio = 10.0;           ///< friction-to-normal impedance ratio
  int noslip_iterations = 3;        ///< post-solve friction projection; removes soft-contact creep
  int solver_iterations = 100;      ///< Newton iterations
  double tolerance = 1e-10;         ///< solver tolerance
  int condim = 3;                   ///< contact dimensionality of object contacts (3, 4 or 6)
  double gravity_m_s2 = 9.81;       ///< magnitude, along world -z [m/s^2]; 0 disables gravity
  bool table = true;                ///< include the table (off for free-floating tests)
};

/// Everything of the scene besides the layout.
struct SceneConfig {
  ObjectConfig object;
  HandConfig hand;
  PhysicsConfig physics;

  /// Throws std::invalid_argument naming the field and value.
  void Validate() const;
};

/// Reads a SceneConfig from a YAML map with optional sections object / hand (with motor) / physics;
/// unknown keys are refused. Lengths in the file are in metres (keys end in _m).
SceneConfig LoadSceneConfig(const common::YamlMap& map);
/// Loads a scene file (top-level map as above).
SceneConfig LoadSceneConfigFile(const std::string& path);

}  // namespace graspbed::sim
