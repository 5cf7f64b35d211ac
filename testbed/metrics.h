#pragma once
/// Scoring of a scenario run: MetricsTracker turns the per-tick ground truth, tactile state and
/// controller telemetry into the metrics of summary.json (definitions: docs/scenarios.md,
/// "Metrics"), and EvaluateExpectations checks them against a scenario's expectations.
/// Update() allocates nothing (fixed-capacity event storage).

#include <array>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "controller/grasp_controller.h"
#include "sensor/strain_model.h"
#include "sensor/tactile_state.h"
#include "sim/simulation.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {

/// One ground-truth slip event while the object was held.
struct SlipEvent {
  double onset_s = 0.0;         ///< first tick with relative speed above slip_speed_m_s [s]
  double end_s = 0.0;           ///< last tick above it [s] (event closes slip_event_gap_s later)
  double peak_speed_m_s = 0.0;  ///< [m/s]
  double distance_m = 0.0;      ///< slip distance accumulated during the event [m]
  bool detected = false;        ///< a controller slip flag matched the event
  /// Some unit carried a normal force of at least the contact threshold at a tick of the event's
  /// sliding (from the tick it opened, a creep's back-dated onset aside, to its end). An event
  /// without is one the tactile sensor had nothing to report on (the object sliding on an unsensed
  /// part of the finger, e.g. the fingertip cap while a grasp forms).
  bool sensed = false;
  /// Which digits slid at the event's ticks: contacts of that digit at the friction limit faster
  /// than slip_speed_m_s (creep_speed_m_s at a creep event's ticks). Only the thumb: the object slid
  /// on the unsensed digit while the sensed finger's contact stuck.
  bool finger_slid = false;
  bool thumb_slid = false;
  /// The object was dropped while this event was open (an event opened at the drop if none was).
  bool ends_in_drop = false;
  /// Gross slip: slid at least MetricsConfig::gross_slip_m or ended in a drop; what a hand must
  /// catch. Smaller events are micro-slips (the soft contact's slides), reported, not targeted.
  bool gross = false;
  double latency_s = 0.0;  ///< flag time - onset, >= 0 (0 for an early flag) [s]
};

/// Counts of one class of slip events (gross or micro).
struct SlipClassCounts {
  int events = 0;    ///< events of the class while held
  int detected = 0;  ///< of those, flagged by the controller
  /// Largest detection latency over the detected events of the class [ms]; nullopt with none.
  std::optional<double> worst_latency_ms;
};

/// The oracle's figures for a run (graspbed oracle; docs/scenarios.md, "The oracle grip").
struct OracleGrip {
  /// The lightest constant grip that holds the scenario (no drop, no gross slip, on the sensorised
  /// pad) on the ideal sensor: the mean true squeeze over the held time of that constant_grip run [N]; nullopt when
  /// the motor's stall force does not hold it (reason says so).
  std::optional<double> grip_n;
  std::string reason;  ///< why grip_n is absent ("" when present)
};

