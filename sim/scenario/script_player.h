#pragma once
/// ScriptPlayer: plays a scenario's timed actions on a running SimRig -- the user's intent to the
/// controller, wrist moves and shakes to the wrist servo target, mass, friction and external force to
/// the object, faults to the simulated sensor. Update() is called before every physics step with the
/// simulated time; it allocates nothing.

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "controller/grasp_controller.h"
#include "sim/scenario/scenario_config.h"
#include "sim/sim_rig.h"

namespace graspbed::scenario {

/// Smooth 0..1 progress of a move or ramp at normalised time `s` in [0, 1] (clamped).
double ProfileProgress(Profile profile, double s);

/// Plays one script on one rig. Holds no reference to the rig between calls.
class ScriptPlayer {
 public:
  /// `script` sorted by at_s (ScenarioConfig keeps it so); `seed` drives the frame-drop draws.
  ScriptPlayer(const ScenarioConfig& config);

  /// Takes the rig's initial wrist target, object mass and friction as the starting point and sets
  /// the grip ceiling. Call once before the first Update().
  void Start(sim::SimRig& rig);
  /// Fires every action due at or before `time_s` [s] and applies the continuous ones (moves, shakes,
  /// ramps, timed faults) for that instant. Allocates nothing.
  void Update(double time_s, sim::SimRig& rig);

  /// The intent last given to the controller.
  controller::GraspIntent intent() const { return intent_; }
  /// Time of the first close action that has fired, or < 0 before it [s].
  double first_close_time_s() const { return first_close_time_s_; }
  /// Actions fired so far.
  int fired_count() const { return static_cast<int>(next_); }
  /// Current wrist target without the shake offset [m], world frame.
  const std::array<double, 3>& base_wrist_target_m() const { return base_target_; }
  /// External force now applied to the object [N], world frame.
  const std::array<double, 3>& external_force_n() const { return force_now_; }

 private:
  void Fire(const Action& action, double time_s, sim::SimRig& rig);

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
  size_t next_ = 0;
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

}  // namespace graspbed::scenario
