// threshold_grip: a small force-regulating grip controller, as a graspbed plugin. It closes at a
// fixed effort until the fingertip feels contact, then integrates the error between the sensed
// squeeze (TactileState::total_fn_n) and a target into the motor effort, holds with the brake when
// the tactile data cannot be trusted, and opens on request. No slip detection: the target must be
// enough for the object (graspbed's grip_slip controller is the one that adapts).
// From the hand's own state (HandState, controller API version 3) it takes two things: when the
// index reaches its closed end stop without feeling anything, the hand closed on nothing, and it
// stops driving the motor into the stop until the next intent; and it logs the index's motor
// current beside its grip error (a diagnostic channel), the squeeze the motor makes as the motor
// sees it.
#include <algorithm>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "controller/controller_api.h"

namespace {

using graspbed::controller::ControllerParameter;
using graspbed::controller::ControllerParams;
using graspbed::controller::ControllerTelemetry;
using graspbed::controller::DiagnosticChannel;
using graspbed::controller::GraspController;
using graspbed::controller::GraspIntent;
using graspbed::controller::HandCommand;
using graspbed::hand::HandState;
using graspbed::sensor::TactileState;

struct ThresholdGripConfig {
  double target_grip_n = 3.0;    ///< squeeze to hold [N], sum of Fn over the fingertip's units
  double approach_effort = 0.3;  ///< effort while closing without contact [-]
  double contact_n = 0.2;        ///< squeeze that counts as contact [N]
  double gain_per_n_s = 0.3;     ///< effort change per N of error per second [1/(N s)]
  double open_effort = 0.5;      ///< effort magnitude while opening [-]
  int min_valid_units = 4;       ///< fewer valid units than this: hold (safe hold) [-]
};

/// The index's motor current as the hand measures it [A]; NaN when the hand does not report it.
double IndexCurrentA(const HandState& hand) {
  const bool known = hand.digit_count > 0 && hand.digits[0].current_known;
  return known ? hand.digits[0].motor_current_a : std::numeric_limits<double>::quiet_NaN();
}

/// True when the index rests against its closed end stop (a hand that reports its stops).
bool IndexAtClosedStop(const HandState& hand) {
  return hand.digit_count > 0 && hand.digits[0].stops_known && hand.digits[0].at_closed_stop;
}

class ThresholdGripController final : public GraspController {
 public:
  explicit ThresholdGripController(const ThresholdGripConfig& config) : config_(config) { Reset(); }

  void Reset() override {
    intent_ = GraspIntent::kIdle;
    effort_ = 0.0;
    last_time_s_ = -1.0;
    grip_error_n_ = 0.0;
    closed_empty_ = false;
    telemetry_ = ControllerTelemetry{};
  }
  void SetIntent(GraspIntent intent) override {
    intent_ = intent;
    closed_empty_ = false;
  }
  void SetGripCeiling(double ceiling_n) override { ceiling_n_ = ceiling_n; }

  // Allocation-free: plain arithmetic on the state and members.
  HandCommand Update(const TactileState& state, const HandState& hand, double time_s) override {
    const double dt_s = last_time_s_ < 0.0 ? 0.0 : std::clamp(time_s - last_time_s_, 0.0, 0.01);
    last_time_s_ = time_s;
    index_current_a_ = IndexCurrentA(hand);
    const double target_n =
        ceiling_n_ > 0.0 ? std::min(config_.target_grip_n, ceiling_n_) : config_.target_grip_n;
    telemetry_.grip_target_n = target_n;
    telemetry_.safe_hold = false;
    HandCommand command;
    switch (intent_) {
      case GraspIntent::kIdle:
        telemetry_.phase = "idle";
        effort_ = 0.0;
        break;
      case GraspIntent::kOpen:
        telemetry_.phase = "opening";
        effort_ = 0.0;
        command.grip_effort = -config_.open_effort;
        return command;
      case GraspIntent::kClose:
        if (state.stale || state.valid_count < config_.min_valid_units) {
          // Stale or too few units: keep the grip as it is, never open on data we cannot trust.
          telemetry_.phase = "safe_hold";
          telemetry_.safe_hold = true;
          command.brake = true;
          command.grip_effort = effort_;
          return command;
        }
        if (state.total_fn_n < config_.contact_n && effort_ <= config_.approach_effort) {
          // Closed all the way without feeling anything: nothing to hold, stop pushing the stop.
          closed_empty_ = closed_empty_ || IndexAtClosedStop(hand);
          telemetry_.phase = closed_empty_ ? "closed_empty" : "closing";
          effort_ = closed_empty_ ? 0.0 : config_.approach_effort;
        } else {
          telemetry_.phase = "holding";
          grip_error_n_ = target_n - state.total_fn_n;
          effort_ = std::clamp(effort_ + config_.gain_per_n_s * grip_error_n_ * dt_s, 0.0, 1.0);
        }
        break;
    }
    command.grip_effort = effort_;
    return command;
  }

