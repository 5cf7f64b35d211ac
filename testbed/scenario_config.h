#pragma once
/// ScenarioConfig: one scripted grasp experiment read from a scenario YAML file -- the scene (object,
/// hand, physics), the sensor (layout, sampling, strain model, readout), the controller, a seed, a
/// duration, a script of actions (at fixed times or after events) and the expectations a run is
/// scored against. Every key, its unit and its default: docs/scenarios.md.
///
/// Loading validates everything before anything runs: unknown keys, wrong types, out-of-range
/// values and unknown action or controller names are common::ConfigError "file:line: key = value:
/// reason" (with the valid names where there is a list). EmitScenarioYaml writes the fully resolved
/// configuration (every default filled in), which loads again to the same configuration.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/field_table.h"
#include "common/yaml_map.h"
#include "controller/control_loop.h"
#include "controller/grasp_controller.h"
#include "hardware/hardware_config.h"
#include "sensor/inversion.h"
#include "sensor/readout.h"
#include "sensor/strain_model.h"
#include "sim/proprioception.h"
#include "sim/scene_config.h"

namespace graspbed::testbed {

/// Every script action. Names in files: ActionName().
enum class ActionKind {
  kClose,        ///< intent close: the controller grasps and holds
  kOpen,         ///< intent open: the controller releases
  kIdle,         ///< intent idle
  kMove,         ///< wrist to an absolute position or by an offset over duration_s (smooth profile)
  kLift,         ///< wrist up by height_m (negative: down) over duration_s (smooth profile)
  kShake,        ///< sinusoidal wrist oscillation on top of the trajectory
  kAddMass,      ///< add mass to the object, as a step or a ramp (pouring)
  kPull,         ///< external force on the object, as a step or a ramp, optionally for a while
  kSetFriction,  ///< change the object's friction coefficient (step or ramp)
  kDeadUnit,     ///< a unit's channels read open circuit from now on
  kShortUnit,    ///< a unit's channels read short circuit from now on
  kRestoreUnit,  ///< clears a dead/short fault
  kBias,         ///< constant offset on a unit's R1 and R2
  kNoiseBurst,   ///< sensor noise multiplied by a factor for a while
  kDropFrames,   ///< the sensor link loses frames for a while
  kAddLatency,   ///< extra sensor latency from now on
};

/// Name of an action in scenario files ("close", "lift", "add_mass", ...).
const char* ActionName(ActionKind kind);
/// Every action name, in declaration order (for error messages and docs).
std::vector<std::string> ActionNames();

/// What a script action can wait for instead of a fixed time (`after:` in files, names:
/// EventName()). Each is decided once per control tick from what the run knows without ground truth:
/// the script's own intent, the sensor estimate (TactileState) and the controller's slip flag. The
/// thresholds are the metrics' (MetricsConfig) applied to the estimate; docs/scenarios.md, "Waiting
/// for the grasp".
enum class ScriptEvent {
  kNone,         ///< no event: the action fires at its at_s
  kGrasped,      ///< intent close, and the estimate carries >= grasp_force_n on >= 1 contact unit
                 ///< for kEventConfirmS without a break (fresh data only)
  kStable,       ///< grasped for stable_window_s, the estimated total Fn within +-stable_force_band
                 ///< of its mean over that window, and no controller slip flag in it
  kSlipFlagged,  ///< the controller raises its slip flag at this tick
  kReleased,     ///< intent open, and the estimate shows no contact unit and < grasp_force_n in
                 ///< total for kEventConfirmS without a break (fresh data, >= 1 valid unit)
};

/// How long the grasped/released condition must hold without a break before the event counts [s].
inline constexpr double kEventConfirmS = 0.02;

/// The loader bounds the signals a run keeps in memory by these numeric columns per row: at most
/// kSignalBoundFixedColumns before and after the per-unit ones (the loop's, the truth and scoring,
/// a replay's recorded command), kSignalBoundColumnsPerUnit per unit, and
/// controller::kMaxDiagnosticChannels. Each backend asserts at compile time that its columns fit.
inline constexpr size_t kSignalBoundFixedColumns = 80;
inline constexpr size_t kSignalBoundColumnsPerUnit = 7;

/// Name of an event in scenario files ("grasped", "stable", "slip_flagged", "released"; "" for kNone).
const char* EventName(ScriptEvent event);
/// Every event name (kNone excluded), in declaration order.
std::vector<std::string> EventNames();

/// Velocity profile of wrist moves and ramps.
enum class Profile {
  kMinimumJerk,  ///< 10 s^3 - 15 s^4 + 6 s^5: zero velocity and acceleration at both ends
  kLinear,       ///< constant rate
};
const char* ToString(Profile profile);

/// One script action, at a fixed time or after an event. Which fields matter depends on the kind
/// (docs/scenarios.md); the rest keep their defaults and are not written to config.yaml.
///
/// Ordering: fixed-time actions fire at at_s whatever happens. An action with `after` set is armed
/// when the action before it in the script has fired (at time 0 when it is the first); it fires
/// delay_s after the first control tick at or after arming at which its event holds. No such tick
/// within timeout_s of arming (or before the run ends) fails the run, and the action, and every
/// event action after it in the script that waits on it, does not run.
struct Action {
  double at_s = 0.0;  ///< start time [s], simulation clock; unused (0) when `after` is set
  ActionKind kind = ActionKind::kClose;
  int line = 0;                            ///< line in the scenario file (for messages), 0 when built in code
  ScriptEvent after = ScriptEvent::kNone;  ///< the event this action waits for (kNone: at at_s)
  double delay_s = 0.0;                    ///< after an event: fire this long after it [s] (>= 0)
  double timeout_s = 0.0;                  ///< after an event: longest wait for it from arming [s] (> 0)

