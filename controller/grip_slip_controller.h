#pragma once
/// The reference grip-slip controller (docs/controller.md). Phases as in grasp controllers that have
/// worked on real hands (Romano et al. 2011 on the PR2; grip-load coupling after Johansson and
/// Westling): close until contact, load to an initial grip, hold with the grip force coupled to the
/// measured tangential load over an estimated friction coefficient times a safety margin, respond to
/// slip by raising the grip within a few milliseconds and learning the friction coefficient from the
/// ratio at slip, release on command, and hold the last safe command whenever the data are stale or
/// too few units are valid (it never opens the hand because data stopped).
///
/// The grip force is closed-loop on the measured normal force (sum over valid units, saturated units
/// counted at the rated range) with feed-forward + PI and anti-windup, since the motor effort to
/// force map depends on the object. Sees only TactileState, the hand's own state, time and intent.
///
/// With proprioception (`proprioception` 1, the default; the hand reports its motor current and
/// joints) it also keeps the grip's absolute numbers (initial grip, floor, ceiling, slip step) on the
/// object's real squeeze when the units see only part of it (MotorSqueeze's sensed share), and stops
/// driving a closing that reached the closed end stop without finding anything (phase "missed").
/// Without it, or on a hand that does not report them, it behaves as before.

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "controller/filters.h"
#include "controller/grasp_controller.h"
#include "controller/learned_slip_cue.h"
#include "controller/motor_squeeze.h"
#include "controller/slip_detector.h"

namespace graspbed::controller {

/// Every setting of the grip-slip controller; each is also a controller parameter (GripSlipController::
/// Parameters() lists name, default, range, unit and meaning; docs/controller.md has the table).
struct GripSlipConfig {
  // Closing and release.
  double close_effort = 0.3;       ///< motor effort while closing towards the object [-]
  double open_effort = 0.5;        ///< motor effort magnitude while releasing [-]
  double release_time_s = 0.5;     ///< opening effort is applied this long after an open command [s]
  int contact_min_units = 1;       ///< valid units above the contact threshold that mean contact
  int contact_confirm_frames = 3;  ///< consecutive frames with contact before loading starts
  double contact_lost_s = 0.1;     ///< no contact unit this long while holding: close again [s]
  int min_valid_units = 3;         ///< fewer valid units than this: safe hold

  // Grip force targets.
  double initial_grip_n = 2.0;      ///< grip reached in the loading phase [N]
  double load_rate_n_per_s = 20.0;  ///< ramp rate of the grip target while loading [N/s]
  double load_timeout_s = 0.3;      ///< loading ends after this long even if the grip lags [s]
  double min_grip_n = 1.5;          ///< grip target never drops below this while holding [N]
  double max_grip_n =
      10.0;  ///< overall grip ceiling, sum over the units (tuning choice, docs/controller.md) [N]
  double safety_margin = 1.4;               ///< grip = tangential load / friction estimate x this
  /// Share of the shear locked in when the grasp settled (SlipSignals::preload_shear_*) that the
  /// hold grip is coupled to, besides the load added since [-]: 1 couples to the whole shear the
  /// contact holds, 0 to the load alone (the preload of a non-antipodal pinch is made by the squeeze
  /// and shrinks with it, so coupling to it asks a hard squeeze for a hard squeeze).
  double preload_coupling = 0.0;
  double grip_decrease_rate_n_per_s = 2.0;  ///< how fast the coupled target may fall [N/s]
  double unit_range_n = 10.0;               ///< a saturated (out-of-range) unit counts as this force [N]
  /// With a sensor that cannot resolve shear (SlipSignals::shear_blind) the hold grip is this
  /// fraction of the ceiling: the load is unknown, so the grip is set for the heaviest it may be.
  double shear_blind_grip_fraction = 0.8;

  // Friction estimate.
  double friction_initial = 0.5;           ///< friction coefficient assumed at the start of each grasp
  double friction_min = 0.15;              ///< the estimate never goes below this
  double friction_learn_rate = 1.0;        ///< fraction of the way towards the ratio observed at slip
  double friction_learn_min_load_n = 0.2;  ///< learn only from slips under at least this tangential load [N]
  /// One slip lowers the estimate by at most this fraction of it; a slip at a ratio further below
  /// the estimate (a jolt, not the friction limit) teaches nothing.
  double friction_learn_max_drop = 0.5;

  // Force loop (feed-forward + PI with anti-windup) on the measured grip.
  double effort_per_newton = 0.05;  ///< feed-forward effort per newton of target (1 / the 20 N stall pinch)
  double kp_effort_per_n = 0.04;    ///< proportional gain [1/N]
  double ki_effort_per_n_s = 1.5;   ///< integral gain [1/(N s)]
  double integrator_limit = 0.5;    ///< bound of the integral term [-]
  double max_effort = 1.0;          ///< largest closing effort ever commanded [-]
  double ceiling_effort_margin = 1.0;  ///< effort cap = this x effort_per_newton x grip ceiling
  double grip_filter_s = 0.002;        ///< low-pass time constant of the measured grip [s]
  /// With the target at its ceiling the P term acts only on the grip error beyond this band [N]: a P
  /// term answering the units' summed noise there shakes the contact (docs/controller.md).
  double ceiling_deadband_n = 0.15;