/// The metrics of one run.
struct Metrics {
  /// The grasp was established at some point after a close: both digits in contact, then the object
  /// lifted off the table, still in the hand, the wrist moving or time up (MetricsConfig's
  /// acquisition_*; docs/scenarios.md, "Acquisition and holding").
  bool grasped = false;
  double grasp_time_s = -1.0;    ///< when it first was [s]; < 0 never
  double contact_time_s = -1.0;  ///< when both digits first touched the object [s]; < 0 never
  /// Largest displacement of the object relative to the wrist from the digits' first touch to the
  /// established grasp, over the run's grasps: the object moving while the digits close and seat
  /// (acquisition, not slip) [mm].
  double acquisition_shift_mm = 0.0;
  /// The object moved more than MetricsConfig::drop_distance_m relative to the wrist between a close
  /// command and the established grasp (pushed out, knocked over, or left behind by a wrist that
  /// moved on before the digits met it); such a run is also `dropped`.
  bool pushed_out = false;
  bool dropped = false;        ///< left the hand while held (or was never grasped, or pushed out)
  /// Close commands (intent close, until it changes or the run ends) during which the object was
  /// never grasped: a regrasp that missed, a grip too light to count (the first close's miss is
  /// also `dropped`).
  int ungrasped_closes = 0;
  double drop_time_s = -1.0;   ///< [s]; < 0 not dropped
  double max_slip_mm = 0.0;    ///< slip distance accumulated above the creep speed while held [mm]
  /// Distance slid while held by contacts carrying less than MetricsConfig::slip_min_load_share of
  /// their digit's force, the rest sticking (partial slip; not in max_slip_mm) [mm].
  double partial_slip_mm = 0.0;
  double peak_grip_n = 0.0;  ///< largest squeeze on the object over the run [N]
  bool crushed = false;      ///< peak_grip_n above object.crush_limit_n (fragile objects only)
  /// Mean squeeze on the object over the time held [N] (0 when never held).
  double mean_held_grip_n = 0.0;
  /// Largest squeeze-independent lower bound of the grip while held (GroundTruth::load_bound_grip_n:
  /// the hand's load over 2 mu) [N].
  double peak_load_bound_grip_n = 0.0;
  /// Where the grasp meets the sensor, over the held time. sensed_grip_share: the normal force the
  /// mesas press on the object over the index finger's whole normal force on it (holder, tip cap,
  /// phalanges; a fingertip brushing the table counts in neither), both
  /// integrated over the held time [-]; nullopt when never held or the finger carried nothing.
  std::optional<double> sensed_grip_share;
  /// Time held with no unit's true normal force at or above the contact threshold, outside slip
  /// events (an object sliding out of the hand leaves the pad on its way) [s].
  double unsensed_held_s = 0.0;
  /// The unit (layout order) whose true normal force integrated over the held time is largest: where
  /// the contact sits on the fingertip; -1 when no unit was loaded while held.
  int contact_unit = -1;
  /// The oracle grip of the scenario, when the run asked for it (RunOptions::oracle).
  std::optional<OracleGrip> oracle;
  /// mean_held_grip_n / the oracle grip: how many times the lightest grip that holds the hand held
  /// on average [-]; nullopt without an oracle grip or a held time.
  std::optional<double> grip_efficiency;
  /// peak_grip_n / the oracle grip [-]; nullopt without an oracle grip.
  std::optional<double> peak_grip_ratio;
  /// Largest detection latency over the slip events [ms]; nullopt when no slip event happened.
  std::optional<double> slip_detect_latency_ms;
  SlipClassCounts gross;                ///< gross slip events (SlipEvent::gross)
  SlipClassCounts micro;                ///< micro-slip events (the rest)
  int slip_events = 0;                  ///< ground-truth slip events while held
  int missed_slip_events = 0;           ///< of those, never flagged by the controller
  int missed_unsensed_slip_events = 0;  ///< of the missed, those with no unit loaded (SlipEvent::sensed)
  /// Of the missed, those where only the thumb slid (SlipEvent::thumb_slid, not finger_slid).
  int missed_thumb_only_slip_events = 0;
  int controller_slip_flags = 0;  ///< rising edges of the controller's slip flag while held
  /// Flags matching no slip event with no contact sliding at the friction limit (above creep speed)
  /// in the early_detection_window_s before them: the contact was not slipping at all.
  int false_slip_flags = 0;
  /// false_slip_flags by the controller's slip_cues label at the flag's rise ("" as "(none)"; past
  /// MetricsTracker::kMaxCueLabels labels, "(other)").
  std::map<std::string, int> false_slip_flags_by_cue;
  double false_slip_per_min = 0.0;  ///< false_slip_flags per minute held [1/min]
  /// Flags matching no slip event but raised at most early_detection_window_s after a contact slid
  /// at the friction limit faster than creep_speed_m_s (and slower than slip_speed_m_s): an
  /// incipient or partial slip too slow to be an event (a load landing, a pull ending). Neither
  /// detections nor false alarms; counted apart.
  int incipient_slip_flags = 0;
  /// Time the controller's slip flag was up while held, outside slip events and seating [s]. A flag
  /// that stays up counts once in false_slip_flags; this is what it costs.
  double false_slip_flag_s = 0.0;
  /// false_slip_flag_s as a share of the time held [%].
  double false_slip_flag_pct = 0.0;
  double held_s = 0.0;              ///< time the object was held [s]
  std::optional<double> fn_rmse_n;  ///< per-unit Fn estimation RMSE over contact samples [N]
  std::optional<double> ft_rmse_n;  ///< per-unit Ft estimation RMSE over the same samples [N]
  int64_t estimation_samples = 0;   ///< (tick, unit) pairs in the RMSEs
  /// Time from the first close to the start of the first stable window [s]; nullopt never stable.
  std::optional<double> time_to_stable_s;
  double sim_s = 0.0;          ///< simulated time [s]
  double wall_s = 0.0;         ///< wall-clock time of the run [s]
  bool physics_fault = false;  ///< NaN or MuJoCo warning during the run
  std::string physics_fault_cause;
  double physics_fault_time_s = 0.0;
  std::vector<SlipEvent> events;  ///< every slip event (first kMaxEvents)
};