  /// move: target position [m], world frame (absolute) or offset (relative = true).
  /// pull: force [N], world frame. shake: axis (normalised on load).
  std::array<double, 3> vector = {0.0, 0.0, 0.0};
  bool relative = false;  ///< move: vector is an offset from the current wrist target
  double height_m = 0.0;  ///< lift: vertical displacement [m], + up
  /// move/lift: time to reach the target [s]; shake/noise_burst/drop_frames: how long it lasts [s];
  /// pull: how long the force stays after its ramp (0 = until the end or the next pull) [s].
  double duration_s = 0.0;
  double ramp_s = 0.0;  ///< add_mass/pull/set_friction: ramp time, 0 = step; shake: fade in and out [s]
  Profile profile = Profile::kMinimumJerk;
  double mass_kg = 0.0;       ///< add_mass: mass added [kg] (negative removes, total stays > 0)
  double friction = 0.0;      ///< set_friction: new coefficient [-]
  double frequency_hz = 0.0;  ///< shake [Hz]
  double amplitude_m = 0.0;   ///< shake: peak displacement [m]
  int unit = 0;               ///< dead_unit/short_unit/restore_unit/bias: layout index
  double r1_bias_ohm = 0.0;   ///< bias [Ohm]
  double r2_bias_ohm = 0.0;   ///< bias [Ohm]
  double noise_scale = 1.0;   ///< noise_burst: factor on the configured noise (>= 0)
  double noise_ohm = 0.0;     ///< noise_burst: noise std-dev when none is configured [Ohm]
  double probability = 1.0;   ///< drop_frames: chance each frame is lost [0..1]
  double latency_s = 0.0;     ///< add_latency: extra latency [s]
};

/// What a run must achieve. Every check is optional (absent = not checked).
struct Expectations {
  std::optional<bool> not_dropped;                ///< the object stays in the hand while held
  std::optional<double> max_slip_mm;              ///< accumulated slip distance <= [mm]
  std::optional<double> max_peak_grip_n;          ///< peak squeeze on the object <= [N]
  std::optional<bool> not_crushed;                ///< squeeze never above object.crush_limit_n
  std::optional<double> slip_detected_within_ms;  ///< every gross slip event flagged within [ms]
  std::optional<double> micro_slip_detected_within_ms;  ///< every micro-slip event flagged within [ms]
  /// Mean grip over the held time / the oracle grip <= this [-] (the run computes the oracle).
  std::optional<double> max_grip_efficiency;
  std::optional<double> max_estimation_error_n;   ///< fn_rmse_n and ft_rmse_n <= [N]
  std::optional<double> stable_within_s;          ///< time_to_stable_s <= [s] after the first close
  std::optional<double> max_false_slip_per_min;   ///< false slip alarms per minute held <= [1/min]
  /// The held object sits on the sensorised pad: unsensed_held_s <= MetricsConfig::max_unsensed_held_s
  /// and sensed_grip_share >= MetricsConfig::min_sensed_grip_share. Checked in every run unless set
  /// false (a scene meant to be held off the pad); not counted by empty().
  std::optional<bool> grasped_on_sensor;

