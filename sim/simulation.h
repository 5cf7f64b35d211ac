#pragma once
/// Simulation: owns the MuJoCo model and data of one scene (the generated hand with the sensorised
/// fingertip, the table and the object), steps it, takes script commands (wrist targets, grip
/// effort, perturbations of the object) and maps contacts onto the sensing units. The only place in
/// graspbed that holds mjModel/mjData besides the CLI's `model` command and the sim tests.
///
/// Frames: world (z up, table top z = 0); unit frames from the layout (holder frame) carried along
/// with the holder body. Step(), ComputeUnitLoads() and truth() allocate nothing.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "sensor/layout.h"
#include "sensor/strain_model.h"
#include "sim/scene_config.h"

// MuJoCo types stay out of users' translation units.
struct mjModel_;
struct mjData_;

namespace graspbed::sim {

/// A physics failure during a run: a value, not a crash. Once set, the simulation keeps the
/// time and cause of the first fault, and the physics stops: Step() then only advances the clock
/// (MuJoCo has reset the state), so a run ends at the fault and no loop waits on time forever.
struct PhysicsFault {
  bool occurred = false;
  double time_s = 0.0;            ///< simulation time at the start of the faulty step [s]
  std::array<char, 160> cause{};  ///< NUL-terminated text: MuJoCo warning or "NaN in qpos" etc.
  uint64_t warning_count = 0;     ///< MuJoCo warnings seen so far (all kinds)
  const char* cause_text() const { return cause.data(); }
};

/// Ground truth of one instant, never passed through the sensor path. World frame unless noted.
struct GroundTruth {
  double time_s = 0.0;
  std::array<double, 3> object_position_m{};              ///< object centre of mass [m]
  std::array<double, 3> object_velocity_m_s{};            ///< linear velocity of the object centre [m/s]
  std::array<double, 3> object_angular_velocity_rad_s{};  ///< [rad/s]
  /// Lowest point of the object above the table top [m] (0 when resting on it).
  double object_height_above_table_m = 0.0;
  std::array<double, 3> wrist_position_m{};  ///< actual wrist position [m]
  /// How far the aperture between the finger's pad and the thumb's contact face (sites finger_pad,
  /// thumb_pad) has closed since the start [m], either hand model.
  double grip_closure_m = 0.0;
  double grip_velocity_m_s = 0.0;  ///< closing speed of that aperture [m/s]
  /// The (index) grip motor's drive, back-EMF included, as the pinch force it makes [N]: the jaw's
  /// tendon force; the index motor's torque over the pad's lever arm in the contact posture.
  double grip_motor_force_n = 0.0;
  /// Largest relative tangential speed between object and finger/thumb at their contact points
  /// [m/s]; 0 without contact. Includes MuJoCo's residual creep (um/s with noslip).
  double slip_speed_m_s = 0.0;
  /// Same, normal-force weighted mean over the finger/thumb contacts [m/s].
  double mean_slip_speed_m_s = 0.0;
  /// Largest relative tangential speed at a finger/thumb contact with the object whose friction
  /// force is at the edge of its cone, |Ft| >= sliding_friction_fraction() x mu x Fn: Coulomb
  /// sliding, what the slip metrics count. Soft contacts also move inside the cone (MuJoCo's
  /// friction is a soft velocity constraint: under a shake the object rocks against the pads at a
  /// third of the friction limit); that is excluded here [m/s].
  double sliding_speed_m_s = 0.0;
  /// The same per digit: the largest at the finger's contacts (sensed) and at the thumb's [m/s];
  /// sliding_speed_m_s is the larger. Tells a slide under the sensor from one on the thumb alone.
  double finger_sliding_speed_m_s = 0.0;
  double thumb_sliding_speed_m_s = 0.0;
  /// Share of a digit's normal force on the object carried by its sliding contacts (those counted in
  /// sliding_speed_m_s), the larger of the two digits' [0, 1]: near 1 the digit slides over the
  /// object as a whole; a few percent is a lightly loaded contact at the patch's edge sliding while
  /// the rest sticks (partial slip, as when the object pivots a little in the grasp).
  double sliding_load_share = 0.0;
  /// Total contact normal force on the sensorised finger (holder, mesas, fingertip, phalanges) from anything
  /// outside the hand [N]; on the thumb (pad, link) [N].
  double finger_normal_force_n = 0.0;
  double thumb_normal_force_n = 0.0;
  /// Normal force on the object from the index's proximal and middle phalanges (the jaw's link) and
  /// from the palm [N]: in a wrap the links and the palm take a share of the squeeze.
  double finger_links_normal_force_n = 0.0;
  double palm_normal_force_n = 0.0;
  /// Normal force of the index finger (every part) and of its mesas on the object alone [N].
  double finger_object_normal_force_n = 0.0;
  double sensed_object_normal_force_n = 0.0;
  /// Normal force carried by the mesas (sensed) and by the whole holder (mesas + shell) [N].
  double sensed_normal_force_n = 0.0;
  double holder_normal_force_n = 0.0;
  /// sensed / holder normal force [0..1]; 0 when the holder carries nothing.
  double sensed_share = 0.0;
  /// Largest squeeze on the object: the larger of the total normal force from the finger and from
  /// the thumb on the object [N] (compare with a crush limit).
  double object_squeeze_n = 0.0;
  /// Deepest penetration of the object into a mesa [m] (>= 0) and whether the object touches the
  /// holder shell itself (pushed through the mesas).
  double max_mesa_penetration_m = 0.0;
  bool object_touches_holder_shell = false;
  /// Total tangential contact force the finger and the thumb exert on the object, world frame [N]
  /// (held still under gravity: the weight, pointing up).
  std::array<double, 3> object_tangential_force_n{};
  /// Its magnitude [N]: the load the pinch carries by friction (weight, pulls, inertia).
  double object_tangential_load_n = 0.0;
  /// Net force of the hand (both digits, normal and tangential) on the object, world frame [N]. Two
  /// digits pressing equally cancel in this sum, on a non-antipodal pinch too: by Newton it is the load
  /// the hand carries, m a - m g - external pulls - the table's support (weight and inertia once
  /// lifted).
  std::array<double, 3> hand_load_n{};
  /// |hand_load_n| / (2 mu), mu the object's current friction coefficient [N]: the grip two digits
  /// need to carry that load by friction alone, each at most mu times its normal force; a lower bound
  /// of the grip that holds the object when the load lies along the pads (weight, inertia, pulls down
  /// or sideways), not when it pushes along the pinch axis, which normal forces carry. It does not
  /// grow with the squeeze. 0 while the table carries the object.
  double load_bound_grip_n = 0.0;
  int finger_contacts = 0;  ///< contacts between the object and the finger
  int thumb_contacts = 0;   ///< contacts between the object and the thumb
};

/// One digit's joints and motor as the physics has them, for the simulated proprioception
/// (sim/proprioception.h). Joints proximal first: prosthetic index MCP, PIP; thumb flexion; jaw
/// fixture one slide per digit.
struct DigitTruth {
  int joint_count = 0;
  bool linear = false;  ///< slides (the jaw fixture) [m], else hinges [rad]
  /// Flexion since the model's start pose (the pre-shape): qpos - qpos0, + closing [rad] or [m].
  std::array<double, 2> position{};
  std::array<double, 2> velocity{};  ///< [rad/s] or [m/s]
  /// The first joint's travel from the start pose to its open and closed end stops [rad] or [m]
  /// (open <= 0 <= closed); +-inf for a joint without limits.
  double open_stop = 0.0;
  double closed_stop = 0.0;
  /// Whether a grip motor drives this digit (the jaw's one motor drives both: it is counted on the
  /// finger), and its torque as a share of its stall torque: effort minus the back-EMF term, so
  /// proportional to the winding current; 0 while braked (the motor is off) [-].
  bool has_motor = false;
  double motor_torque_share = 0.0;
};

/// Compiles MJCF text (e.g. GenerateMjcf's) with MuJoCo's XML loader, one load at a time
/// process-wide. The caller owns the model (mj_deleteModel). Simulation compiles through a
/// per-process cache on top of it; tests and tools that need a model compiled directly call it.
/// Its contact pairs come in the order dynamic collision would test them (body pair, then geom ids).
/// @throws std::runtime_error with MuJoCo's message when the text does not load.
mjModel_* CompileMjcf(const std::string& mjcf);

/// The scene in MuJoCo. Owns mjModel/mjData; not copyable, not movable.
class Simulation {
 public:
  /// Generates the MJCF from `layout` and `scene` and loads it from memory. Throws
  /// std::runtime_error with MuJoCo's message if the model does not load, std::invalid_argument for
  /// a bad scene.
  Simulation(const sensor::Layout& layout, const SceneConfig& scene);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  /// One physics step (scene.physics.timestep_s). Checks for MuJoCo warnings and NaN afterwards and
  /// records the first as fault(). time_s() grows by one timestep on every call, fault or not;
  /// after a fault nothing else changes. Never throws, never allocates.
  void Step();
  /// Steps until time_s() >= `time_s` [s], or until a physics fault.
  void StepUntil(double time_s);
  /// Simulation time [s].
  double time_s() const;
  /// Physics step [s].
  double timestep_s() const;

