#pragma once
/// MotorSqueeze: what the grip motor says about the squeeze, for a controller that also feels its
/// own hand (hand::HandState). A DC motor's torque is its constant times its current; held still
/// against an object, the current's share of the stall current is the share of the stall pinch force
/// the digit presses with. The tactile units see only the part of that squeeze that lands on their
/// mesas (a small object also presses the holder between them: a plastic cup 2.05 of 3.84 N), so the
/// ratio of the two, taken while the digits stand still, is the share of the squeeze the sensor
/// sees. A controller then keeps the squeeze's absolute limits (a floor, a ceiling, a step) on the
/// object's real squeeze while it regulates on the units (docs/controller.md, "Proprioception").
///
/// Also: the current's offset is tared while the motor is off and the digits still, and a digit at
/// its closed end stop while closing means the grasp found nothing. Update() allocates nothing.

#include "hand/hand_state.h"

namespace graspbed::controller {

/// Settings of the motor's squeeze estimate.
struct MotorSqueezeConfig {
  /// The pinch force of a digit at stall with full effort in the grasp's posture [N]: the hand's
  /// rating (20 N for graspbed's prosthetic hand, DigitMotorConfig::stall_pinch_force_n).
  double stall_pinch_n = 20.0;
  /// The estimate of the sensed share is trusted only while the motor squeezes at least this [N] ...
  double min_squeeze_n = 0.5;
  /// ... and every known joint turns slower than this [rad/s] (back-EMF then costs < 1 % of the
  /// current at the default 1.6 rad/s no-load speed) ...
  double max_joint_speed_rad_s = 0.05;
  /// ... and is kept in [min_sensed_share, 1]: below half the object is mostly off the pad, and a
  /// grip scaled further keeps it there (narrow_box: the units saw nothing for the first 0.3 s of
  /// contact, a share of 0.25 quartered the grip and the box stayed off the pad) [-].
  double min_sensed_share = 0.5;
  /// A share above this counts as 1: the motor's squeeze is known to +-10 % (the current sensing's
  /// gain error and noise, the pad's lever arm moving with the posture), and a grip scaled by a
  /// share of 0.9 would be a 10 % weaker grip on an object the units see whole [-].
  double full_share_above = 0.75;
  double share_filter_s = 0.05;   ///< low-pass time constant of the sensed share [s]
  double offset_filter_s = 0.02;  ///< low-pass time constant of the tared current offset [s]
};

/// The motor's view of the squeeze. Reset() at the start of every grasp's life (it keeps nothing
/// between controllers).
class MotorSqueeze {
 public:
  explicit MotorSqueeze(const MotorSqueezeConfig& config = {}) : config_(config) { Reset(); }

  void Reset();
  /// One control tick: `hand` the newest hand state, `last_effort` the effort commanded at the
  /// previous tick [-], `sensed_grip_n` the grip the units measure now [N], `calm` whether the
  /// grasp is settled (the controller's judgement: holding, no slip cue for a while; an object
  /// bouncing on the pad reads 0 and 8 N by turns and says nothing of the share), `dt_s` since the
  /// last tick [s]. A hand without a known current leaves the estimate unknown.
  void Update(const hand::HandState& hand, double last_effort, double sensed_grip_n, bool calm, double dt_s);

  /// Whether the index motor's current is known (fresh) at this tick.
  bool known() const { return known_; }
  /// The squeeze the index's motor makes [N] (0 unknown).
  double squeeze_n() const { return squeeze_n_; }
  /// Share of the squeeze the units see, in [min_sensed_share, 1]; 1 until it has been measured.
  double sensed_share() const {
    return share_measured_ && share_ <= config_.full_share_above ? share_ : 1.0;
  }
  /// The index (or the jaw's finger) rests at its closed end stop: a closing found nothing.
  bool closed_on_nothing() const { return closed_on_nothing_; }
  /// Forgets the sensed share (a new grasp: another object, another share).
  void RestartShare();

 private:
  MotorSqueezeConfig config_;
  double share_ = 1.0;         ///< filtered sensed share [-]
  double offset_share_ = 0.0;  ///< tared current offset as a share of the stall current [-]
  bool share_measured_ = false;
  bool known_ = false;
  double squeeze_n_ = 0.0;
  bool closed_on_nothing_ = false;
};

}  // namespace graspbed::controller