  /// True when no check is configured.
  bool empty() const;
};

/// The fields of Expectations (loader, emitter and reference table derive from it; the loader adds
/// not_crushed's need of a fragile object).
const common::FieldTable<Expectations>& ExpectationsFields();

/// Thresholds that define the metrics (docs/scenarios.md, "Metrics").
struct MetricsConfig {
  /// Slip is relative object/fingertip motion at a contact whose friction force is at the edge of
  /// its cone: at least this fraction of mu x its normal force (Coulomb sliding). Inside the cone
  /// MuJoCo's soft friction lets the object rock against the pads (a shake at a third of the
  /// friction limit moved it +-0.09 mm, 7 um net); that is not slip [-].
  double sliding_friction_fraction = 0.95;
  /// Slip also needs the sliding contacts to carry at least this share of their digit's normal force
  /// on the object (GroundTruth::sliding_load_share). Below it a lightly loaded contact at the edge
  /// of the patch slides while the rest sticks: partial slip, the object pivoting a little in a grasp
  /// with margin to spare (a shaken 150 g box: 3-7 % of the pad's force sliding at 4.6 mm/s, 0.1 mm,
  /// with 3x the grip it needed). It is reported as Metrics::partial_slip_mm, opens no slip event, and
  /// a controller flag during it is an incipient-slip flag. 0: any sliding contact is slip [-].
  double slip_min_load_share = 0.2;
  /// Sliding speed below which motion counts as creep, not slip [m/s]; slip distance accumulates
  /// only above it.
  double creep_speed_m_s = 0.5e-3;
  /// Sliding speed above which a slip event starts [m/s].
  double slip_speed_m_s = 2e-3;
  /// A slower slide (above creep_speed_m_s) is a slip event too once it has slid this far without a
  /// pause of slip_event_gap_s; its onset is when it began [m]. 0: only slip_speed_m_s opens events.
  double creep_event_m = 0.0;
  /// A slip event ends after the speed stays below slip_speed_m_s this long [s].
  double slip_event_gap_s = 0.05;
  /// A controller slip flag up to this long before a ground-truth onset counts as detecting it
  /// (incipient slip); later flags count from the onset [s].
  double early_detection_window_s = 0.05;
  /// A slip event that slides at least this far (or ends in a drop) is gross; smaller ones are
  /// micro-slips [m].
  double gross_slip_m = 0.5e-3;
  /// Finger normal force above which the object counts as grasped [N].
  double grasp_force_n = 0.3;
  /// Seating: for this long after a grasp is established the pads settle on the object (the
  /// impact of the closing digits, a flexing pad rolling onto the face). Relative motion then
  /// counts in max_slip_mm but opens no slip event, and controller flags then are not false [s].
  double seating_s = 0.05;
  /// Object displacement relative to the wrist, from where it was when grasped, that counts as
  /// dropped [m]; from where it was at the close command, before the grasp is established, it
  /// counts as pushed out (a failed grasp).
  double drop_distance_m = 0.02;
  /// Acquisition ends and the grasp is established, both digits touching, at the first of: the
  /// object's lowest point this far above the table (the hand carries its weight) [m] ...
  double acquisition_lift_m = 1e-3;
  /// ... the object within acquisition_settle_m of one place relative to the wrist for
  /// acquisition_settle_s (the digits have seated on it) [s], [m] ...
  double acquisition_settle_s = 0.15;
  double acquisition_settle_m = 0.2e-3;
  /// ... the wrist moved this far from where it was at the first touch (an action loads the grasp)
  /// [m] ... or acquisition_max_s after the first touch [s].
  double acquisition_wrist_m = 1e-3;
  double acquisition_max_s = 0.3;
  /// grasped_on_sensor: the longest time the object may be held with no unit loaded at or above the
  /// contact threshold [s], and the least share of the finger's normal force the mesas must carry
  /// over the held time [-] (docs/scenarios.md, "On the sensor").
  double max_unsensed_held_s = 0.1;
  double min_sensed_grip_share = 0.25;
  /// Stable grasp: no slip event and the squeeze within +-stable_force_band of its mean over a
  /// window this long [s].
  double stable_window_s = 0.2;
  double stable_force_band = 0.1;  ///< relative band for the stable squeeze [-]
};

/// The fields of MetricsConfig (loader, emitter and reference table derive from it; the loader adds
/// slip_speed_m_s >= creep_speed_m_s).
const common::FieldTable<MetricsConfig>& MetricsConfigFields();

/// Sensor options of a scenario: which layout, how the simulated backend samples, the strain
/// model's non-ideal effects, the readout and the inversion.
struct SensorOptions {
  /// Layout: "default_20", "paper_3x3" (shipped in sensor/layouts/) or a path to a layout file
  /// (relative to the scenario file).
  std::string layout = "default_20";
  double sample_rate_hz = 1000.0;  ///< sensor frames per second [Hz]
  double latency_s = 0.0;          ///< delay from sampling to delivery [s]
  double drop_probability = 0.0;   ///< chance each frame is lost on the link [0..1]
  /// Where the strain model's kn and kt come from: "paper" (strain_model.kn_per_n / kt_per_n, the
  /// paper's values unless set) or "fea" (graspbed's finite-element analysis of the unit described
  /// by fea_config; overrides strain_model.kn_per_n and kt_per_n). The inversion uses the same
  /// nominal constants either way.
  std::string sensitivities = "paper";
  /// FEA config for sensitivities "fea" (relative to the scenario file); empty = the shipped
  /// sensor/fea/unit_fea.yaml.
  std::string fea_config;
  /// Sensor profile (sensor/sensor_profile.h): "ideal" or a realistic readout chain, resolved
  /// against the sensitivities above; it sets strain_model and readout values, and keys given
  /// explicitly in those sections override it.
  std::string profile = "ideal";
  sensor::StrainModelConfig strain_model;
  sensor::ReadoutConfig readout;
  sensor::InversionConfig inversion;
};

/// The fields of SensorOptions: the plain ones load and emit through it; layout and fea_config
/// paths, the profile's resolution and the strain_model / readout / inversion sections (custom
/// fields) are the scenario loader's.
const common::FieldTable<SensorOptions>& SensorOptionsFields();

/// The controller under test.
struct ControllerOptions {
  /// A built-in controller ("grip_slip", "open_loop") or "plugin:LIBRARY" (controller/plugin_loader.h;
  /// relative library paths already made absolute).
  std::string name = "open_loop";
  /// Parameters by name (controller's declared parameters; unknown ones refused). Defaults of the
  /// controller fill the rest (written out in config.yaml).
  controller::ControllerParams params;
  /// Grip ceiling for the task [N] (e.g. a fragile object); 0 = none.
  double grip_ceiling_n = 0.0;
  double rate_hz = 1000.0;        ///< control ticks per second [Hz]
  double stale_timeout_s = 0.02;  ///< no frame for this long: state stale, controller holds [s]
};

/// The fields of ControllerOptions: grip_ceiling_n, rate_hz and stale_timeout_s load and emit
/// through it; name, plugin and params (custom fields) are LoadControllerOptions' own.
const common::FieldTable<ControllerOptions>& ControllerOptionsFields();

/// Reads a controller section (name or plugin, params, grip_ceiling_n, rate_hz, stale_timeout_s; the
/// same in a scenario and in `graspbed hw --config`). `plugin: LIBRARY` stands for
/// `name: plugin:LIBRARY`; a relative library path is taken relative to the file, and a plugin that
/// does not load is refused at that key. Unknown keys, names and parameters, out-of-range values
/// and the controller's own cross-field checks are refused at the offending key with file and line.
/// @throws common::ConfigError naming file, line, key and value.
ControllerOptions LoadControllerOptions(const common::YamlMap& map,
                                        const std::string& default_name = "open_loop");

/// Where a run's frames come from and its commands go (docs/hardware.md, "One runner, three
/// backends"): the simulation; the hand over a serial link (or `graspbed emulate`); a recording
/// played back through readout, inversion and controller.
enum class Backend { kSim, kSerial, kReplay };

/// "sim", "serial", "replay".
const char* BackendName(Backend backend);

/// A complete scenario.
struct ScenarioConfig {
  std::string name;  ///< default: the file name without .yaml
  std::string description;
  std::string source_file;  ///< file it was loaded from ("" when built in code)
  uint64_t seed = 1;        ///< seeds the sensor noise, spreads and frame drops
  double duration_s = 3.0;  ///< simulated time [s]
  sim::SceneConfig scene;
  SensorOptions sensor;
  /// The hand's joint encoders and motor current sensing in simulation (`proprioception:`; a
  /// profile and overrides, sim/proprioception.h). The serial and replay backends report what the
  /// device or the recording carries instead.
  sim::ProprioceptionConfig proprioception;
  ControllerOptions controller;
  /// Fixed-time actions sorted by at_s (stable); an event action right after the action it follows
  /// in the file (so "the action before it" is the same in the file and here).
  std::vector<Action> script;
  Expectations expectations;
  MetricsConfig metrics;
  Backend backend = Backend::kSim;  ///< `backend:`; `graspbed run --backend`
  /// backend serial: ports, baud and timeouts of the link (`serial:`, as in `hw --config`).
  hardware::HardwareConfig serial;
  /// backend serial: also write every decoded frame to this CSV (optional, "" none); backend replay:
  /// the recording to replay (a run's signals.csv or a frame log; required). `graspbed run --log`.
  std::string log;

