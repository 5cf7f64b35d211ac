#pragma once
/// ScriptPlayer: plays a scenario's actions on a running SimRig -- the user's intent to the
/// controller, wrist moves and shakes to the wrist servo target, mass, friction and external force to
/// the object, faults to the simulated sensor. Update() is called before every physics step with the
/// simulated time, Observe() after every control tick (it feeds the events that actions with `after`
/// wait for); neither allocates.

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "controller/grasp_controller.h"
#include "sensor/tactile_state.h"
#include "sim/sim_rig.h"
#include "testbed/metrics.h"
#include "testbed/scenario_config.h"
#include "testbed/script_events.h"

namespace graspbed::testbed {

/// Smooth 0..1 progress of a move or ramp at normalised time `s` in [0, 1] (clamped).
double ProfileProgress(Profile profile, double s);

/// When one script action was armed, saw its event and fired [s]; < 0 where it did not happen.
struct ActionTiming {
  double armed_s = -1.0;      ///< event actions: when the action before it fired (0 for the first)
  double event_s = -1.0;      ///< event actions: the control tick at which the event was seen
  double fired_s = -1.0;      ///< when the action fired (every action)
  double timed_out_s = -1.0;  ///< event actions: when the wait was given up (armed_s + timeout_s)
};

/// Plays one script on one rig. Holds no reference to the rig between calls.
class ScriptPlayer {
 public:
  /// `config.script` ordered as ScenarioConfig keeps it (fixed-time actions by at_s, an event
  /// action right after the action it follows); `seed` drives the frame-drop draws.
  ScriptPlayer(const ScenarioConfig& config);

  /// Takes the rig's initial wrist target, object mass and friction as the starting point and sets
  /// the grip ceiling. Call once before the first Update().
  void Start(sim::SimRig& rig);
  /// Fires every action due at or before `time_s` [s] -- fixed-time actions first (by at_s), then
  /// event actions in script order, so a chain of event actions whose events hold fires in one call --
  /// and applies the continuous ones (moves, shakes, ramps, timed faults) for that instant. Gives up
  /// an event action whose wait has reached its timeout_s. Allocates nothing.
  void Update(double time_s, sim::SimRig& rig);
  /// After a control tick at `time_s` [s]: decides which events hold from the estimate `state` and
  /// the controller's `slip_flag` (ScriptEventMonitor) and records them for armed event actions.
  /// Allocates nothing.
  void Observe(double time_s, const sensor::TactileState& state, bool slip_flag);

  /// Per action of the script (same order): when it was armed, saw its event, fired or timed out.
  const std::vector<ActionTiming>& timings() const { return timings_; }
  /// One outcome per event action for the run's expectation list: passed when it fired; failed
  /// (naming the action, its line, the event and the timeout) when its event did not come within
  /// timeout_s, the run ended first, or the action before it never ran. `end_s`: the run's end [s].
  std::vector<ExpectationOutcome> EventOutcomes(double end_s) const;

  /// The intent last given to the controller.
  controller::GraspIntent intent() const { return intent_; }
  /// Time of the first close action that has fired, or < 0 before it [s].
  double first_close_time_s() const { return first_close_time_s_; }
  /// Actions fired so far.
  int fired_count() const { return fired_count_; }
  /// Current wrist target without the shake offset [m], world frame.
  const std::array<double, 3>& base_wrist_target_m() const { return base_target_; }
  /// External force now applied to the object [N], world frame.
  const std::array<double, 3>& external_force_n() const { return force_now_; }

 private:
  void Fire(const Action& action, double time_s, sim::SimRig& rig);
  /// Fires the event actions that are due, in script order.
  void UpdateEventActions(double time_s, sim::SimRig& rig);

  /// A value moving from `from` to `to` over [start, start + duration] along a profile.
  struct Ramp {
    double from = 0.0;
    double to = 0.0;
    double start_s = 0.0;
    double duration_s = 0.0;
    Profile profile = Profile::kLinear;
    bool active = false;
    double At(double time_s) const;
  };

  std::vector<Action> script_;
  SensorOptions sensor_;
  double grip_ceiling_n_ = 0.0;
  std::vector<size_t> fixed_actions_;  ///< indices of fixed-time actions, by at_s
  std::vector<size_t> event_actions_;  ///< indices of event actions, in script order
  size_t next_fixed_ = 0;
  int fired_count_ = 0;
  std::vector<ActionTiming> timings_;
  ScriptEventMonitor monitor_;
  uint32_t tick_events_ = 0;   ///< EventBit()s that held at the latest control tick
  double tick_time_s_ = -1.0;  ///< time of the latest control tick (< 0: none yet)
  controller::GraspIntent intent_ = controller::GraspIntent::kIdle;
  double first_close_time_s_ = -1.0;

  // Wrist: one move at a time, one shake at a time on top.
  std::array<double, 3> base_target_{};
  std::array<double, 3> move_from_{};
  std::array<double, 3> move_to_{};
  double move_start_s_ = 0.0;
  double move_duration_s_ = 0.0;
  Profile move_profile_ = Profile::kMinimumJerk;
  bool moving_ = false;
  std::array<double, 3> shake_axis_{};
  double shake_start_s_ = 0.0;
  double shake_end_s_ = -1.0;
  double shake_frequency_hz_ = 0.0;
  double shake_amplitude_m_ = 0.0;
  double shake_ramp_s_ = 0.0;  ///< fade in and out [s]

  // Object: mass, friction and external force as ramps towards their latest targets.
  Ramp mass_;
  Ramp friction_;
  std::array<Ramp, 3> force_;
  std::array<double, 3> force_now_{};
  double force_release_s_ = -1.0;  ///< pull with a duration: force back to zero at this time

  // Sensor faults with an end.
  double noise_end_s_ = -1.0;
  double drop_start_s_ = 0.0;
  double drop_end_s_ = -1.0;
  double drop_probability_ = 0.0;
  int64_t next_drop_sample_ = 0;
  double added_latency_s_ = 0.0;
  std::mt19937_64 drop_rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
};

}  // namespace graspbed::testbed