  // Slip response.
  double slip_grip_gain = 0.25;           ///< on slip, grip target = grip x (1 + this) + step
  double slip_grip_step_n = 0.5;          ///< additive part of the slip response [N]
  double slip_refractory_s = 0.04;        ///< a new slip event is counted no sooner than this [s]
  /// A cue still up after a slip response (no frame without slip since) asks for another only once
  /// the measured grip has reached this fraction of the raised floor and the ratio cue still counts
  /// [-]; a cue that fell and rose again always may.
  double slip_landed_fraction = 0.9;
  /// While only the vibration cue keeps reporting slip after a response, the slip floor rises this
  /// fast [N/s] (slip_grip_rate_n_per_s is for the load cues); 0 = off.
  double slip_vibration_rate_n_per_s = 0.0;
  double slip_floor_decay_n_per_s = 0.5;  ///< the raised grip after slip relaxes this fast [N/s]
  /// While the cues keep reporting slip after a response (a load the step did not cover), the slip
  /// floor keeps rising at this rate until the next event may raise it again [N/s]; 0 = off.
  double slip_grip_rate_n_per_s = 100.0;
  /// With the target at its ceiling, the ratio cue counts as slip only this long after its episode
  /// rose [s]; 0 = not at all (the grip can rise no further, and the cue then says the load is
  /// beyond what the ceiling holds at the friction estimate, not that the contact slides; the
  /// vibration cue still flags). The centroid cue is held with it.
  double ratio_ceiling_count_s = 0.0;
  /// With the target at its ceiling, a ratio cue that rises again within this time of falling
  /// continues the episode it rose in (a load hovering at the threshold), rather than being a new
  /// slip [s]; 0 = every rise is new. Matters with ratio_ceiling_count_s > 0.
  double ratio_ceiling_rearm_s = 0.25;
  /// The reported slip flag stays up this long after the last frame a cue counted as slip, so a
  /// cue flickering about its threshold within one episode is one flag, not one per crossing [s];
  /// 0 = the flag follows the cues frame by frame. The grip response follows the cues either way.
  double slip_flag_hold_s = 0.005;

  SlipDetectorConfig slip;  ///< slip detection cues (their own parameters)
  /// Use the hand's proprioception (motor current, joints) where the hand reports it.
  bool use_proprioception = true;
  MotorSqueezeConfig motor;  ///< the motor's squeeze estimate
  /// Also count the learned slip cue (controller/learned_slip_cue.h; the model file
  /// $GRASPBED_SLIP_MODEL, else the shipped models/slip/default_20.json) as slip, beside the
  /// hand-tuned cues.
  bool learned_cue = false;

  /// @throws common::ConfigError keyed by the offending parameter (its name among Parameters(),
  /// also for a detector field: "detector_settle_s" for slip.settle_s), with its value, in the
  /// context "controller 'grip_slip'".
  void Validate() const;
};

/// Internals exposed for logging and tests, filled every update.
struct GripSlipDiagnostics {
  double measured_grip_n = 0.0;  ///< filtered grip force the loop closes on [N]
  double effort = 0.0;           ///< commanded effort [-]
  double integrator = 0.0;       ///< integral term of the force loop [-]
  double ceiling_n = 0.0;        ///< effective grip ceiling (overall and per task) [N]
  double slip_floor_n = 0.0;     ///< grip raised by the last slip response, decaying [N]
  int saturated_units = 0;       ///< units out of range in the newest frame
  double motor_squeeze_n = 0.0;  ///< squeeze the motor current says (0 unknown) [N]
  double sensed_share = 1.0;     ///< share of the squeeze the units see, as the grip's scale [-]
  SlipSignals signals;           ///< what the slip detector saw
};

class GripSlipController final : public GraspController {
 public:
  /// Validates `config` (@throws common::ConfigError, as GripSlipConfig::Validate).
  explicit GripSlipController(const GripSlipConfig& config);

  /// Parameter declarations for the factory, defaults from GripSlipConfig.
  static std::vector<ControllerParameter> Parameters();
  /// Config from a factory-resolved parameter map (every declared name present, values in range).
  /// @throws common::ConfigError keyed by the parameter for a non-integer count or a failed
  /// Validate().
  static GripSlipConfig ConfigFromParams(const ControllerParams& params);