  /// Checks the sections (scene, strain model, readout, inversion) and the cross-field rules.
  /// @throws common::ConfigError with the key's path in a scenario file ("sensor.readout.adc_min_ohm",
  ///   "controller.stale_timeout_s") and its value.
  void Validate() const;
};

/// One --set override: dotted key path (object.mass_kg, script[2].at_s) and YAML value text.
struct Override {
  std::string key;
  std::string value;
  /// What the user typed, when not `--set key=value` (e.g. "--controller plugin:x.so"): errors name it.
  std::string origin = {};
};

/// Parses "key=value".
/// @throws common::ConfigError for text without '=' or an empty key.
Override ParseOverride(const std::string& text);

/// Loads and validates a scenario file, applying `overrides` in order.
/// @throws common::ConfigError: errors in the file "file:line: key = value: reason"; errors caused by
///   an override carry the context "--set key=value" (ConfigError::context()) in front.
ScenarioConfig LoadScenario(const std::string& path, const std::vector<Override>& overrides = {});
/// Like LoadScenario, from YAML text; `source_name` stands for the file name in messages and
/// relative layout paths are resolved from its directory.
ScenarioConfig LoadScenarioFromString(const std::string& text, const std::string& source_name,
                                      const std::vector<Override>& overrides = {});

/// Sets `key` (dotted path, list indices as [i]) in `root` to the YAML value `value`, creating
/// maps on the way.
/// @throws common::ConfigError for a malformed path, a value that is not YAML or an index out of range.
void ApplyOverride(YAML::Node& root, const Override& override_value);

/// The fully resolved configuration as YAML (every default filled in; loadable by LoadScenario
/// to the same configuration).
std::string EmitScenarioYaml(const ScenarioConfig& config);

/// Largest sensor latency of the run [s]: sensor.latency_s plus every add_latency action.
double MaxLatencyS(const ScenarioConfig& config);

/// Absolute path of the layout file `config.sensor.layout` names.
std::string ResolveLayoutPath(const ScenarioConfig& config);

}  // namespace graspbed::testbed
