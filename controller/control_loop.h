#pragma once
/// ControlLoop: backend -> readout -> inversion -> controller -> actuator, one tick at a time. The same
/// code serves the simulation and the serial hardware; only who calls Tick() differs (the simulated
/// clock after each control period, or the hardware thread when frames arrive).

#include <cstdint>

#include "controller/grasp_controller.h"
#include "hand/hand_command.h"
#include "hand/hand_state.h"
#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/layout.h"
#include "sensor/raw_frame.h"
#include "sensor/readout.h"
#include "sensor/tactile_backend.h"
#include "sensor/tactile_state.h"

namespace graspbed::controller {

/// Settings of the loop itself; the readout and inversion carry their own.
struct ControlLoopConfig {
  /// No new frame for this long marks the tactile state stale; the controller must hold [s].
  double stale_timeout_s = 0.02;
  sensor::ReadoutConfig readout;
  sensor::InversionConfig inversion;

  /// @throws common::ConfigError naming the field (key path) and value.
  void Validate() const;
};

/// What happened in the loop since it started.
struct LoopCounters {
  uint64_t ticks = 0;        ///< Tick() calls
  uint64_t frames = 0;       ///< new frames processed
  uint64_t stale_ticks = 0;  ///< ticks with a stale state
  uint64_t disconnected_ticks = 0;
  uint64_t actuator_failures = 0;  ///< Write() that did not reach the motor
  uint64_t retares = 0;            ///< baselines restarted after a device session change
  uint64_t hand_readings = 0;      ///< new hand states (proprioception) taken
  uint64_t hand_stale_ticks = 0;   ///< ticks with a stale hand state (its backend reports one)
};

/// Ties one tactile backend, one hand sensor (proprioception), one controller and one actuator
/// together. Not copyable; holds references that must outlive it. Tick() allocates nothing and does
/// no I/O of its own.
class ControlLoop {
 public:
  ControlLoop(sensor::TactileBackend& backend, hand::HandSensor& hand_sensor, GraspController& controller,
              hand::HandActuator& actuator, const sensor::Layout& layout, const sensor::Calibration& calibration,
              const ControlLoopConfig& config);
  /// A loop whose hand reports no proprioception (every HandState field unknown).
  ControlLoop(sensor::TactileBackend& backend, GraspController& controller, hand::HandActuator& actuator,
              const sensor::Layout& layout, const sensor::Calibration& calibration,
              const ControlLoopConfig& config);
  ControlLoop(const ControlLoop&) = delete;
  ControlLoop& operator=(const ControlLoop&) = delete;

  /// One control tick at `time_s` on the loop's clock [s]: takes the newest frame if any, updates the
  /// tactile state (marking it stale when frames stop), asks the controller, writes the command.
  /// Returns the backend's read status for this tick.
  sensor::ReadStatus Tick(double time_s);

  /// Newest tactile state (forces per unit, validity, totals, stale flag).
  const sensor::TactileState& state() const { return state_; }
  /// Newest hand state (proprioception; stale after stale_timeout_s without a reading).
  const hand::HandState& hand_state() const { return hand_state_; }
  /// Newest raw frame taken from the backend.
  const sensor::RawFrame& frame() const { return frame_; }
  /// dR/R of the newest frame.
  const sensor::ReadoutFrame& readout_frame() const { return readout_frame_; }
  /// Command written at the last tick.
  const hand::HandCommand& command() const { return command_; }
  const LoopCounters& counters() const { return counters_; }
  /// The backend's answer at the last Tick() (kNoNewFrame before the first).
  sensor::ReadStatus last_status() const { return last_status_; }
  /// Device session of the frame the loop holds (a change re-tares).
  uint64_t session() const { return session_; }
  /// Forgets the tare baseline; the next frames are averaged into a new one.
  void Retare();
  /// Uses a stored baseline instead of taring from the first frames [Ohm], layout order.
  void SetBaseline(std::span<const double> r1_ohm, std::span<const double> r2_ohm);

 private:
  sensor::TactileBackend& backend_;
  hand::NoHandSensor no_hand_sensor_;
  hand::HandSensor& hand_sensor_;
  GraspController& controller_;
  hand::HandActuator& actuator_;
  ControlLoopConfig config_;
  sensor::Readout readout_;
  sensor::Inversion inversion_;

  sensor::RawFrame frame_;
  sensor::ReadoutFrame readout_frame_;
  sensor::TactileState state_;
  hand::HandState hand_state_;
  hand::HandCommand command_;
  LoopCounters counters_;
  double last_frame_time_s_ = -1.0;  ///< loop time of the newest frame; < 0 before the first
  uint64_t session_ = 0;
  sensor::ReadStatus last_status_ = sensor::ReadStatus::kNoNewFrame;
  bool stale_ = false;
};

}  // namespace graspbed::controller
