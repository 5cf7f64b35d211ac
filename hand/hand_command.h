#pragma once
/// HandCommand and the HandActuator interface: what a controller asks of the grip motor, and who
/// carries it out (sim/'s simulated motor or hardware/'s serial link to the hand electronics). This
/// sits below controller/, sim/ and hardware/ (which all speak it) and depends on nothing, as
/// sensor/tactile_backend.h does for the other direction of the loop.

#include <cstdint>
#include <string>

namespace graspbed::hand {

/// One command to the single grip motor that closes thumb and finger through the linkage.
struct HandCommand {
  double grip_effort = 0.0;  ///< [-1, 1] of stall torque; + closes, - opens
  bool enable = true;        ///< false: motor off (coasts)
  bool brake = false;        ///< true: hold position with the brake (motor effort ignored)
};

/// Outcome of one Write(); errors in the loop are values.
enum class WriteStatus { kOk, kDisconnected };

/// Carries HandCommands to a motor. Owners of devices: not copyable, not movable.
class HandActuator {
 public:
  HandActuator() = default;
  HandActuator(const HandActuator&) = delete;
  HandActuator& operator=(const HandActuator&) = delete;
  virtual ~HandActuator() = default;

  /// Applies `command` from now on; never blocks, never allocates.
  virtual WriteStatus Write(const HandCommand& command) = 0;
  /// Motor off; safe to call twice.
  virtual void Stop() {}
  virtual std::string name() const = 0;
};

}  // namespace graspbed::hand
