#pragma once
/// The learned cue alone (`learned_slip`): closes and holds a grip with the constant-grip force loop,
/// starting at the reference's loading grip, and raises the grip target whenever LearnedSlipCue flags
/// a slip (target x (1 + gain) + step, as the reference responds), never above max_grip_n or the task
/// ceiling. No load estimate, no hand-tuned cue: what the learned cue is worth on its own
/// (docs/training-slip-detector.md, "On the scorecard").
///
/// The model: $GRASPBED_SLIP_MODEL if set, else the shipped models/slip/default_20.json (a
/// controller parameter is a number, so a file cannot be one yet). Its unit count is checked against
/// the sensor at the first tick.

#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "controller/constant_grip_controller.h"
#include "controller/grasp_controller.h"
#include "controller/learned_slip_cue.h"

namespace graspbed::controller {

/// Parameters of the learned-cue controller.
struct LearnedSlipControllerConfig {
  double initial_grip_n = 2.0;     ///< grip target when the hold starts [N]
  double max_grip_n = 10.0;        ///< grip target ceiling [N]
  double slip_grip_gain = 0.25;    ///< on a flag: target = target x (1 + gain) + step [-]
  double slip_grip_step_n = 0.5;   ///< additive part of the response [N]
  double slip_refractory_s = 0.04; ///< no second response sooner than this [s]
  double threshold = -1.0;         ///< flag threshold on the score; < 0: the model's own [-]
  double close_effort = 0.3;       ///< motor effort while closing [-]
};

class LearnedSlipController final : public GraspController {
 public:
  /// Loads the model (`model_path`; "" = $GRASPBED_SLIP_MODEL or the shipped one).
  /// @throws std::invalid_argument naming the file when it cannot be used
  LearnedSlipController(const LearnedSlipControllerConfig& config, const std::string& model_path = "");

  static std::vector<ControllerParameter> Parameters();
  static LearnedSlipControllerConfig ConfigFromParams(const ControllerParams& params);
  /// The model file the controller loads when given none.
  static std::string DefaultModelPath();

  void Reset() override;
  void SetIntent(GraspIntent intent) override;
  /// @throws std::invalid_argument at a state whose unit count differs from the model's (once, at the
  /// first tick: a configuration error, not a run-time condition)
  hand::HandCommand Update(const sensor::TactileState& state, const hand::HandState& hand,
                           double time_s) override;
  void SetGripCeiling(double ceiling_n) override;
  ControllerTelemetry telemetry() const override { return telemetry_; }
  std::string name() const override { return "learned_slip"; }
  std::span<const DiagnosticChannel> diagnostic_channels() const override;
  void ReadDiagnostics(std::span<double> values) const override;

 private:
  LearnedSlipControllerConfig config_;
  LearnedSlipCue cue_;
  ConstantGripController grip_;
  double task_ceiling_n_ = 0.0;
  double target_n_ = 0.0;
  double last_response_s_ = -1.0;
  bool was_holding_ = false;
  bool was_flagged_ = false;
  int slip_events_ = 0;  ///< rising edges of the flag while holding, since Reset()
  ControllerTelemetry telemetry_;
};

}  // namespace graspbed::controller