  void Reset() override;
  void SetIntent(GraspIntent intent) override;
  hand::HandCommand Update(const sensor::TactileState& state, const hand::HandState& hand,
                           double time_s) override;
  /// Per-task ceiling [N]; the effective ceiling is min(this, max_grip_n). A value <= 0 or +inf
  /// removes the task ceiling; NaN throws std::invalid_argument. Survives Reset().
  void SetGripCeiling(double ceiling_n) override;
  ControllerTelemetry telemetry() const override { return telemetry_; }
  std::string name() const override { return "grip_slip"; }
  /// The detector's statistics and thresholds, the measured grip and the slip floor
  /// (docs/controller.md, "Slip cues").
  std::span<const DiagnosticChannel> diagnostic_channels() const override;
  void ReadDiagnostics(std::span<double> values) const override;

  const GripSlipDiagnostics& diagnostics() const { return diagnostics_; }
  const GripSlipConfig& config() const { return config_; }

 private:
  enum class Phase { kIdle, kClosing, kMissed, kLoading, kHolding, kSlip, kReleasing, kOpen };
  static const char* PhaseName(Phase phase);

  void Enter(Phase phase, double time_s);
  /// The grip ceiling on the object's squeeze [N] (overall and per task).
  double CeilingN() const;
  /// The same in the units' measure: scaled by the sensed share [N].
  double SensedCeilingN() const;
  /// An absolute grip figure (floor, initial grip, slip step) in the units' measure [N].
  double Sensed(double squeeze_n) const;

  // One tick, in order (Update): the clock and the intent, the safe hold on bad data, the frame,
  // then the phase's own function, then the telemetry.
  double AdvanceClock(double time_s);
  void FollowIntent(double time_s);
  hand::HandCommand SafeHold();
  bool TakeFrame(const sensor::TactileState& state, bool data_ok, double time_s);
  hand::HandCommand Close(bool new_frame, double time_s);
  hand::HandCommand Hold(double time_s, double dt_s, bool* slip_now);
  hand::HandCommand Release(double time_s);
  /// Counts the cues as slip or not (the ratio cue held at the ceiling; SlipCueGate).
  bool CountCues(double time_s);
  /// Raises the slip floor while cues persist after a response; responds to a new slip.
  void FollowSlip(bool slip_now, double time_s, double dt_s);
  hand::HandCommand Report(const hand::HandCommand& command, bool slip_now, bool data_ok, double time_s);
  /// Largest closing effort allowed under the current ceiling [-].
  double EffortCap() const;
  /// Force loop: effort for `target_n` given the measured grip; updates the integrator.
  double ForceLoop(double target_n, double grip_n, double dt_s, bool may_increase);
  void UpdateHoldTarget(double dt_s);
  void RespondToSlip(double time_s);

  GripSlipConfig config_;
  SlipDetector detector_;
  MotorSqueeze motor_;
  std::unique_ptr<LearnedSlipCue> learned_;  ///< null unless config_.learned_cue
  bool learned_counts_ = false;              ///< the learned cue counts as slip now
  LowPassFilter grip_filter_;

  GraspIntent intent_ = GraspIntent::kIdle;
  Phase phase_ = Phase::kIdle;
  double phase_start_s_ = 0.0;
  bool safe_hold_ = false;
  double task_ceiling_n_ = 0.0;  ///< 0 = none set

  bool have_time_ = false;
  double last_time_s_ = 0.0;
  bool have_frame_ = false;
  uint32_t last_sequence_ = 0;
  double last_frame_time_s_ = 0.0;

  int contact_frames_ = 0;
  double last_contact_s_ = 0.0;
  double friction_ = 0.0;
  double load_target_n_ = 0.0;
  double coupled_target_n_ = 0.0;
  double slip_floor_n_ = 0.0;
  double target_n_ = 0.0;
  double integrator_ = 0.0;
  double refractory_until_s_ = 0.0;
  bool cue_fell_since_response_ = true;  ///< a frame without slip since the last slip response
  bool ratio_was_up_ = false;     ///< the ratio cue was up in the last frame
  bool ratio_counts_ = false;     ///< the ratio cue counts as slip now (not held at the ceiling)
  bool centroid_counts_ = false;  ///< the centroid cue counts as slip now (likewise)
  double ratio_rise_s_ = 0.0;     ///< when the ratio cue's current episode began [s]
  /// A time before any other: a cue that never fell did not fall "just now".
  static constexpr double kNeverS = -std::numeric_limits<double>::infinity();
  double ratio_fall_s_ = kNeverS;  ///< when the ratio cue last fell [s]
  double flag_until_s_ = kNeverS;  ///< the reported slip flag stays up until then [s]
  const char* flag_cues_ = "";     ///< cues named by the reported flag while it is held [-]
  hand::HandCommand last_good_command_;

  ControllerTelemetry telemetry_;
  GripSlipDiagnostics diagnostics_;
};

}  // namespace graspbed::controller
