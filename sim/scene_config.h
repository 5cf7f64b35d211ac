#pragma once
/// SceneConfig: everything that shapes the simulated world besides the sensor layout: the object to
/// grasp, the hand and its grip motor, the wrist servo, contact and solver options. Plain structs with
/// in-class defaults (the default scene is a 10 N-class pinch of a 50 mm box), a YAML loader and
/// Validate(). Docs: docs/simulation.md.
///
/// World frame: z up, the table top is the plane z = 0, the object starts centred at x = y = 0.
/// Both hand models pinch along world x: the sensorised index finger's pad meets the object on its
/// -x side, the thumb on its +x side. The prosthetic hand's kinematics: docs/simulation.md.

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "common/field_table.h"
#include "common/yaml_map.h"

namespace graspbed::sim {

/// Bounds of the scene's values: what no real grasp scene has is refused at load (file:line:key),
/// because MuJoCo turns it into NaN, a stalled clock or a run that never ends. docs/scenarios.md,
/// "Bounds", lists them. Lower bounds of 0 exclusive are not repeated here.
inline constexpr double kMinObjectSizeM = 0.001;       ///< used object.size_m entries [m]
inline constexpr double kMaxObjectSizeM = 0.3;         ///< the table is 0.6 m square [m]
inline constexpr double kMinObjectMassKg = 0.001;      ///< [kg]
inline constexpr double kMaxObjectMassKg = 10.0;       ///< far beyond any prosthetic pinch [kg]
inline constexpr double kMaxFriction = 10.0;           ///< Coulomb coefficient (rubber on rubber ~1-2)
inline constexpr double kMaxTorsionalFrictionM = 0.1;  ///< [m]
inline constexpr double kMaxSolrefTimeconstS = 0.1;    ///< contact time constant [s]
inline constexpr double kMaxSolrefDampratio = 10.0;    ///< [-]
inline constexpr double kMaxSolimpWidthM = 0.1;        ///< solimp[2] [m]
inline constexpr double kMaxSolimpPower = 10.0;        ///< solimp[4], >= 1 [-]
inline constexpr double kMaxObjectOffsetM = 0.3;       ///< |object.initial_position_m x, y|: on the table [m]
inline constexpr double kMaxPositionM = 1.0;           ///< any position coordinate, world frame [m]
inline constexpr double kMaxYawRad = 10.0;             ///< |object.initial_yaw_rad| [rad]
inline constexpr double kMaxForceN = 1000.0;           ///< force limits such as crush_limit_n [N]
inline constexpr double kMinOpenGapM = 0.001;          ///< hand.open_gap_m [m]
inline constexpr double kMaxOpenGapM = 0.2;            ///< [m]
inline constexpr double kMinPalmMassKg = 0.01;         ///< [kg]
inline constexpr double kMaxPalmMassKg = 10.0;         ///< [kg]
inline constexpr double kMinDigitMassKg = 0.001;       ///< [kg]
inline constexpr double kMaxDigitMassKg = 1.0;         ///< [kg]
inline constexpr double kMaxWristStiffnessNM = 1e6;    ///< [N/m]
inline constexpr double kMaxWristDampingNSM = 1e5;     ///< [N s/m]
inline constexpr double kMaxStallForceN = 500.0;       ///< hand.motor.stall_force_n [N]
inline constexpr double kMaxDigitSpeedMS = 5.0;        ///< hand.motor.no_load_speed_m_s [m/s]
inline constexpr double kMaxArmatureKg = 10.0;         ///< [kg]
inline constexpr double kMaxMotorDampingNSM = 1e4;     ///< [N s/m]
inline constexpr double kMinTimestepS = 1e-5;          ///< physics.timestep_s [s]
inline constexpr double kMaxTimestepS = 0.01;          ///< [s]
inline constexpr double kMaxImpratio = 1000.0;         ///< [-]
/// physics.impratio auto: objects at least this stiff keep kMaxImpratio; softer ones get
/// kMaxImpratio x stiffness / this (SceneConfig::Impratio) [N/m].
inline constexpr double kHardFrictionStiffnessNM = 2.5e6;
/// physics.impratio auto never goes below this [-].
inline constexpr double kMinAutoImpratio = 10.0;
inline constexpr int kMaxNoslipIterations = 1000;
inline constexpr int kMaxSolverIterations = 1000;
inline constexpr double kMinTolerance = 1e-15;   ///< physics.tolerance [-]
inline constexpr double kMaxTolerance = 1e-2;    ///< [-]
inline constexpr double kMaxGravityMS2 = 100.0;  ///< [m/s^2] (Jupiter: 24.8)

inline constexpr double kMinStiffnessNM = 10.0;   ///< object.stiffness_n_m [N/m]
inline constexpr double kMaxStiffnessNM = 1e8;    ///< [N/m]
/// Impedance (solimp dmin = dmax) of an object whose compliance is given as a stiffness: flat, so
/// the force grows linearly with penetration at the stated stiffness (docs/scenarios.md, "Object
/// compliance").
inline constexpr double kStiffnessImpedance = 0.99;

/// Shape of the graspable object. Beyond the three primitives, the everyday objects of the library
/// (sim/object_shapes.h builds their parts), each sized by object.size_m as ObjectConfig says.
enum class ObjectShape { kBox, kCylinder, kSphere, kMug, kBottle, kCup, kWineGlass, kEgg, kBanana, kMesh };

/// "box" / "cylinder" / "sphere" / "mug" / "bottle" / "cup" / "wine_glass" / "egg" / "banana" / "mesh".
const char* ToString(ObjectShape shape);

/// The object on the table.
struct ObjectConfig {
  ObjectShape shape = ObjectShape::kBox;
  /// Box: full edge lengths x, y, z [m]. Cylinder: {diameter, unused, height} (axis along world z).
  /// Sphere: {diameter, unused, unused}. Mug: {body diameter, depth with the handle (along +y),
  /// height}. Bottle: {body diameter, neck diameter, height}. Cup: {rim diameter, base diameter,
  /// height}. Wine glass: {bowl diameter, foot diameter, height}. Egg: {diameter, unused, length}
  /// (standing on its blunt end). Banana: {chord length (along y), thickness, bow (sagitta, towards
  /// -x)}, lying on the table. Mesh: the bounding box of the scaled mesh, set from the file.
  std::array<double, 3> size_m = {0.05, 0.05, 0.08};
  /// Total mass [kg]: primitives are uniform solids; the library's shapes spread it over their parts
  /// (sim/object_shapes.h).
  double mass_kg = 0.1;
  /// Library name the object came from ("" when none); not part of the physics.
  std::string name;
  /// Mesh shape: path of the STL or OBJ file (made absolute at load); scale multiplies its
  /// coordinates into metres (e.g. 0.001 for a file in mm).
  std::string mesh;
  std::optional<double> scale;
  /// Bottle: share of the body's inner height filled with water (0..1); the liquid's mass is part
  /// of mass_kg.
  std::optional<double> fill_fraction;
  /// Contact stiffness against a rigid, immovable surface [N/m]: when set, solref_timeconst_s and
  /// solimp are derived from it and the mass at load (docs/scenarios.md, "Object compliance").
  std::optional<double> stiffness_n_m;
  /// Coulomb friction coefficient of every contact with the object (the object's geom has contact
  /// priority, so its friction and compliance govern its contacts with the fingers and the table).
  double friction = 0.8;
  /// MuJoCo torsional friction [m]: the most torque about the contact normal per newton of normal
  /// force (only with condim >= 4). NaN: the soft finger's, SceneConfig::TorsionalFrictionM.
  double torsional_friction = std::numeric_limits<double>::quiet_NaN();
  /// Contact dimensionality of this object's contacts (3, 4 or 6); 0 = physics.condim. A soft object
  /// the pad sinks into takes 6: its rolling friction stands for the wide patch that keeps it from
  /// rolling about the point contacts (docs/scenarios.md, "Object compliance").
  int condim = 0;
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
  /// World height of the object's centre at the start [m]: initial_position_m z, or resting on the
  /// table (RestHalfHeightM) when that is negative.
  double StartCentreZM() const { return initial_position_m[2] < 0.0 ? RestHalfHeightM() : initial_position_m[2]; }
  /// The contact dimensionality the object's contacts get: condim, or `physics_condim` when 0.
  int ContactCondim(int physics_condim) const { return condim != 0 ? condim : physics_condim; }
};

/// Which hand the scene carries.
enum class HandModel {
  /// The default: an index finger flexing at MCP and PIP (PIP coupled to MCP by a linkage, DIP fixed)
  /// whose distal phalanx is the sensor holder, and an opposable thumb; one DC motor per digit.
  kProsthetic,
  /// The bench fixture: finger and thumb on two coupled slide joints, the holder never turns.
  kJaw,
};
/// "prosthetic" / "jaw".
const char* ToString(HandModel model);

/// The grasp the pre-shape prepares.
enum class GraspType {
  /// Index fingertip pad against the thumb tip, hand above the object, near its top.
  kPinch,
  /// Power grasp of an upright cylinder against the palm (prosthetic hand only): the palm faces the
  /// cylinder from the side, the index curls round it until its pad presses it against the palm,
  /// the thumb closes round its other side.
  kWrap,
};
/// "pinch" / "wrap".
const char* ToString(GraspType grasp);

/// Diameter range of an upright cylinder, or of a bottle's body, that a library object's default
/// grasp wraps [m]: narrower, the object is small enough to pinch (a marker); wider, the prosthetic
/// hand cannot wrap it (ProstheticKinematics::Wrap refuses 100 mm) and pinches it instead.
inline constexpr double kMinDefaultWrapDiameterM = 0.04;
inline constexpr double kMaxDefaultWrapDiameterM = 0.09;

/// The jaw fixture's single grip motor, driving both digits through the linkage. The digits close in
/// parallel (the holder keeps its orientation), so the motor's output is a force on the grip tendon
/// whose length is the closure of finger + thumb; pinch force = tendon force at rest.
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

/// The prosthetic index finger (adult index: proximal 39-45 mm, middle 22-26 mm). Its distal phalanx
/// is the sensor holder (cross-section and length from the layout) with a rounded tip.
struct FingerConfig {
  double proximal_length_m = 0.043;  ///< MCP -> PIP [m]
  double middle_length_m = 0.024;    ///< PIP -> DIP [m]
  /// PIP flexion per radian of MCP flexion, fixed by the linkage (commercial fingers: 1 to 1.3) [-].
  double pip_mcp_ratio = 1.1;
  /// Fixed flexion of the DIP joint (the holder against the middle phalanx) [rad].
  double dip_flexion_rad = 0.15;
  /// Fixed angle of the proximal phalanx at MCP = 0 below the palm plane, towards flexion [rad].
  double mcp_rest_angle_rad = 0.3;
};

/// The opposable thumb: a rotation about the palm normal set by the pre-shape, then one flexion joint
/// with a fixed interphalangeal bend; an unsensorised rounded tip.
struct ThumbConfig {
  double proximal_length_m = 0.060;  ///< flexion joint (CMC) -> IP: metacarpal + proximal phalanx [m]
  double distal_length_m = 0.030;    ///< IP -> tip centre [m]
  double tip_radius_m = 0.008;       ///< radius of the rounded distal segment [m]
  double ip_flexion_rad = 0.35;      ///< fixed interphalangeal flexion [rad]
  /// Opposition (rotation about the palm normal at the thumb base) [rad]; NaN: from the grasp (0 in
  /// a pinch and a wrap: the thumb flexes in the index finger's plane).
  double opposition_rad = std::numeric_limits<double>::quiet_NaN();
};

/// The prosthetic hand's motors: one DC motor per digit (index MCP, thumb flexion), both commanded
/// with the one grip effort. Torque = stall x (effort - omega / no_load_speed).
struct DigitMotorConfig {
  /// Fingertip pinch force at stall, effort 1, in the pinch posture of the object [N]; the index
  /// motor's stall torque is this times the pad's lever arm there, the thumb's likewise (so the two
  /// balance on the object). >= 15 N so the 10 N sensor range can be exceeded.
  double stall_pinch_force_n = 20.0;
  /// No-load speed of the index MCP [rad/s]: open to closed in about 1 s at effort 1. The thumb's
  /// motor is geared so that its tip closes as fast as the pad (both meet the object together).
  double no_load_speed_rad_s = 1.6;
  /// Reflected rotor + gearbox inertia on each driven joint [kg m^2].
  double armature_kg_m2 = 2e-4;
  /// Viscous friction on every finger joint [N m s/rad].
  double damping_n_m_s = 0.002;
  /// In a wrap, the thumb's stall force as a share of the pad's [-]: the thumb closes round the
  /// cylinder's far side and the palm takes the rest of the pad's squeeze.
  double wrap_thumb_share = 0.5;
};

/// The hand: geometry of the digits around the object and the wrist servo that scripts move.
struct HandConfig {
  HandModel model = HandModel::kProsthetic;
  GraspType grasp = GraspType::kPinch;
  /// Pre-shape aperture: gap between the finger's pad (mesa tops) and the thumb at the start [m].
  /// NaN: follows the object (its width across the pinch + 2 x preshape_clearance_m). Pinch only:
  /// a wrap opens each digit until it clears the cylinder by preshape_clearance_m.
  double open_gap_m = std::numeric_limits<double>::quiet_NaN();
  /// Clearance on each side of the object in the automatic pre-shape [m]; in a wrap, of every link.
  double preshape_clearance_m = 0.0075;
  /// Pinch: the index's pad meets the object square (the nominal pinch's posture) and the thumb
  /// closes the rest of the way, so an object narrower or wider than the nominal 50 mm sits off the
  /// hand's centre; false: both digits meet it at the same distance from the centre, the pad tilted
  /// (17 deg for an 18 mm marker, which then tips against it).
  bool pinch_square_pad = false;
  /// Radius of the contact patch a fingertip's silicone skin makes on an object [m]: a soft finger
  /// resists spin about the contact normal up to (2/3) mu a N, a uniform-pressure disc's friction
  /// torque (docs/simulation.md, "The soft finger"). 4 mm: half the default holder's 8 mm minor axis,
  /// the widest patch the pad's curved face can make across it.
  double contact_patch_radius_m = 0.004;
  /// Mass of the palm (with the wrist carriage) [kg], of each digit [kg].
  double palm_mass_kg = 0.3;
  double digit_mass_kg = 0.03;
  /// Friction of hand geoms (used only against geoms without priority, e.g. the table).
  double friction = 1.0;
  /// Initial wrist position [m], world frame; NaN entries: chosen so the digits straddle the object
  /// (pre-grasp pose): prosthetic hand, the contacts where the placement puts them (PlacePinch,
  /// sim/grasp_placement.h; docs/simulation.md); jaw, holder centre level with the object's centre.
  std::array<double, 3> initial_wrist_position_m = {std::numeric_limits<double>::quiet_NaN(),
                                                    std::numeric_limits<double>::quiet_NaN(),
                                                    std::numeric_limits<double>::quiet_NaN()};
  /// Wrist position servo per axis: stiffness [N/m] and damping [N s/m]. Gravity on the hand is
  /// compensated in the servo target, the held object's weight is not (it sags by m g / stiffness).
  double wrist_stiffness_n_m = 20000.0;
  double wrist_damping_n_s_m = 400.0;
  MotorConfig motor;             ///< jaw fixture only
  FingerConfig finger;           ///< prosthetic hand only
  ThumbConfig thumb;             ///< prosthetic hand only
  DigitMotorConfig digit_motor;  ///< prosthetic hand only
};

/// The grasp a library object (`object: {name: ...}`) gets when the scenario does not name one
/// (no hand.grasp, no hand.open_gap_m): `wrap` for the prosthetic hand and an upright cylinder, a
/// bottle or a mug whose body is kMinDefaultWrapDiameterM .. kMaxDefaultWrapDiameterM across and at
/// least as tall as it is wide (a can, a bottle or a mug by its body); `pinch` for everything else:
/// the small and thin (a marker, a card, an egg), the round (balls, fruit), the shapes the wrap does
/// not take (a cup, a glass, a banana, a box, a mesh) and every grasp of the jaw fixture.
/// Docs: docs/scenarios.md, "Object library".
GraspType DefaultGrasp(const ObjectConfig& object, const HandConfig& hand);

/// Solver and contact options (MuJoCo <option>); defaults chosen for grasping, docs/simulation.md.
struct PhysicsConfig {
  double timestep_s = 0.001;   ///< physics step [s]
  bool elliptic_cones = true;  ///< elliptic friction cones (pyramidal drops held objects)
  /// Friction-to-normal impedance ratio [-]. NaN: from the object's stiffness,
  /// SceneConfig::Impratio (1000 keeps a rigid object's creep near 1 um/s without noslip).
  double impratio = std::numeric_limits<double>::quiet_NaN();
  /// Post-solve friction projection (removes soft-contact creep; costs a J M^-1 J' per step).
  int noslip_iterations = 0;
  int solver_iterations = 100;  ///< Newton iterations
  double tolerance = 1e-10;     ///< solver tolerance
  /// Contact dimensionality of object contacts (3, 4 or 6): 4, the soft finger, resists spin about
  /// each contact's normal (3: point contacts an object pivots about).
  int condim = 4;
  double gravity_m_s2 = 9.81;   ///< magnitude, along world -z [m/s^2]; 0 disables gravity
  bool table = true;            ///< include the table (off for free-floating tests)
  /// List the geom pairs that can touch in the model (collision="predefined"); false leaves them
  /// to MuJoCo's broad phase: the same contacts, 10 to 14 % slower (docs/simulation.md).
  bool contact_pairs = true;
};

/// A config value as messages quote it: "%g", and a triple as "[x, y, z]" with "auto" for NaN.
std::string FormatConfigNumber(double value);
std::string FormatConfigTriple(const std::array<double, 3>& values);

/// Everything of the scene besides the layout.
struct SceneConfig {
  ObjectConfig object;
  HandConfig hand;
  PhysicsConfig physics;

