#include "controller/constant_grip_controller.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/config_error.h"
#include "controller/parameter_binding.h"

namespace graspbed::controller {
namespace {

/// Longest time step the integrator accepts [s] (a pause of the clock is not integrated).
constexpr double kMaxStepS = 0.01;

#define GRASPBED_BIND(name, field, min, max, unit, doc) \
  GRASPBED_BIND_PARAMETER(ConstantGripConfig, name, field, min, max, unit, doc)

const ParameterBinding<ConstantGripConfig> kBindings[] = {
    GRASPBED_BIND("grip_n", grip_n, 0.01, 500.0, "N", "total normal force held after contact (sum over the valid units)"),
    GRASPBED_BIND("close_effort", close_effort, 0.01, 1.0, "", "motor effort while closing towards the object"),
    GRASPBED_BIND("open_effort", open_effort, 0.01, 1.0, "", "motor effort magnitude while releasing"),
    GRASPBED_BIND("release_time_s", release_time_s, 0.01, 10.0, "s",
                  "the opening effort is applied this long after an open command"),
    GRASPBED_BIND("contact_threshold_n", contact_threshold_n, 0.01, 10.0, "N",
                  "total normal force that means the digits touch the object"),
    GRASPBED_BIND("contact_confirm_frames", contact_confirm_frames, 1, 100, "frames",
                  "consecutive frames above the threshold before the force loop starts"),
    GRASPBED_BIND("effort_per_newton", effort_per_newton, 0.0, 1.0, "1/N", "feed-forward effort per newton of grip"),
    GRASPBED_BIND("kp_effort_per_n", kp_effort_per_n, 0.0, 1.0, "1/N", "proportional gain of the force loop"),
    GRASPBED_BIND("ki_effort_per_n_s", ki_effort_per_n_s, 0.0, 100.0, "1/(N s)", "integral gain of the force loop"),
    GRASPBED_BIND("integrator_limit", integrator_limit, 0.0, 1.0, "", "bound of the integral term"),
    GRASPBED_BIND("grip_filter_s", grip_filter_s, 0.0, 0.1, "s", "low-pass time constant of the measured grip"),
};

#undef GRASPBED_BIND

void Validate(const ConstantGripConfig& config) {
  try {
    RequireParametersInRange<ConstantGripConfig>(kBindings, config);
  } catch (const common::ConfigError& error) {
    throw error.WithContext("controller 'constant_grip'");
  }
}

constexpr DiagnosticChannel kDiagnosticChannels[] = {
    {"measured_grip_n", "filtered grip force the loop closes on [N]"},
};

}  // namespace

ConstantGripController::ConstantGripController(const ConstantGripConfig& config) : config_(config) {
  Validate(config_);
  // Designed for 1 kHz frames (the default sensor and control rates), as grip_slip's default is.
  grip_filter_ = LowPassFilter(config_.grip_filter_s, 1e-3);
  Reset();
}

std::vector<ControllerParameter> ConstantGripController::Parameters() {
  return DescribeParameters<ConstantGripConfig>(kBindings);
}

ConstantGripConfig ConstantGripController::ConfigFromParams(const ControllerParams& params) {
  ConstantGripConfig config;
  try {
    ApplyParameters<ConstantGripConfig>(kBindings, params, &config);
  } catch (const common::ConfigError& error) {
    throw error.WithContext("controller 'constant_grip'");
  }
  Validate(config);
  return config;
}

void ConstantGripController::Reset() {
  grip_filter_.Clear();
  intent_ = GraspIntent::kIdle;
  phase_ = Phase::kIdle;
  phase_start_s_ = 0.0;
  have_time_ = false;
  last_time_s_ = 0.0;
  contact_frames_ = 0;
  measured_grip_n_ = 0.0;
  integrator_ = 0.0;
  last_good_command_ = hand::HandCommand{.grip_effort = 0.0};
  telemetry_ = ControllerTelemetry{};
}

void ConstantGripController::SetIntent(GraspIntent intent) { intent_ = intent; }

void ConstantGripController::SetGripCeiling(double ceiling_n) {
  if (std::isnan(ceiling_n)) throw std::invalid_argument("grip ceiling = nan: must be a number of newtons");
  task_ceiling_n_ = (ceiling_n > 0.0 && std::isfinite(ceiling_n)) ? ceiling_n : 0.0;
}

double ConstantGripController::TargetN() const {
  return task_ceiling_n_ > 0.0 ? std::min(config_.grip_n, task_ceiling_n_) : config_.grip_n;
}

std::span<const DiagnosticChannel> ConstantGripController::diagnostic_channels() const {
  return kDiagnosticChannels;
}

void ConstantGripController::ReadDiagnostics(std::span<double> values) const {
  if (!values.empty()) values[0] = measured_grip_n_;
}

hand::HandCommand ConstantGripController::Update(const sensor::TactileState& state,
                                                 const hand::HandState& /*hand*/, double time_s) {
  const double dt_s = have_time_ ? std::clamp(time_s - last_time_s_, 0.0, kMaxStepS) : 0.0;
  have_time_ = true;
  last_time_s_ = time_s;

  if (intent_ == GraspIntent::kOpen && phase_ != Phase::kReleasing && phase_ != Phase::kOpen) {
    phase_ = Phase::kReleasing;
    phase_start_s_ = time_s;
  } else if (intent_ == GraspIntent::kClose &&
             (phase_ == Phase::kIdle || phase_ == Phase::kOpen || phase_ == Phase::kReleasing)) {
    phase_ = Phase::kClosing;
    phase_start_s_ = time_s;
    contact_frames_ = 0;
    integrator_ = 0.0;
  }

  const bool data_ok = !state.stale && state.valid_count >= config_.min_valid_units;
  if (data_ok) measured_grip_n_ = grip_filter_.Update(state.total_fn_n);
  hand::HandCommand command;
  switch (phase_) {
    case Phase::kIdle:
    case Phase::kOpen:
      command.grip_effort = 0.0;
      break;
    case Phase::kClosing:
      command.grip_effort = config_.close_effort;
      if (data_ok) contact_frames_ = state.total_fn_n >= config_.contact_threshold_n ? contact_frames_ + 1 : 0;
      if (contact_frames_ >= config_.contact_confirm_frames) {
        phase_ = Phase::kHolding;
        phase_start_s_ = time_s;
        integrator_ = 0.0;
      }
      break;
    case Phase::kHolding: {
      if (!data_ok) {  // never open on stale data: keep squeezing as before
        command = last_good_command_;
        break;
      }
      const double target_n = TargetN();
      const double error_n = target_n - measured_grip_n_;
      const double feed_forward = config_.effort_per_newton * target_n;
      const double unclamped = feed_forward + config_.kp_effort_per_n * error_n + integrator_;
      // Anti-windup: integrate only while the output is not pinned in the direction of the error.
      if (!(unclamped >= 1.0 && error_n > 0.0) && !(unclamped <= 0.0 && error_n < 0.0)) {
        integrator_ = std::clamp(integrator_ + config_.ki_effort_per_n_s * error_n * dt_s,
                                 -config_.integrator_limit, config_.integrator_limit);
      }
      command.grip_effort =
          std::clamp(feed_forward + config_.kp_effort_per_n * error_n + integrator_, 0.0, 1.0);
      break;
    }
    case Phase::kReleasing:
      command.grip_effort = -config_.open_effort;
      if (time_s - phase_start_s_ >= config_.release_time_s) phase_ = Phase::kOpen;
      break;
  }
  if (data_ok) last_good_command_ = command;

  static constexpr const char* kPhaseNames[] = {"idle", "closing", "holding", "releasing", "open"};
  telemetry_.phase = kPhaseNames[static_cast<int>(phase_)];
  telemetry_.grip_target_n = phase_ == Phase::kHolding ? TargetN() : 0.0;
  telemetry_.safe_hold = !data_ok && phase_ == Phase::kHolding;
  return command;
}

}  // namespace graspbed::controller
