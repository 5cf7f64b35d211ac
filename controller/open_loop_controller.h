#pragma once
/// The open-loop baseline: a fixed closing effort on "close", a fixed opening effort on "open",
/// blind to the tactile signals. It is what a prosthesis without tactile feedback does, and the
/// reference the grip-slip controller has to beat.

#include "controller/grasp_controller.h"

namespace graspbed::controller {

/// Parameters of the open-loop baseline.
struct OpenLoopConfig {
  double close_effort = 0.5;  ///< motor effort while closing and holding [-] in (0, 1]
  double open_effort = 0.5;   ///< motor effort magnitude while opening [-] in (0, 1]
};

class OpenLoopController final : public GraspController {
 public:
  explicit OpenLoopController(const OpenLoopConfig& config);

  /// Parameter declarations for the factory ("close_effort", "open_effort").
  static std::vector<ControllerParameter> Parameters();

  void Reset() override;
  void SetIntent(GraspIntent intent) override;
  hand::HandCommand Update(const sensor::TactileState& state, const hand::HandState& hand,
                           double time_s) override;
  /// The baseline cannot measure grip force, so a ceiling only caps nothing; kept for the interface.
  void SetGripCeiling(double ceiling_n) override;
  ControllerTelemetry telemetry() const override { return telemetry_; }
  std::string name() const override { return "open_loop"; }

 private:
  OpenLoopConfig config_;
  GraspIntent intent_ = GraspIntent::kIdle;
  ControllerTelemetry telemetry_;
};

}  // namespace graspbed::controller