  ControllerTelemetry telemetry() const override { return telemetry_; }
  std::string name() const override { return "threshold_grip"; }

  // Optional: internal signals graspbed logs as signals.csv columns (ctl_grip_error_n,
  // ctl_index_current_a).
  std::span<const DiagnosticChannel> diagnostic_channels() const override {
    static constexpr DiagnosticChannel kChannels[] = {
        {"grip_error_n", "grip target minus the sensed squeeze while holding [N]"},
        {"index_current_a", "the index's motor current the hand measured [A]; NaN when not reported"}};
    return kChannels;
  }
  void ReadDiagnostics(std::span<double> values) const override {
    if (values.size() >= 2) {
      values[0] = grip_error_n_;
      values[1] = index_current_a_;
    }
  }

 private:
  ThresholdGripConfig config_;
  GraspIntent intent_ = GraspIntent::kIdle;
  double effort_ = 0.0;           ///< current motor effort [-]
  double last_time_s_ = -1.0;     ///< time of the previous Update [s]; < 0 before the first
  double ceiling_n_ = 0.0;        ///< task grip ceiling [N]; 0 = none
  double grip_error_n_ = 0.0;     ///< target minus sensed squeeze at the last holding update [N]
  double index_current_a_ = 0.0;  ///< the index's motor current at the last update [A]; NaN unknown
  bool closed_empty_ = false;     ///< closed onto the stop without contact, since the last intent
  ControllerTelemetry telemetry_;
};

std::vector<ControllerParameter> ThresholdGripParameters() {
  const ThresholdGripConfig d;
  return {
      {"target_grip_n", d.target_grip_n, 0.2, 10.0, "N", "squeeze held once in contact"},
      {"approach_effort", d.approach_effort, 0.05, 1.0, "", "motor effort while closing without contact"},
      {"contact_n", d.contact_n, 0.01, 5.0, "N", "squeeze that counts as contact"},
      {"gain_per_n_s", d.gain_per_n_s, 0.0, 10.0, "1/(N s)", "effort change per N of error per second"},
      {"open_effort", d.open_effort, 0.0, 1.0, "", "motor effort magnitude while opening"},
      {"min_valid_units", static_cast<double>(d.min_valid_units), 1.0, 64.0, "",
       "fewer valid units: safe hold"},
  };
}

std::unique_ptr<GraspController> MakeThresholdGrip(const ControllerParams& params) {
  ThresholdGripConfig config;
  config.target_grip_n = params.at("target_grip_n");
  config.approach_effort = params.at("approach_effort");
  config.contact_n = params.at("contact_n");
  config.gain_per_n_s = params.at("gain_per_n_s");
  config.open_effort = params.at("open_effort");
  config.min_valid_units = static_cast<int>(params.at("min_valid_units"));
  // A cross-field check, reported by graspbed like any bad parameter (file:line, exit 2).
  if (config.contact_n >= config.target_grip_n) {
    throw graspbed::controller::ParameterError(
        "contact_n", config.contact_n,
        "must be below target_grip_n = " + std::to_string(config.target_grip_n));
  }
  return std::make_unique<ThresholdGripController>(config);
}

}  // namespace

GRASPBED_CONTROLLER_PLUGIN("threshold_grip", &ThresholdGripParameters, &MakeThresholdGrip)