  /// Grip motor effort in [-1, 1] (clamped): + closes, - opens; force = stall (effort - v / v0).
  void SetGripEffort(double effort);
  double grip_effort() const { return grip_effort_; }
  /// Engages (holds the current closure, whatever the load) or releases the grip brake.
  void SetGripBrake(bool engaged);
  bool grip_brake() const { return brake_engaged_; }
  /// Wrist servo target [m], world frame (the wrist body origin). Scripts move it for approach,
  /// lift, carry, place and shake; the servo is stiff but not rigid (HandConfig).
  void SetWristTarget(const std::array<double, 3>& position_m);
  const std::array<double, 3>& wrist_target() const { return wrist_target_; }
  /// External force on the object's centre of mass [N], world frame (pull, knock); stays until reset.
  void SetObjectExternalForce(const std::array<double, 3>& force_n);
  /// Changes the object's mass [kg] (> 0), scaling its inertia with it (mass steps, pouring), and
  /// everything MuJoCo derived from them at compile time, so the model is the one compiled with
  /// that mass (mass matrix, inverse weights, subtree masses, mean mass and inertia).
  void SetObjectMass(double mass_kg);
  double object_mass_kg() const;
  /// Changes the friction coefficient of every object contact (> 0).
  void SetObjectFriction(double friction);
  /// A contact counts as sliding in GroundTruth::sliding_speed_m_s when its friction force is at
  /// least this fraction of mu x its normal force (in (0, 1]; 0.95 by default: the cone's edge
  /// within MuJoCo's regularisation, where a ramped pull starts to slide at 0.9998 x Coulomb).
  void set_sliding_friction_fraction(double fraction) { sliding_friction_fraction_ = fraction; }
  double sliding_friction_fraction() const { return sliding_friction_fraction_; }

