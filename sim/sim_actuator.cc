#include "sim/sim_actuator.h"

namespace graspbed::sim {

hand::WriteStatus SimActuator::Write(const hand::HandCommand& command) {
  last_command_ = command;
  if (command.brake) {
    simulation_.SetGripBrake(true);
    simulation_.SetGripEffort(0.0);
    return hand::WriteStatus::kOk;
  }
  simulation_.SetGripBrake(false);
  simulation_.SetGripEffort(command.enable ? command.grip_effort : 0.0);
  return hand::WriteStatus::kOk;
}

void SimActuator::Stop() {
  last_command_ = hand::HandCommand{};
  last_command_.grip_effort = 0.0;
  simulation_.SetGripBrake(false);
  simulation_.SetGripEffort(0.0);
}

}  // namespace graspbed::sim
