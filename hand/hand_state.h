#pragma once
/// HandState and the HandSensor interface: what the hand knows of itself (proprioception), read once
/// per control tick beside the TactileState: per digit its joint positions and velocities, its
/// motor's current and whether it rests against a stop. Like HandCommand it sits below controller/,
/// sim/ and hardware/ (each backend fills it: sim/proprioception.h, the serial link's HAND message,
/// a recording's columns) and depends on nothing. Part of the controller API.
///
/// Every field group carries a `known` flag. A backend that cannot measure a quantity (a device
/// speaking protocol version 1, an old recording, a jaw fixture's second digit) leaves it unknown;
/// an unknown value is never a measured zero, and controllers must check the flag before use.

#include <array>
#include <string>

namespace graspbed::hand {

/// Most digits a hand reports (prosthetic hand: index, thumb; jaw fixture: finger, thumb).
inline constexpr int kMaxDigits = 2;
/// Most joints a digit reports (index: MCP, PIP; thumb: flexion; jaw: one slide).
inline constexpr int kMaxDigitJoints = 2;

/// One digit's proprioception at one sample time.
struct DigitState {
  int joint_count = 0;  ///< joints reported, <= kMaxDigitJoints (proximal first)
  /// True when the digit's joints are slides (the jaw fixture): positions in [m], velocities in
  /// [m/s]; false for hinges: [rad], [rad/s].
  bool linear = false;
  bool position_known = false;  ///< joint_position_* holds encoder readings
  /// Flexion since the hand's start pose (the pre-shape) [rad] or [m], + closing; the open stop
  /// may lie below 0 (the pre-shape is partly closed).
  std::array<double, kMaxDigitJoints> joint_position{};
  bool velocity_known = false;
  std::array<double, kMaxDigitJoints> joint_velocity{};  ///< d(position)/dt [rad/s] or [m/s]
  /// The digit's drive motor current [A], + closing. Current, not a torque estimate: it is what the
  /// electronics measure (a shunt), and torque = k_t x current needs a motor constant the controller
  /// may hold better than the device (parameters, calibration). At stall it is proportional to the
  /// squeeze the digit makes; while the digit moves freely back-EMF keeps it low.
  bool current_known = false;
  double motor_current_a = 0.0;
  /// The current at stall with full effort [A] (the motor's rating as the backend knows it; 0 when
  /// unknown): motor_current_a / stall_current_a is the share of the stall torque the motor makes.
  double stall_current_a = 0.0;
  bool stops_known = false;
  bool at_open_stop = false;    ///< the digit rests against its open end stop
  bool at_closed_stop = false;  ///< the digit closed all the way (on nothing, or round something tiny)
  /// The encoder's reading stood still while the motor ran freely (the backend's own check): the
  /// position is then marked unknown. Counted, not fatal.
  bool encoder_fault = false;
};

/// The hand's proprioception at one control tick.
struct HandState {
  /// Sample time of the newest reading on the loop's clock [s]; < 0 before the first.
  double time_s = -1.0;
  /// No new reading for the loop's stale timeout: the values are the last ones known.
  bool stale = false;
  int digit_count = 0;  ///< digits reported (0: the backend has no proprioception)
  std::array<DigitState, kMaxDigits> digits{};

  /// True when any digit reports any field.
  bool any_known() const {
    for (int d = 0; d < digit_count; ++d) {
      const DigitState& digit = digits[d];
      if (digit.position_known || digit.velocity_known || digit.current_known || digit.stops_known) return true;
    }
    return false;
  }
};

/// Where the loop's HandState comes from (the simulated joints, the serial link's HAND messages, a
/// recording). Owners of devices: not copyable, not movable.
class HandSensor {
 public:
  HandSensor() = default;
  HandSensor(const HandSensor&) = delete;
  HandSensor& operator=(const HandSensor&) = delete;
  virtual ~HandSensor() = default;

  /// Writes the newest reading available at loop time `time_s` [s] into `state`; returns false when
  /// nothing newer than the last call has arrived (`state` then keeps its values). Never blocks,
  /// never allocates.
  virtual bool Read(double time_s, HandState* state) = 0;
  virtual std::string name() const = 0;
};

/// A hand with no proprioception: every field stays unknown (digit_count 0).
class NoHandSensor final : public HandSensor {
 public:
  bool Read(double /*time_s*/, HandState* /*state*/) override { return false; }
  std::string name() const override { return "none"; }
};

}  // namespace graspbed::hand