  /// Current load on every unit, unit frames, layout order (`loads.size()` == unit count):
  /// Fn along the inward normal (+ pressing in), Ft along the beam axis, cross-axis shear, offset of
  /// the normal load along the beam from the mesa centre. Force on the holder between mesas is not
  /// sensed. Allocates nothing.
  void ComputeUnitLoads(std::span<sensor::UnitLoad> loads) const;
  /// Ground truth now (object state, slip, contact forces). Allocates nothing.
  GroundTruth truth() const;
  /// World height of the lowest point of the object's colliding geoms [m] (compound objects).
  double LowestObjectPointM() const;
  /// The digits' joints and motors now (index or finger first, then the thumb). Allocates nothing.
  std::array<DigitTruth, 2> ReadDigits() const;
  /// First physics fault (NaN, MuJoCo warning), if any.
  const PhysicsFault& fault() const { return fault_; }

  /// Wrist origin -> holder centre, digit stroke etc. of this model.
  const sensor::Layout& layout() const { return layout_; }
  const SceneConfig& scene() const { return scene_; }
  int unit_count() const { return layout_.unit_count(); }

  /// Raw MuJoCo handles, for sim/ internals and sim tests only (controllers never see them).
  const mjModel_* model() const { return model_.get(); }
  mjModel_* mutable_model() { return model_.get(); }
  const mjData_* data() const { return data_.get(); }
  mjData_* mutable_data() { return data_.get(); }

 private:
  void ApplyControls();
  void CheckFault();
  void RecordFault(const char* cause);