  /// The object's extent across the grasp [m]: along world x for a pinch (box: with its yaw),
  /// the diameter for a round object, a bottle's neck in a pinch and its body in a wrap.
  double ObjectWidthM() const;
  /// The pre-shape aperture in use [m]: hand.open_gap_m, or the object's width plus clearance on
  /// both sides when it is NaN (the pre-shape follows the object).
  double OpenGapM() const;
  /// Torsional friction of the object's contacts at sliding friction `friction` [m]:
  /// object.torsional_friction, or when it is NaN the soft finger's (2/3) friction x
  /// hand.contact_patch_radius_m.
  double TorsionalFrictionM(double friction) const;
  /// Thumb opposition in use [rad].
  double ThumbOppositionRad() const;
  /// MuJoCo's impratio in use [-]: physics.impratio, or when it is NaN kMaxImpratio scaled down by
  /// the object's stiffness against a rigid surface below kHardFrictionStiffnessNM, at least
  /// kMinAutoImpratio. Friction that hard locks in the tangential motion of an object sinking into
  /// the tilted mesas, which a soft object's flesh takes up (docs/simulation.md, "Friction on a
  /// sunk pad").
  double Impratio() const;

  /// Checks every field against SceneConfigFields() and the cross-field rules (time constant vs
  /// timestep, pre-shape wider than the object).
  /// @throws common::ConfigError "scene.SECTION.KEY = VALUE: reason".
  void Validate() const;
};

/// The field tables of the scene's sections (loader, Validate(), emitter and reference tables
/// derive from them); SceneConfigFields() holds object, hand and physics as sections.
const common::FieldTable<ObjectConfig>& ObjectConfigFields();
const common::FieldTable<HandConfig>& HandConfigFields();
const common::FieldTable<PhysicsConfig>& PhysicsConfigFields();
const common::FieldTable<SceneConfig>& SceneConfigFields();

/// Reads a SceneConfig from a YAML map with optional sections object / hand (with motor) / physics;
/// unknown keys are refused. Lengths in the file are in metres (keys end in _m). An object section
/// with `name` starts from that entry of the object library (sim/object_library.h), its other keys
/// overriding the entry's; with `mesh`, the object is that file's mesh (relative paths from the
/// file's directory), sized from it; a hull warning goes to stderr (MeshHullWarning).
/// @throws common::ConfigError naming file, line, key and value (an unknown library name lists the
///   known ones; a mesh file that cannot be read is named).
SceneConfig LoadSceneConfig(const common::YamlMap& map);
/// Reads a library entry's object: the object keys of `map` besides `also_valid`, `name` the
/// entry's own; stiffness turned into solref / solimp for the default physics.timestep_s.
/// @throws common::ConfigError as LoadSceneConfig.
ObjectConfig LoadLibraryObjectConfig(const common::YamlMap& map, const std::vector<std::string>& also_valid);
/// The solref time constant that gives `object` its stiffness_n_m against a rigid surface with the
/// flat impedance kStiffnessImpedance: tau = sqrt(m / ((1 - d) K)) / dampratio [s].
double SolrefTimeconstForStiffness(double stiffness_n_m, double mass_kg, double dampratio);
/// The stiffness against a rigid surface that solref / solimp give `object` at its impedance dmax
/// (exact when dmin = dmax): K = m / ((1 - d) tau^2 dampratio^2) [N/m].
double StiffnessOfSolref(const ObjectConfig& object);
/// Writes the scene as the sections object, hand, physics of the map `out` is in (a scenario's
/// config.yaml): the field tables' keys plus the object's name and mesh when it has them.
void EmitSceneConfig(const SceneConfig& scene, YAML::Emitter& out);
/// Loads a scene file (top-level map as above).
/// @throws common::ConfigError as LoadSceneConfig, or when the file cannot be read.
SceneConfig LoadSceneConfigFile(const std::string& path);

}  // namespace graspbed::sim