/// What one tick tells the tracker. References are only read during Update().
struct TickSample {
  double time_s = 0.0;
  controller::GraspIntent intent = controller::GraspIntent::kIdle;
  const sim::GroundTruth* truth = nullptr;
  const sensor::TactileState* state = nullptr;
  /// True unit loads at the sample time of `state`, layout order (estimation error reference).
  std::span<const sensor::UnitLoad> true_loads;
  bool controller_slip = false;      ///< telemetry().slip_detected at this tick
  const char* controller_cues = "";  ///< telemetry().slip_cues at this tick (a static string)
};

/// Accumulates the metrics tick by tick.
class MetricsTracker {
 public:
  /// Most slip events kept with their details (more are counted, not stored).
  static constexpr int kMaxEvents = 256;
  /// Distinct slip_cues labels whose false flags are counted apart.
  static constexpr int kMaxCueLabels = 8;

  /// `contact_threshold_n`: per-unit Fn above which a (tick, unit) pair enters the RMSEs [N].
  MetricsTracker(const MetricsConfig& config, double crush_limit_n, double contact_threshold_n);

  /// One control tick. Allocates nothing.
  void Update(const TickSample& sample);

  /// Whether the object counts as held now (grasped and intent close).
  bool holding() const { return holding_; }
  /// Whether a slip event is open now.
  bool in_slip_event() const { return event_open_; }
  /// Slip distance accumulated so far [m].
  double slip_distance_m() const { return slip_distance_m_; }

  /// Closes open events and returns the metrics; `first_close_time_s` < 0 when no close fired.
  Metrics Finish(double sim_s, double wall_s, double first_close_time_s) const;

 private:
  // Update's parts, in this order: the grasp (established, held, dropped), slip events and the
  // controller's flags while held, the estimate's error, the first stable stretch of squeeze [N].
  void UpdateGrasp(const TickSample& sample, double dt);
  /// From the digits' first touch to the established grasp (or a push-out) during a close.
  void UpdateAcquisition(const TickSample& sample);
  /// While held: how much of the finger's squeeze lands on the units, and which unit carries it.
  void UpdateSensorContact(const TickSample& sample, double dt);
  void UpdateSlip(const TickSample& sample, double dt);
  void UpdateEstimationError(const TickSample& sample);
  void UpdateStableGrasp(double squeeze_n, double time_s);
  /// A flag not (yet) matched to an event, within the early-detection window of now.
  struct PendingFlag {
    double time_s = 0.0;
    bool after_sliding = false;  ///< a contact slid above creep speed within the window before it
    const char* cues = "";       ///< the controller's slip_cues at the rise
  };
  /// False flags of one slip_cues label.
  struct CueCount {
    const char* cues = "";
    int false_flags = 0;
  };
  /// Opens an event at `time_s` whose onset was `onset_s` (earlier for a creep, which becomes an event
  /// only once it has crept MetricsConfig::creep_event_m).
  void OpenEvent(double time_s, double onset_s);
  void CloseEvent();
  /// One tick of the open event: which digits slid faster than `digit_speed_m_s`, whether a unit
  /// carried load.
  void NoteEventTick(const TickSample& sample, double digit_speed_m_s);
  void OnControllerFlag(double time_s, const char* cues);
  /// A flag that matched no event: false, or incipient when a contact slid just before it.
  void JudgeUnmatchedFlag(const PendingFlag& flag);

  MetricsConfig config_;
  double crush_limit_n_ = 0.0;
  double contact_threshold_n_ = 0.0;
  double last_time_s_ = -1.0;