  sensor::Layout layout_;
  SceneConfig scene_;
  struct ModelDeleter {
    void operator()(mjModel_* model) const;
  };
  struct DataDeleter {
    void operator()(mjData_* data) const;
  };
  /// Owned: released by their deleters, also when the constructor throws half-way.
  std::unique_ptr<mjModel_, ModelDeleter> model_;
  std::unique_ptr<mjData_, DataDeleter> data_;

  // Ids resolved once at construction.
  int object_body_ = -1;
  int object_geom_ = -1;                ///< the object's first geom ("object_geom")
  std::vector<char> geom_is_object_;     ///< per geom: 1 when it is one of the object's colliding geoms
  std::vector<int> object_geoms_;        ///< the object's colliding geoms
  std::vector<int> object_pairs_;  ///< the contact pairs (model pair ids) that include the object
  int holder_body_ = -1;
  int holder_shell_geom_ = -1;
  int wrist_body_ = -1;
  int finger_pad_site_ = -1;
  int thumb_pad_site_ = -1;
  double initial_aperture_m_ = 0.0;  ///< pad-to-thumb site distance at the start [m]
  double sliding_friction_fraction_ = 0.95;
  /// One per grip motor (jaw: 1, prosthetic: index and thumb), in GripMotorNames order.
  struct GripDrive {
    int actuator = -1;
    int brake_equality = -1;
    int brake_joint_qpos = -1;   ///< qpos address of the joint the brake holds (-1: a tendon)
    int brake_tendon = -1;       ///< the tendon the brake holds (-1: a joint)
    /// Radians (metres) the actuator's transmission moves per radian (metre) of the driven joint
    /// in free motion: 2 for the wrap's flexor tendon across MCP and PIP, else 1.
    double transmission = 1.0;
    double stall = 0.0;          ///< stall torque [N m] or force [N]
    double no_load_speed = 1.0;  ///< [rad/s] or [m/s]
    double lever_arm_m = 1.0;    ///< drive -> pinch force [m] (1 for the jaw)
  };
  std::vector<GripDrive> grip_drives_;
  /// Per digit (finger, thumb): joint ids, proximal first (-1: none); the drive index (-1: none).
  std::array<std::array<int, 2>, 2> digit_joints_{{{-1, -1}, {-1, -1}}};
  std::array<int, 2> digit_drive_{-1, -1};
  std::array<int, 3> wrist_actuators_{-1, -1, -1};
  std::array<int, 3> wrist_joint_qpos_{-1, -1, -1};
  /// geom id -> unit index (-1 for non-mesa geoms); built once.
  std::vector<int> geom_unit_;
  /// geom id -> 1 finger, 2 thumb, 3 palm and wrist, 0 other (hand-side classification for ground truth).
  std::vector<int> geom_side_;
  /// geom id -> whether it is a finger link below the holder (proximal, middle phalanx; jaw link).
  std::vector<char> geom_is_link_;
  /// Unit frames in the holder body frame (inward normal, beam axis, cross axis, centre), per unit.
  std::vector<std::array<double, 12>> unit_frames_;
  /// The object as compiled: mass [kg], principal inertia [kg m^2], and what MuJoCo derived from
  /// them (the free joint's diagonal mass at qpos0 and inverse weights, the body's inverse weights);
  /// SetObjectMass scales them all together.
  double object_mass_ = 0.0;
  std::array<double, 3> object_inertia_{};
  int object_dof_ = -1;  ///< first of the free joint's 6 dofs
  std::array<double, 6> object_dof_m0_{};
  std::array<double, 6> object_dof_invweight0_{};
  std::array<double, 2> object_body_invweight0_{};
  double hand_weight_n_ = 0.0;  ///< weight of everything the wrist servo carries [N]

  double grip_effort_ = 0.0;
  bool brake_engaged_ = false;
  std::array<double, 3> wrist_target_{};
  std::array<double, 3> external_force_{};  ///< on the object [N], re-applied every step
  PhysicsFault fault_;
  double step_start_time_s_ = 0.0;          ///< simulation time when the current Step() began [s]
  std::array<uint64_t, 8> warning_seen_{};  ///< per MuJoCo warning kind, last count seen
};

}  // namespace graspbed::sim
