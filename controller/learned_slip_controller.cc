#include "controller/learned_slip_controller.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string_view>

#include "common/config_error.h"
#include "common/data_dir.h"
#include "controller/parameter_binding.h"

namespace graspbed::controller {
namespace {

#define GRASPBED_BIND(name, field, min, max, unit, doc) \
  GRASPBED_BIND_PARAMETER(LearnedSlipControllerConfig, name, field, min, max, unit, doc)

const ParameterBinding<LearnedSlipControllerConfig> kBindings[] = {
    GRASPBED_BIND("initial_grip_n", initial_grip_n, 0.05, 100.0, "N", "grip target when the hold starts"),
    GRASPBED_BIND("max_grip_n", max_grip_n, 0.1, 200.0, "N", "grip target ceiling"),
    GRASPBED_BIND("slip_grip_gain", slip_grip_gain, 0.0, 5.0, "", "on a learned flag: target = target x (1 + gain) + step"),
    GRASPBED_BIND("slip_grip_step_n", slip_grip_step_n, 0.0, 50.0, "N", "additive part of the response"),
    GRASPBED_BIND("slip_refractory_s", slip_refractory_s, 0.001, 1.0, "s", "no second response sooner than this"),
    GRASPBED_BIND("threshold", threshold, -1.0, 1.0, "", "flag threshold on the model's score; < 0: the model's own"),
    GRASPBED_BIND("close_effort", close_effort, 0.01, 1.0, "", "motor effort while closing towards the object"),
};

#undef GRASPBED_BIND

constexpr DiagnosticChannel kDiagnosticChannels[] = {
    {"learned_score", "the learned cue's score: probability of a gross slip within its horizon [-]"},
    {"learned_threshold", "score at or above which the cue flags [-]"},
    {"grip_target_n", "grip target of the force loop [N]"},
};

/// The force loop's settings. With a task ceiling the closing effort is capped at the effort that
/// holds the ceiling, as the reference caps it (ceiling_effort_margin 1): a fragile object is not
/// crushed by the digits' impact.
ConstantGripConfig GripConfig(const LearnedSlipControllerConfig& config, double ceiling_n) {
  ConstantGripConfig grip;
  grip.grip_n = config.max_grip_n;  // the held grip is set through the ceiling (SetGripCeiling)
  grip.close_effort = config.close_effort;
  if (ceiling_n > 0.0) grip.close_effort = std::clamp(grip.effort_per_newton * ceiling_n, 0.01, config.close_effort);
  return grip;
}

SlipModel LoadModel(const std::string& path) {
  // The layout is not known before the first state; the unit count is checked there.
  return LoadSlipModel(path.empty() ? LearnedSlipController::DefaultModelPath() : path, {.layout_name = "", .units = 0});
}

}  // namespace

std::string LearnedSlipController::DefaultModelPath() {
  const char* environment = std::getenv("GRASPBED_SLIP_MODEL");
  if (environment != nullptr && *environment != '\0') return environment;
  return common::DataPath("models/slip/default_20.json");
}

LearnedSlipController::LearnedSlipController(const LearnedSlipControllerConfig& config, const std::string& model_path)
    : config_(config), cue_(LoadModel(model_path), config.threshold), grip_(GripConfig(config, 0.0)) {
  if (config.initial_grip_n > config.max_grip_n) {
    throw common::ConfigError("", 0, "initial_grip_n", common::ReadableNumber(config.initial_grip_n),
                              "must be <= max_grip_n")
        .WithContext("controller 'learned_slip'");
  }
  Reset();
}

std::vector<ControllerParameter> LearnedSlipController::Parameters() {
  return DescribeParameters<LearnedSlipControllerConfig>(kBindings);
}

LearnedSlipControllerConfig LearnedSlipController::ConfigFromParams(const ControllerParams& params) {
  LearnedSlipControllerConfig config;
  ApplyParameters<LearnedSlipControllerConfig>(kBindings, params, &config);
  return config;
}

void LearnedSlipController::Reset() {
  cue_.Reset();
  grip_.Reset();
  target_n_ = config_.initial_grip_n;
  grip_.SetGripCeiling(target_n_);
  last_response_s_ = -1.0;
  was_holding_ = false;
  was_flagged_ = false;
  slip_events_ = 0;
  telemetry_ = ControllerTelemetry{};
}

void LearnedSlipController::SetIntent(GraspIntent intent) { grip_.SetIntent(intent); }

void LearnedSlipController::SetGripCeiling(double ceiling_n) {
  if (std::isnan(ceiling_n)) throw std::invalid_argument("grip ceiling = nan: must be a number of newtons");
  task_ceiling_n_ = (ceiling_n > 0.0 && std::isfinite(ceiling_n)) ? ceiling_n : 0.0;
  grip_ = ConstantGripController(GripConfig(config_, task_ceiling_n_));  // before a run, not per tick
  grip_.SetGripCeiling(target_n_);
}

hand::HandCommand LearnedSlipController::Update(const sensor::TactileState& state, const hand::HandState& hand,
                                                double time_s) {
  if (state.unit_count != cue_.model().layout.units) {
    throw std::invalid_argument(cue_.model().source_file + ": layout.units = " +
                                std::to_string(cue_.model().layout.units) + ": the model was trained for layout " +
                                cue_.model().layout_name + ", this sensor has " + std::to_string(state.unit_count) +
                                " units");
  }
  const LearnedSlipOutput cue = cue_.Update(state, time_s);
  const bool holding = std::string_view(grip_.telemetry().phase) == "holding";
  if (holding && !was_holding_) target_n_ = config_.initial_grip_n;  // a new hold starts light
  const bool respond = holding && cue.flag && (last_response_s_ < 0.0 || time_s - last_response_s_ >= config_.slip_refractory_s);
  if (respond) {
    target_n_ = std::min(config_.max_grip_n, target_n_ * (1.0 + config_.slip_grip_gain) + config_.slip_grip_step_n);
    last_response_s_ = time_s;
  }
  was_holding_ = holding;
  const double ceiling = task_ceiling_n_ > 0.0 ? std::min(target_n_, task_ceiling_n_) : target_n_;
  grip_.SetGripCeiling(ceiling);
  const hand::HandCommand command = grip_.Update(state, hand, time_s);
  telemetry_ = grip_.telemetry();
  const bool flagged = holding && cue.flag;
  telemetry_.slip_detected = flagged;
  telemetry_.slip_cues = flagged ? "learned" : "";
  if (flagged && !was_flagged_) ++slip_events_;
  telemetry_.slip_events = slip_events_;
  was_flagged_ = flagged;
  return command;
}

std::span<const DiagnosticChannel> LearnedSlipController::diagnostic_channels() const { return kDiagnosticChannels; }

void LearnedSlipController::ReadDiagnostics(std::span<double> values) const {
  const double all[] = {cue_.output().score, cue_.threshold(), target_n_};
  std::copy_n(all, std::min(values.size(), std::size(all)), values.begin());
}

}  // namespace graspbed::controller
