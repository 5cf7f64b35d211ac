#include "controller/open_loop_controller.h"

namespace graspbed::controller {

OpenLoopController::OpenLoopController(const OpenLoopConfig& config) : config_(config) { Reset(); }

std::vector<ControllerParameter> OpenLoopController::Parameters() {
  const OpenLoopConfig defaults;
  return {
      {"close_effort", defaults.close_effort, 0.0, 1.0, "", "grip motor effort while closed"},
      {"open_effort", defaults.open_effort, 0.0, 1.0, "", "grip motor effort magnitude while opening"},
  };
}

void OpenLoopController::Reset() {
  intent_ = GraspIntent::kIdle;
  telemetry_ = ControllerTelemetry{};
}

void OpenLoopController::SetIntent(GraspIntent intent) { intent_ = intent; }

void OpenLoopController::SetGripCeiling(double /*ceiling_n*/) {}

hand::HandCommand OpenLoopController::Update(const sensor::TactileState& /*state*/,
                                             const hand::HandState& /*hand*/, double /*time_s*/) {
  hand::HandCommand command;
  switch (intent_) {
    case GraspIntent::kIdle:
      telemetry_.phase = "idle";
      command.grip_effort = 0.0;
      break;
    case GraspIntent::kClose:
      telemetry_.phase = "closed";
      command.grip_effort = config_.close_effort;
      break;
    case GraspIntent::kOpen:
      telemetry_.phase = "opening";
      command.grip_effort = -config_.open_effort;
      break;
  }
  return command;
}

}  // namespace graspbed::controller
