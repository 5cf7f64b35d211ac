#pragma once
/// SimActuator: the simulated grip motor behind the HandActuator interface. Write() sets the motor
/// effort of the Simulation (or its brake, or lets it coast) from the next physics step on.

#include <string>

#include "hand/hand_command.h"
#include "sim/simulation.h"

namespace graspbed::sim {

/// Carries HandCommands to the simulated motor. Holds a reference to the Simulation.
class SimActuator : public hand::HandActuator {
 public:
  explicit SimActuator(Simulation& simulation) : simulation_(simulation) {}

  /// enable = false: effort 0 (coasts); brake: holds the current closure; otherwise the effort,
  /// clamped to [-1, 1]. Never fails in simulation.
  hand::WriteStatus Write(const hand::HandCommand& command) override;
  /// Motor off (effort 0, brake released).
  void Stop() override;
  std::string name() const override { return "sim"; }
  /// Last command written.
  const hand::HandCommand& last_command() const { return last_command_; }

 private:
  Simulation& simulation_;
  hand::HandCommand last_command_;
};

}  // namespace graspbed::sim
