#pragma once
/// The constant-grip baseline: closes on "close", then holds one total normal force (`grip_n`) with a
/// force loop on what the sensor reports, whatever the load does. It knows nothing else: no load
/// estimate, no slip cue. It is the oracle's instrument (the lightest grip_n that holds a scenario is
/// the scenario's slip force, docs/scenarios.md "The oracle grip") and the two strawmen of the
/// disturbance scenarios (a blind light grip, a blind firm grip).

#include "controller/filters.h"
#include "controller/grasp_controller.h"

namespace graspbed::controller {

/// Parameters of the constant-grip baseline.
struct ConstantGripConfig {
  double grip_n = 2.0;  ///< total normal force held, sum over the valid units [N]
  /// Motor effort while closing towards the object [-]. Low, so that the impact of the digits on the
  /// object does not decide the grip: at 0.15 the pads meet a box with about 2 N.
  double close_effort = 0.15;
  double open_effort = 0.5;             ///< motor effort magnitude while releasing [-]
  double release_time_s = 0.5;          ///< the opening effort is applied this long [s]
  double contact_threshold_n = 0.1;     ///< total normal force that means the digits touch [N]
  int contact_confirm_frames = 3;       ///< consecutive frames above it before the force loop starts
  double effort_per_newton = 0.05;      ///< feed-forward effort per newton of grip (1 / 20 N stall pinch)
  double kp_effort_per_n = 0.04;        ///< proportional gain [1/N]
  double ki_effort_per_n_s = 1.5;       ///< integral gain [1/(N s)]
  double integrator_limit = 0.5;        ///< bound of the integral term [-]
  double grip_filter_s = 0.002;         ///< low-pass time constant of the measured grip [s]
  int min_valid_units = 3;              ///< fewer valid units (or stale data): hold the last command
};

class ConstantGripController final : public GraspController {
 public:
  /// @throws common::ConfigError for a value out of its range (keyed by the parameter).
  explicit ConstantGripController(const ConstantGripConfig& config);

  /// Parameter declarations for the factory, defaults from ConstantGripConfig.
  static std::vector<ControllerParameter> Parameters();
  /// Config from a factory-resolved parameter map (every declared name present, values in range).
  static ConstantGripConfig ConfigFromParams(const ControllerParams& params);

  void Reset() override;
  void SetIntent(GraspIntent intent) override;
  hand::HandCommand Update(const sensor::TactileState& state, const hand::HandState& hand,
                           double time_s) override;
  /// The held grip is min(grip_n, ceiling); <= 0 or +inf removes the task ceiling.
  void SetGripCeiling(double ceiling_n) override;
  ControllerTelemetry telemetry() const override { return telemetry_; }
  std::string name() const override { return "constant_grip"; }
  std::span<const DiagnosticChannel> diagnostic_channels() const override;
  void ReadDiagnostics(std::span<double> values) const override;

 private:
  enum class Phase { kIdle, kClosing, kHolding, kReleasing, kOpen };

  double TargetN() const;

  ConstantGripConfig config_;
  LowPassFilter grip_filter_;
  GraspIntent intent_ = GraspIntent::kIdle;
  Phase phase_ = Phase::kIdle;
  double phase_start_s_ = 0.0;
  double task_ceiling_n_ = 0.0;  ///< 0 = none
  bool have_time_ = false;
  double last_time_s_ = 0.0;
  int contact_frames_ = 0;
  double measured_grip_n_ = 0.0;
  double integrator_ = 0.0;
  hand::HandCommand last_good_command_;
  ControllerTelemetry telemetry_;
};

}  // namespace graspbed::controller