  bool grasped_ever_ = false;
  double grasp_time_s_ = -1.0;
  // Acquisition: both digits touching since the latest close (touching_), where the object was then
  // and where its current still stretch began, relative to the wrist [m], and that stretch's start [s].
  bool touching_ = false;
  double contact_time_s_ = -1.0;   ///< the run's first touch [s]
  double contact_start_s_ = -1.0;  ///< this close's first touch [s]
  std::array<double, 3> close_offset_m_{};  ///< object - wrist at the latest close command [m]
  std::array<double, 3> touch_offset_m_{};
  std::array<double, 3> settle_offset_m_{};
  std::array<double, 3> touch_wrist_m_{};
  double settle_start_s_ = -1.0;
  double acquisition_shift_m_ = 0.0;
  bool pushed_out_ = false;
  // Sensor contact while held: mesa and finger normal force integrated [N s], time with no unit
  // loaded [s], each unit's normal force integrated [N s].
  double sensed_integral_n_s_ = 0.0;
  double finger_integral_n_s_ = 0.0;
  double unsensed_held_s_ = 0.0;
  std::array<double, sensor::kMaxUnits> unit_integral_n_s_{};
  double grasp_start_s_ = -1.0;  ///< when the current grasp was established [s]
  bool grasped_ = false;         ///< grasped since the latest close
  bool closing_ = false;         ///< the intent is close (a close episode is open)
  int ungrasped_closes_ = 0;
  bool holding_ = false;
  std::array<double, 3> reference_offset_m_{};  ///< object - wrist when grasped [m]
  bool dropped_ = false;
  double drop_time_s_ = -1.0;
  double held_s_ = 0.0;

  double slip_distance_m_ = 0.0;
  double partial_slip_distance_m_ = 0.0;
  double peak_grip_n_ = 0.0;
  double held_grip_integral_n_s_ = 0.0;  ///< squeeze integrated over the held time [N s]
  double peak_load_bound_grip_n_ = 0.0;

  std::array<SlipEvent, kMaxEvents> events_{};
  int event_count_ = 0;  ///< events started (may exceed kMaxEvents)
  bool event_open_ = false;
  /// The current creep: sliding above creep speed since creep_start_s_ (< 0: none) [s], the latest
  /// such tick [s] and the distance so far [m].
  double creep_start_s_ = -1.0;
  double creep_last_s_ = 0.0;
  double creep_distance_m_ = 0.0;
  SlipEvent current_{};
  double last_above_s_ = 0.0;
  bool previous_flag_ = false;
  double last_rise_s_ = -1e9;  ///< time of the flag's latest rising edge [s]
  int flags_ = 0;
  int false_flags_ = 0;
  std::array<CueCount, kMaxCueLabels> false_by_cue_{};
  int cue_labels_ = 0;
  int false_other_cues_ = 0;  ///< false flags of labels beyond kMaxCueLabels
  int incipient_flags_ = 0;
  double last_sliding_s_ = -1e9;  ///< latest held tick with a contact sliding above creep speed [s]
  double false_flag_s_ = 0.0;
  std::array<PendingFlag, 64> pending_flags_{};
  int pending_count_ = 0;
  int missed_ = 0;
  int missed_unsensed_ = 0;
  int missed_thumb_only_ = 0;
  double worst_latency_s_ = -1.0;
  std::array<int, 2> class_events_{};  ///< [micro, gross]
  std::array<int, 2> class_detected_{};
  std::array<double, 2> class_worst_latency_s_{-1.0, -1.0};

  double fn_square_sum_ = 0.0;
  double ft_square_sum_ = 0.0;
  int64_t estimation_samples_ = 0;

  // Stable-window search: start of the current candidate window and squeeze range within it.
  double stable_start_s_ = -1.0;
  double stable_min_n_ = 0.0;
  double stable_max_n_ = 0.0;
  double stable_found_s_ = -1.0;
};

/// Outcome of one expectation.
struct ExpectationOutcome {
  std::string name;             ///< key in the scenario's expectations section
  std::string limit;            ///< the limit as written ("<= 2 mm", "true")
  std::optional<double> value;  ///< the measured value (nullopt where there is none)
  std::string value_text;       ///< the measured value for tables ("1.23 mm", "none")
  bool passed = false;
  std::string note;  ///< why, when not obvious
};

/// Checks `metrics` against every configured expectation (in a fixed order), plus the implicit
/// "no_physics_fault" that every run must meet and "grasped_on_sensor" unless set false (its limits
/// from `config`).
std::vector<ExpectationOutcome> EvaluateExpectations(const Expectations& expectations, const Metrics& metrics,
                                                     const MetricsConfig& config);

/// Fills metrics.oracle, grip_efficiency and peak_grip_ratio from the scenario's oracle grip.
void ApplyOracle(const OracleGrip& oracle, Metrics& metrics);

}  // namespace graspbed::testbed
