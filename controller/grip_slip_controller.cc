#include "controller/grip_slip_controller.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/config_error.h"
#include "controller/learned_slip_controller.h"
#include "controller/parameter_binding.h"

namespace graspbed::controller {
namespace {

using sensor::TactileState;
using sensor::UnitValidity;

/// Longest time step the integrator accepts [s]; a larger gap (first call, a pause of the clock)
/// is not integrated as if the error had persisted all along.
constexpr double kMaxStepS = 0.01;
/// Loading ends once the measured grip reaches this fraction of the target.
constexpr double kLoadedFraction = 0.9;
/// Times closer than this are equal [s]: a clock summed frame by frame lands a hair either side of
/// the instant a hold ends.
constexpr double kTimeToleranceS = 1e-9;
/// The share of the squeeze the units see is measured only this long after the last slip flag or
/// response [s]: a slipping object bounces on the pad.
constexpr double kCalmAfterSlipS = 0.2;

/// Static name of the cues that count as slip (telemetry; no allocation).
const char* CueNames(bool ratio, bool vibration, bool centroid, bool learned) {
  static constexpr const char* kNames[16] = {"",
                                             "ratio",
                                             "vibration",
                                             "ratio+vibration",
                                             "centroid",
                                             "ratio+centroid",
                                             "vibration+centroid",
                                             "ratio+vibration+centroid",
                                             "learned",
                                             "ratio+learned",
                                             "vibration+learned",
                                             "ratio+vibration+learned",
                                             "centroid+learned",
                                             "ratio+centroid+learned",
                                             "vibration+centroid+learned",
                                             "ratio+vibration+centroid+learned"};
  return kNames[(ratio ? 1 : 0) | (vibration ? 2 : 0) | (centroid ? 4 : 0) | (learned ? 8 : 0)];
}

using Binding = ParameterBinding<GripSlipConfig>;

#define GRASPBED_BIND(name, field, min, max, unit, doc) \
  GRASPBED_BIND_PARAMETER(GripSlipConfig, name, field, min, max, unit, doc)

const std::vector<Binding>& Bindings() {
  static const std::vector<Binding> bindings = {
      GRASPBED_BIND("close_effort", close_effort, 0.01, 1.0, "",
                    "motor effort while closing towards the object"),
      GRASPBED_BIND("open_effort", open_effort, 0.01, 1.0, "", "motor effort magnitude while releasing"),
      GRASPBED_BIND("release_time_s", release_time_s, 0.01, 10.0, "s",
                    "opening effort is applied this long after an open command, then 0"),
      GRASPBED_BIND("contact_unit_threshold_n", slip.contact_unit_threshold_n, 0.01, 5.0, "N",
                    "a valid unit is in contact above this normal force (and above contact_noise_sigmas x "
                    "its reported noise)"),
      GRASPBED_BIND("contact_noise_sigmas", slip.contact_noise_sigmas, 0.0, 20.0, "sigma",
                    "with the readout's noise figures, a unit is in contact only above this many standard "
                    "deviations of its normal-force noise too (and the contact's sum above as many of the "
                    "summed noise); 0 = off"),
      GRASPBED_BIND("contact_min_units", contact_min_units, 1, 64, "units",
                    "units in contact that mean the hand touches the object"),
      GRASPBED_BIND("contact_confirm_frames", contact_confirm_frames, 1, 100, "frames",
                    "consecutive frames with contact before loading starts"),
      GRASPBED_BIND("contact_lost_s", contact_lost_s, 0.005, 10.0, "s",
                    "no unit in contact this long while holding: close again"),
      GRASPBED_BIND("min_valid_units", min_valid_units, 1, 64, "units",
                    "fewer valid units than this: safe hold (last safe command kept)"),
      GRASPBED_BIND("initial_grip_n", initial_grip_n, 0.05, 100.0, "N", "grip reached in the loading phase"),
      GRASPBED_BIND("load_rate_n_per_s", load_rate_n_per_s, 0.1, 1000.0, "N/s",
                    "ramp rate of the grip target while loading"),
      GRASPBED_BIND("load_timeout_s", load_timeout_s, 0.01, 10.0, "s",
                    "loading ends after this long even if the grip lags"),
      GRASPBED_BIND("min_grip_n", min_grip_n, 0.05, 100.0, "N", "grip target floor while holding"),
      GRASPBED_BIND("max_grip_n", max_grip_n, 0.1, 200.0, "N",
                    "overall grip ceiling (sum of normal force over the units), honoured while slipping"),
      GRASPBED_BIND("safety_margin", safety_margin, 1.0, 5.0, "",
                    "grip target = tangential load / friction estimate x safety_margin"),
      GRASPBED_BIND("preload_coupling", preload_coupling, 0.0, 1.0, "",
                    "share of the shear locked in at grasp settle that the hold grip is coupled to, "
                    "besides the load added since (1: the whole shear, 0: the load alone)"),
      GRASPBED_BIND("grip_decrease_rate_n_per_s", grip_decrease_rate_n_per_s, 0.0, 1000.0, "N/s",
                    "how fast the coupled grip target may fall when the load drops"),
      GRASPBED_BIND("unit_range_n", unit_range_n, 0.1, 1000.0, "N",
                    "a saturated (out-of-range) unit is counted at this force; effort may not rise"),
      GRASPBED_BIND("friction_initial", friction_initial, 0.02, 5.0, "",
                    "friction coefficient assumed at the start of each grasp"),
      GRASPBED_BIND("friction_min", friction_min, 0.01, 5.0, "", "lower bound of the friction estimate"),
      GRASPBED_BIND("friction_learn_rate", friction_learn_rate, 0.0, 1.0, "",
                    "fraction of the way the estimate moves towards the ratio seen at slip"),
      GRASPBED_BIND("friction_learn_max_drop", friction_learn_max_drop, 0.0, 1.0, "",
                    "one slip lowers the friction estimate by at most this fraction of it; a slip at a "
                    "ratio further below the estimate (a jolt) teaches nothing"),
      GRASPBED_BIND("friction_learn_min_load_n", friction_learn_min_load_n, 0.0, 100.0, "N",
                    "the estimate is learned only from slips under at least this tangential load"),
      GRASPBED_BIND("effort_per_newton", effort_per_newton, 0.0, 1.0, "1/N",
                    "feed-forward effort per newton of grip target (about 1 / stall pinch force)"),
      GRASPBED_BIND("kp_effort_per_n", kp_effort_per_n, 0.0, 1.0, "1/N",
                    "proportional gain of the force loop"),
      GRASPBED_BIND("ki_effort_per_n_s", ki_effort_per_n_s, 0.0, 100.0, "1/(N s)",
                    "integral gain of the force loop"),
      GRASPBED_BIND("integrator_limit", integrator_limit, 0.0, 1.0, "", "bound of the integral term"),
      GRASPBED_BIND("max_effort", max_effort, 0.01, 1.0, "", "largest closing effort ever commanded"),
      GRASPBED_BIND("ceiling_effort_margin", ceiling_effort_margin, 1.0, 100.0, "",
                    "effort cap = this x effort_per_newton x grip ceiling (guards against a blind sensor)"),
      GRASPBED_BIND("grip_filter_s", grip_filter_s, 0.0, 0.1, "s",
                    "low-pass time constant of the measured grip"),
      GRASPBED_BIND("ceiling_deadband_n", ceiling_deadband_n, 0.0, 10.0, "N",
                    "with the target at its ceiling the P term acts only on the grip error beyond this band"),
      GRASPBED_BIND("slip_grip_gain", slip_grip_gain, 0.0, 5.0, "",
                    "on slip: grip target = max(target, grip) x (1 + slip_grip_gain) + slip_grip_step_n"),
      GRASPBED_BIND("slip_grip_step_n", slip_grip_step_n, 0.0, 50.0, "N",
                    "additive part of the slip response"),
      GRASPBED_BIND("slip_landed_fraction", slip_landed_fraction, 0.0, 1.0, "",
                    "a slip cue still up after a response asks for another only once the grip reached this "
                    "fraction of the raised floor (and the ratio cue says the load still exceeds it)"),
      GRASPBED_BIND("slip_vibration_rate_n_per_s", slip_vibration_rate_n_per_s, 0.0, 10000.0, "N/s",
                    "while only the vibration cue keeps reporting slip after a response, the slip floor "
                    "rises this fast; 0 = off"),
      GRASPBED_BIND("slip_refractory_s", slip_refractory_s, 0.001, 1.0, "s",
                    "a further slip event is counted no sooner than this"),
      GRASPBED_BIND("slip_floor_decay_n_per_s", slip_floor_decay_n_per_s, 0.0, 1000.0, "N/s",
                    "how fast the grip raised by a slip response relaxes back to the coupled target"),
      GRASPBED_BIND("slip_grip_rate_n_per_s", slip_grip_rate_n_per_s, 0.0, 10000.0, "N/s",
                    "while the cues keep reporting slip after a response, the slip floor keeps rising this "
                    "fast; 0 = off"),
      GRASPBED_BIND("ratio_ceiling_count_s", ratio_ceiling_count_s, 0.0, 10.0, "s",
                    "with the target at its ceiling, the ratio cue (and the centroid cue with it) counts as "
                    "slip only this long after its episode rose; 0 = not at all"),
      GRASPBED_BIND("ratio_ceiling_rearm_s", ratio_ceiling_rearm_s, 0.0, 10.0, "s",
                    "with the target at its ceiling, a ratio cue rising again within this time of falling "
                    "continues its episode instead of being a new slip; 0 = every rise is new"),
      GRASPBED_BIND("slip_flag_hold_s", slip_flag_hold_s, 0.0, 1.0, "s",
                    "the reported slip flag stays up this long after the cues last counted as slip (one "
                    "flag per episode); 0 = it follows the cues frame by frame"),
      GRASPBED_BIND("sample_rate_hz", slip.sample_rate_hz, 10.0, 100000.0, "Hz",
                    "tactile frame rate the detector filters are designed for"),
      GRASPBED_BIND("grid_columns", slip.grid_columns, 1, 64, "units",
                    "units per row in layout order (unit index = row x columns + column)"),
      GRASPBED_BIND("even_units_axial", slip.even_units_axial, 0, 1, "",
                    "1: units with (row + column) even have an axial beam (checkerboard); 0: odd ones"),
      GRASPBED_BIND("ratio_detector", slip.ratio_enabled, 0, 1, "", "1: use the shear/normal ratio cue"),
      GRASPBED_BIND("ratio_filter_s", slip.ratio_filter_s, 0.0, 1.0, "s",
                    "low-pass time constant of the ratio"),
      GRASPBED_BIND("ratio_slip_fraction", slip.ratio_slip_fraction, 0.1, 2.0, "",
                    "ratio cue fires above this fraction of the friction estimate"),
      GRASPBED_BIND(
          "ratio_release_fraction", slip.ratio_release_fraction, 0.01, 1.0, "",
          "once fired, the ratio cue holds until the ratio falls below this fraction of its threshold"),
      GRASPBED_BIND("ratio_noise_sigmas", slip.ratio_noise_sigmas, 0.0, 20.0, "sigma",
                    "ratio threshold raised by this many standard deviations of the ratio estimate"),
      GRASPBED_BIND("ratio_min_grip_n", slip.ratio_min_grip_n, 0.01, 100.0, "N",
                    "ratio evaluated only above this measured grip"),
      GRASPBED_BIND("vibration_detector", slip.vibration_enabled, 0, 1, "",
                    "1: use the high-passed shear energy cue"),
      GRASPBED_BIND("vibration_highpass_hz", slip.vibration_highpass_hz, 1.0, 10000.0, "Hz",
                    "cutoff of the 2nd-order high-pass on each unit's shear"),
      GRASPBED_BIND("vibration_window_s", slip.vibration_window_s, 0.0005, 1.0, "s",
                    "time constant of the high-passed shear energy average"),
      GRASPBED_BIND("vibration_factor", slip.vibration_factor, 1.0, 100.0, "",
                    "vibration cue fires above this multiple of the learned noise RMS"),
      GRASPBED_BIND("vibration_confirm_frames", slip.vibration_confirm_frames, 1, 100, "frames",
                    "vibration cue fires after this many consecutive frames above its threshold"),
      GRASPBED_BIND("vibration_min_rms_n", slip.vibration_min_rms_n, 0.0001, 10.0, "N",
                    "lower bound of the vibration threshold (mechanical vibration, noise-free signals)"),
      GRASPBED_BIND(
          "vibration_noise_sigmas", slip.vibration_noise_sigmas, 0.0, 20.0, "sigma",
          "with the readout's measured noise: vibration threshold floor = max(vibration_min_rms_n, this x "
          "the high-passed per-unit shear noise); 0 = off"),
      GRASPBED_BIND("shear_blind_noise_n", slip.shear_blind_noise_n, 0.0, 100.0, "N",
                    "readout shear noise per unit above which the shear cues are off and the grip is held at "
                    "shear_blind_grip_fraction of the ceiling; 0 = never"),
      GRASPBED_BIND("shear_blind_grip_fraction", shear_blind_grip_fraction, 0.0, 1.0, "",
                    "grip target as a fraction of the ceiling when the sensor cannot resolve shear"),
      GRASPBED_BIND("noise_floor_time_s", slip.noise_floor_time_s, 0.01, 100.0, "s",
                    "time constant of the learned noise floor"),
      GRASPBED_BIND("vibration_noise_reference", slip.vibration_noise_reference, 0, 1, "",
                    "1: the vibration threshold is at least vibration_factor x the high-passed shear RMS "
                    "of the units off the contact (a live noise reference: a noise burst raises it, a "
                    "slip does not)"),
      GRASPBED_BIND("centroid_detector", slip.centroid_enabled, 0, 1, "",
                    "1: use the contact-centroid movement cue"),
      GRASPBED_BIND("centroid_filter_s", slip.centroid_filter_s, 0.0, 0.1, "s",
                    "low-pass time constant of the normal-force centroid"),
      GRASPBED_BIND("centroid_window_s", slip.centroid_window_s, 0.001, 0.5, "s",
                    "centroid movement is measured over this window"),
      GRASPBED_BIND("centroid_shift_units", slip.centroid_shift_units, 0.01, 10.0, "pitch",
                    "centroid cue fires above this movement, in unit pitches"),
      GRASPBED_BIND(
          "centroid_drift_units", slip.centroid_drift_units, 0.01, 10.0, "pitch",
          "centroid cue also fires when the contact has drifted this far since the cues were armed"),
      GRASPBED_BIND("centroid_noise_sigmas", slip.centroid_noise_sigmas, 0.0, 20.0, "sigma",
                    "centroid thresholds raised by this many standard deviations of noise-induced movement"),
      GRASPBED_BIND("centroid_min_weight_n", slip.centroid_min_weight_n, 0.01, 100.0, "N",
                    "minimum contact normal force for a centroid"),
      GRASPBED_BIND(
          "centroid_grip_band", slip.centroid_grip_band, 0.0, 10.0, "",
          "the centroid drift reference is taken afresh when the grip moved by more than this fraction "
          "(the pad rolls with the grip); 0 = off"),
      GRASPBED_BIND("centroid_load_fraction", slip.centroid_load_fraction, 0.0, 10.0, "",
                    "with a shear estimate, the centroid cue fires only while the load ratio is at least "
                    "this fraction of the ratio threshold (the pad's centroid moves with load and "
                    "squeeze); 0 = off"),
      GRASPBED_BIND("centroid_rolling_preload_n", slip.centroid_rolling_preload_n, 0.0, 100.0, "N",
                    "centroid_load_fraction applies to contacts that seated with at least this much "
                    "locked-in shear (a pad that met the object obliquely and rolls)"),
      GRASPBED_BIND("detector_settle_s", slip.settle_s, 0.0, 1.0, "s",
                    "slip cues stay silent at least this long after contact onset or after stale data"),
      GRASPBED_BIND(
          "detector_settle_max_s", slip.settle_max_s, 0.0, 2.0, "s",
          "after detector_settle_s the cues wait for a quiet contact (vibration under its threshold), "
          "at most this long after contact onset or stale data"),
      GRASPBED_BIND("proprioception", use_proprioception, 0, 1, "",
                    "1: use the hand's motor current and joints where it reports them (the squeeze's absolute "
                    "limits on the object's real squeeze, a closing that found nothing stops); 0: the units "
                    "alone"),
      GRASPBED_BIND("learned_cue", learned_cue, 0, 1, "",
                    "1: the learned slip cue (model $GRASPBED_SLIP_MODEL, else the shipped "
                    "models/slip/default_20.json) also counts as slip, beside the hand-tuned cues"),
      GRASPBED_BIND("motor_stall_pinch_n", motor.stall_pinch_n, 1.0, 1000.0, "N",
                    "pinch force of a digit at stall with full effort (the hand's rating): motor current / "
                    "stall current x this is the squeeze the motor makes"),
      GRASPBED_BIND(
          "preload_reference", slip.preload_reference, 0, 1, "",
          "1: the shear locked in when the grasp settles is preload; the ratio cue measures the load on "
          "top of it"),
  };
  return bindings;
}

#undef GRASPBED_BIND

using common::Require;

/// `error` as a parameter's: a detector field's key becomes the parameter that sets it, and the
/// controller is named.
common::ConfigError AsParameterError(const common::ConfigError& error) {
  std::string key = error.key();
  for (const Binding& binding : Bindings()) {
    if ("slip." + key == binding.member) key = binding.name;
  }
  return common::ConfigError("", 0, key, error.value(), error.message())
      .WithContext("controller 'grip_slip'");
}

/// The detector's part of `config`, after validating all of it (so the first message names a
/// controller parameter).
const SlipDetectorConfig& ValidatedSlipConfig(const GripSlipConfig& config) {
  config.Validate();
  return config.slip;
}

}  // namespace

void GripSlipConfig::Validate() const {
  try {
    RequireParametersInRange<GripSlipConfig>(Bindings(), *this);
    Require(min_grip_n <= max_grip_n, "min_grip_n", min_grip_n, "must not exceed max_grip_n");
    Require(initial_grip_n <= max_grip_n, "initial_grip_n", initial_grip_n, "must not exceed max_grip_n");
    Require(friction_min <= friction_initial, "friction_min", friction_min,
            "must not exceed friction_initial");
    slip.Validate();
  } catch (const common::ConfigError& error) {
    throw AsParameterError(error);
  }
}

std::vector<ControllerParameter> GripSlipController::Parameters() {
  return DescribeParameters<GripSlipConfig>(Bindings());
}

GripSlipConfig GripSlipController::ConfigFromParams(const ControllerParams& params) {
  GripSlipConfig config;
  try {
    ApplyParameters<GripSlipConfig>(Bindings(), params, &config);
  } catch (const common::ConfigError& error) {
    throw AsParameterError(error);
  }
  config.Validate();
  return config;
}

GripSlipController::GripSlipController(const GripSlipConfig& config)
    : config_(config), detector_(ValidatedSlipConfig(config)), motor_(config.motor) {
  if (config_.learned_cue) {
    learned_ = std::make_unique<LearnedSlipCue>(
        LoadSlipModel(LearnedSlipController::DefaultModelPath(), {.layout_name = "", .units = 0}));
  }
  grip_filter_ = LowPassFilter(config_.grip_filter_s, 1.0 / config_.slip.sample_rate_hz);
  Reset();
}

const char* GripSlipController::PhaseName(Phase phase) {
  switch (phase) {
    case Phase::kIdle:
      return "idle";
    case Phase::kClosing:
      return "closing";
    case Phase::kMissed:
      return "missed";
    case Phase::kLoading:
      return "loading";
    case Phase::kHolding:
      return "holding";
    case Phase::kSlip:
      return "slip";
    case Phase::kReleasing:
      return "releasing";
    case Phase::kOpen:
      return "open";
  }
  return "unknown";
}

void GripSlipController::Reset() {
  detector_.Reset();
  motor_.Reset();
  if (learned_) learned_->Reset();
  learned_counts_ = false;
  grip_filter_.Clear();
  intent_ = GraspIntent::kIdle;
  phase_ = Phase::kIdle;
  phase_start_s_ = 0.0;
  safe_hold_ = false;
  have_time_ = false;
  have_frame_ = false;
  contact_frames_ = 0;
  last_contact_s_ = 0.0;
  friction_ = config_.friction_initial;
  load_target_n_ = 0.0;
  coupled_target_n_ = 0.0;
  slip_floor_n_ = 0.0;
  target_n_ = 0.0;
  integrator_ = 0.0;
  refractory_until_s_ = 0.0;
  cue_fell_since_response_ = true;
  ratio_was_up_ = false;
  ratio_counts_ = false;
  centroid_counts_ = false;
  ratio_rise_s_ = 0.0;
  ratio_fall_s_ = kNeverS;
  flag_until_s_ = kNeverS;
  flag_cues_ = "";
  last_good_command_ = hand::HandCommand{.grip_effort = 0.0};
  telemetry_ = ControllerTelemetry{};
  telemetry_.friction_estimate = friction_;
  diagnostics_ = GripSlipDiagnostics{};
  diagnostics_.ceiling_n = CeilingN();
}

namespace {

/// The logged signals, in the order ReadDiagnostics() writes them.
constexpr DiagnosticChannel kDiagnosticChannels[] = {
    {"measured_grip_n", "filtered grip force the loop closes on [N]"},
    {"slip_floor_n", "grip raised by the last slip response, decaying [N]"},
    {"load_ratio", "filtered load ratio, the load added since the grasp settled over the grip [-]"},
    {"ratio_threshold", "load ratio above which the ratio cue fires [-]"},
    {"vibration_rms_n", "RMS of the contact's high-passed shear, per unit [N]"},
    {"vibration_threshold_n", "vibration RMS above which the vibration cue counts frames [N]"},
    {"vibration_noise_n", "learned RMS of high-passed shear noise per unit [N]"},
    {"centroid_shift_pitch", "centroid movement over the window [unit pitches]"},
    {"centroid_shift_threshold_pitch", "threshold of the windowed movement [unit pitches]"},
    {"centroid_drift_pitch", "centroid movement since the drift reference [unit pitches]"},
    {"centroid_drift_threshold_pitch", "threshold of the drift [unit pitches]"},
    {"ratio_cue", "1 while the ratio cue is up (before the ceiling's hold) [-]"},
    {"vibration_cue", "1 while the vibration cue is up [-]"},
    {"centroid_cue", "1 while the centroid cue is up (before the ceiling's hold) [-]"},
    {"settled", "1 once the cues are armed after contact [-]"},
    {"shear_blind", "1 while the readout's shear noise is above shear_blind_noise_n [-]"},
    {"motor_squeeze_n", "squeeze the motor current says, 0 unknown (proprioception) [N]"},
    {"sensed_share", "share of the squeeze the units see, the grip's scale (1 until measured) [-]"},
};

}  // namespace

std::span<const DiagnosticChannel> GripSlipController::diagnostic_channels() const {
  return kDiagnosticChannels;
}

void GripSlipController::ReadDiagnostics(std::span<double> values) const {
  const SlipSignals& s = diagnostics_.signals;
  const double all[] = {diagnostics_.measured_grip_n,
                        diagnostics_.slip_floor_n,
                        s.load_ratio,
                        s.ratio_threshold,
                        s.vibration_rms_n,
                        s.vibration_threshold_n,
                        s.noise_rms_n,
                        s.centroid_shift_units,
                        s.centroid_shift_threshold,
                        s.centroid_drift_units,
                        s.centroid_drift_threshold,
                        s.ratio_slip ? 1.0 : 0.0,
                        s.vibration_slip ? 1.0 : 0.0,
                        s.centroid_slip ? 1.0 : 0.0,
                        s.settled ? 1.0 : 0.0,
                        s.shear_blind ? 1.0 : 0.0,
                        diagnostics_.motor_squeeze_n,
                        diagnostics_.sensed_share};
  static_assert(std::size(all) == std::size(kDiagnosticChannels));
  std::copy_n(all, std::min(values.size(), std::size(all)), values.begin());
}

void GripSlipController::SetIntent(GraspIntent intent) { intent_ = intent; }

void GripSlipController::SetGripCeiling(double ceiling_n) {
  if (std::isnan(ceiling_n)) throw std::invalid_argument("grip ceiling = nan: must be a number of newtons");
  task_ceiling_n_ = (ceiling_n > 0.0 && std::isfinite(ceiling_n)) ? ceiling_n : 0.0;
  diagnostics_.ceiling_n = CeilingN();
}

double GripSlipController::CeilingN() const {
  return task_ceiling_n_ > 0.0 ? std::min(task_ceiling_n_, config_.max_grip_n) : config_.max_grip_n;
}

double GripSlipController::SensedCeilingN() const { return Sensed(CeilingN()); }

double GripSlipController::Sensed(double squeeze_n) const { return squeeze_n * diagnostics_.sensed_share; }

void GripSlipController::Enter(Phase phase, double time_s) {
  phase_ = phase;
  phase_start_s_ = time_s;
}

double GripSlipController::EffortCap() const {
  return std::min(config_.max_effort, config_.ceiling_effort_margin * config_.effort_per_newton * CeilingN());
}

double GripSlipController::ForceLoop(double target_n, double grip_n, double dt_s, bool may_increase) {
  const double effort_cap = EffortCap();
  const double error_n = target_n - grip_n;
  // The feed-forward drives the whole squeeze, of which the units see sensed_share.
  const double feed_forward = config_.effort_per_newton * target_n / diagnostics_.sensed_share;
  // At the ceiling the grip may rise no further, and a P term there answers the summed noise of all
  // the units frame by frame: the finger shakes the contact and the vibration cue reads it as slip.
  // There it acts only on the error beyond a band (a motor stronger than the feed-forward assumes
  // still pushes past the ceiling and is pulled back).
  const bool at_ceiling = target_n >= SensedCeilingN();
  const double band_n = at_ceiling ? config_.ceiling_deadband_n : 0.0;
  const double proportional =
      config_.kp_effort_per_n * std::copysign(std::max(std::abs(error_n) - band_n, 0.0), error_n);
  double effort = feed_forward + proportional + integrator_;
  // Anti-windup: integrate only while the output is not pinned in the direction the error pushes,
  // and keep the integral term bounded.
  const bool pinned_high = effort >= effort_cap && error_n > 0.0;
  const bool pinned_low = effort <= 0.0 && error_n < 0.0;
  const bool blocked = !may_increase && error_n > 0.0;
  if (!pinned_high && !pinned_low && !blocked) {
    integrator_ = std::clamp(integrator_ + config_.ki_effort_per_n_s * error_n * dt_s,
                             -config_.integrator_limit, config_.integrator_limit);
  }
  effort = std::clamp(feed_forward + proportional + integrator_, 0.0, effort_cap);
  // A saturated unit hides how hard we already squeeze: never squeeze harder than last time.
  if (!may_increase) effort = std::min(effort, std::max(last_good_command_.grip_effort, 0.0));
  return effort;
}

void GripSlipController::UpdateHoldTarget(double dt_s) {
  const SlipSignals& signals = detector_.signals();
  // The friction holds the whole shear, the locked-in preload too (constant while the contact
  // sticks, so coupling to it does not feed back through the grip).
  const double shear_n = signals.tangential_load_n +
                        config_.preload_coupling * std::max(signals.contact_shear_n - signals.tangential_load_n, 0.0);
  const double coupled = std::max(Sensed(config_.min_grip_n), shear_n / friction_ * config_.safety_margin);
  // Rise at once, fall slowly: a load that drops for a moment must not loosen the grip with it.
  coupled_target_n_ = coupled >= coupled_target_n_
                          ? coupled
                          : std::max(coupled, coupled_target_n_ - config_.grip_decrease_rate_n_per_s * dt_s);
  // Stored above the ceiling (an impact's shear spike coupled at once), the target would sit at
  // the ceiling until it had decayed all the way down from there: it falls from the ceiling.
  coupled_target_n_ = std::min(coupled_target_n_, SensedCeilingN());
  slip_floor_n_ = std::max(0.0, slip_floor_n_ - config_.slip_floor_decay_n_per_s * dt_s);
}

void GripSlipController::RespondToSlip(double time_s) {
  const SlipSignals& signals = detector_.signals();
  ++telemetry_.slip_events;
  refractory_until_s_ = time_s + config_.slip_refractory_s;
  // At slip the contact sits on its friction cone: the ratio measured now is the friction
  // coefficient (or an upper bound of the part still sticking). The filtered ratio lags a sudden
  // load step, so this frame's own ratio counts too: the larger of the two is the better estimate of
  // where the cone is. The ratio cue itself compares against the estimate, so only the independent
  // cues teach the estimate.
  if ((signals.vibration_slip || signals.centroid_slip) &&
      signals.tangential_load_n >= config_.friction_learn_min_load_n) {
    // In the coordinates the ratio cue and the coupling use (the load's part, preload removed). A
    // slip at a ratio more than friction_learn_max_drop below the estimate is a jolt (an impact,
    // the pad reseating, a load step), not the friction limit, and teaches nothing: clamped to half
    // the estimate instead, each such flag halved it, and the ratio and centroid cues then fired on
    // ordinary loads (4 of the scorecard's false flags, the friction estimate down to 0.15).
    const double seen = std::max(signals.load_ratio, signals.instant_load_ratio);
    if (seen >= (1.0 - config_.friction_learn_max_drop) * friction_) {
      const double observed = std::min(seen, friction_);
      friction_ =
          std::max(config_.friction_min, friction_ + config_.friction_learn_rate * (observed - friction_));
    }
  }
  // From the target, not the measured grip: a slip that wedges the object into the pad (a ball
  // rolling in the pinch) spikes the squeeze for a few ms, and a response from that spike went
  // straight to the ceiling and stayed there.
  slip_floor_n_ = target_n_ * (1.0 + config_.slip_grip_gain) + Sensed(config_.slip_grip_step_n);
  cue_fell_since_response_ = false;
  Enter(Phase::kSlip, time_s);
}

double GripSlipController::AdvanceClock(double time_s) {
  const double dt_s = have_time_ ? std::clamp(time_s - last_time_s_, 0.0, kMaxStepS) : 0.0;
  have_time_ = true;
  last_time_s_ = time_s;
  return dt_s;
}

void GripSlipController::FollowIntent(double time_s) {
  // The user's intent changes the phase whatever the data say.
  const bool idle = phase_ == Phase::kIdle || phase_ == Phase::kOpen || phase_ == Phase::kReleasing;
  if (intent_ == GraspIntent::kOpen && phase_ != Phase::kReleasing && phase_ != Phase::kOpen) {
    Enter(Phase::kReleasing, time_s);
  } else if (intent_ == GraspIntent::kClose && idle) {
    Enter(Phase::kClosing, time_s);
    contact_frames_ = 0;
    friction_ = config_.friction_initial;
    slip_floor_n_ = 0.0;
    integrator_ = 0.0;
    motor_.RestartShare();
  }
}

hand::HandCommand GripSlipController::SafeHold() {
  // Keep the last command computed from good data, never opening on its own.
  safe_hold_ = true;
  hand::HandCommand command = last_good_command_;
  command.grip_effort = std::max(command.grip_effort, 0.0);
  telemetry_.phase = "safe_hold";
  telemetry_.safe_hold = true;
  telemetry_.slip_detected = false;
  telemetry_.slip_cues = "";
  telemetry_.grip_target_n = target_n_;
  telemetry_.friction_estimate = friction_;
  diagnostics_.effort = command.grip_effort;
  return command;
}

bool GripSlipController::TakeFrame(const TactileState& state, bool data_ok, double time_s) {
  if (safe_hold_ && data_ok) {
    // Data are back: the filters hold pre-gap samples, so restart them and let them settle.
    safe_hold_ = false;
    detector_.Restart();
    grip_filter_.Clear();
    last_contact_s_ = time_s;
  }
  telemetry_.safe_hold = !data_ok;
  const bool new_frame =
      data_ok && (!have_frame_ || state.sequence != last_sequence_ || state.time_s != last_frame_time_s_);
  if (!new_frame) return false;
  have_frame_ = true;
  last_sequence_ = state.sequence;
  last_frame_time_s_ = state.time_s;
  int saturated = 0;
  const int count = std::clamp(state.unit_count, 0, sensor::kMaxUnits);
  for (int i = 0; i < count; ++i) {
    if (state.validity[static_cast<size_t>(i)] == UnitValidity::kOutOfRange) ++saturated;
  }
  diagnostics_.saturated_units = saturated;
  diagnostics_.measured_grip_n = grip_filter_.Update(state.total_fn_n + saturated * config_.unit_range_n);
  const bool armed = phase_ == Phase::kLoading || phase_ == Phase::kHolding || phase_ == Phase::kSlip;
  detector_.Update(state, diagnostics_.measured_grip_n, friction_, armed, phase_ != Phase::kSlip);
  if (learned_) learned_counts_ = armed && learned_->Update(state, time_s).flag;
  return true;
}

hand::HandCommand GripSlipController::Close(bool new_frame, double time_s) {
  target_n_ = 0.0;
  hand::HandCommand command;
  // The index closed all the way round nothing: driving on would only stall the motor at the stop.
  if (config_.use_proprioception && motor_.closed_on_nothing()) {
    Enter(Phase::kMissed, time_s);
    return command;
  }
  command.grip_effort = std::min(config_.close_effort, EffortCap());
  const SlipSignals& signals = detector_.signals();
  if (new_frame) contact_frames_ = signals.contact_units >= config_.contact_min_units ? contact_frames_ + 1 : 0;
  if (contact_frames_ < config_.contact_confirm_frames) return command;
  Enter(Phase::kLoading, time_s);
  detector_.RestartContact();
  last_contact_s_ = time_s;
  load_target_n_ = std::min(diagnostics_.measured_grip_n, Sensed(config_.initial_grip_n));
  coupled_target_n_ = 0.0;
  // The closing effort drives the finger towards the object, not a force: the force loop starts
  // fresh from the force measured now, so the closing effort does not become a pinch.
  integrator_ = 0.0;
  return command;
}

bool GripSlipController::CountCues(double time_s) {
  // The ratio cue held up with the target at its ceiling says the load is beyond what the ceiling
  // allows by the friction estimate, not that the contact is sliding now (the grip can rise no
  // further either way). Past ratio_ceiling_count_s of its episode (by default from its rise) it
  // does not count as slip, nor does the centroid cue, whose check on a rolling pad is that same
  // load ratio; the vibration cue still does. Held up, it hid every later slip and kept the flag up
  // for seconds. A load hovering at the threshold crosses it again and again (pouring: a rise every
  // few ms): a rise soon after the last fall continues the episode.
  const SlipSignals& signals = detector_.signals();
  const bool at_ceiling = target_n_ >= SensedCeilingN();
  if (signals.ratio_slip && !ratio_was_up_) {
    const bool continues = at_ceiling && time_s - ratio_fall_s_ <= config_.ratio_ceiling_rearm_s;
    if (!continues) ratio_rise_s_ = time_s;
  }
  if (!signals.ratio_slip && ratio_was_up_) ratio_fall_s_ = time_s;
  ratio_was_up_ = signals.ratio_slip;
  const bool ratio_held =
      signals.ratio_slip && at_ceiling && time_s - ratio_rise_s_ >= config_.ratio_ceiling_count_s;
  ratio_counts_ = signals.ratio_slip && !ratio_held;
  centroid_counts_ = signals.centroid_slip && !ratio_held;
  return ratio_counts_ || signals.vibration_slip || centroid_counts_ || learned_counts_;
}

void GripSlipController::FollowSlip(bool slip_now, double time_s, double dt_s) {
  // A load cue persisting after a response (the ratio above the friction estimate, the contact
  // travelling) says the step did not cover the load: the floor keeps rising, and once the squeeze
  // has reached it another step follows. A vibration cue that stays up while the grip steps up is
  // also the step's own ringing of the contact: on its own it asks again only after it fell.
  if (!slip_now) cue_fell_since_response_ = true;
  const bool load_cue = ratio_counts_ || centroid_counts_;
  if (load_cue && phase_ == Phase::kSlip) {
    slip_floor_n_ += config_.slip_grip_rate_n_per_s * dt_s;
  } else if (slip_now && phase_ == Phase::kSlip) {
    // Vibration alone: a slide the step did not stop, or the step's own ringing; slower.
    slip_floor_n_ += config_.slip_vibration_rate_n_per_s * dt_s;
  }
  const double grip_n = diagnostics_.measured_grip_n;
  const bool landed = grip_n >= config_.slip_landed_fraction * std::min(slip_floor_n_, SensedCeilingN());
  const bool asks_again = cue_fell_since_response_ || (landed && load_cue);
  if (slip_now && time_s >= refractory_until_s_ && asks_again) RespondToSlip(time_s);
  if (phase_ == Phase::kSlip && time_s >= refractory_until_s_) Enter(Phase::kHolding, time_s);
}

hand::HandCommand GripSlipController::Hold(double time_s, double dt_s, bool* slip_now) {
  const SlipSignals& signals = detector_.signals();
  const double grip_n = diagnostics_.measured_grip_n;
  hand::HandCommand command;
  if (signals.in_contact) last_contact_s_ = time_s;
  if (time_s - last_contact_s_ > config_.contact_lost_s) {
    // Object gone (or never there): go back to closing rather than squeezing air harder.
    Enter(Phase::kClosing, time_s);
    contact_frames_ = 0;
    target_n_ = 0.0;
    command.grip_effort = std::min(config_.close_effort, EffortCap());
    return command;
  }
  UpdateHoldTarget(dt_s);
  const double ceiling_n = SensedCeilingN();
  if (phase_ == Phase::kLoading) {
    const double initial_n = Sensed(config_.initial_grip_n);
    load_target_n_ = std::min(load_target_n_ + Sensed(config_.load_rate_n_per_s) * dt_s, initial_n);
    const bool loaded = load_target_n_ >= initial_n && grip_n >= kLoadedFraction * std::min(initial_n, ceiling_n);
    if (loaded || time_s - phase_start_s_ >= config_.load_timeout_s) Enter(Phase::kHolding, time_s);
  }
  *slip_now = CountCues(time_s);
  FollowSlip(*slip_now, time_s, dt_s);
  double base_n = phase_ == Phase::kLoading ? std::max(load_target_n_, coupled_target_n_) : coupled_target_n_;
  // A sensor that cannot resolve shear cannot tell the load: hold at a fixed share of the ceiling.
  if (signals.shear_blind && phase_ != Phase::kLoading)
    base_n = std::max(base_n, config_.shear_blind_grip_fraction * ceiling_n);
  target_n_ = std::min(std::max(base_n, slip_floor_n_), ceiling_n);
  // The motor's squeeze at the ceiling already: the units' share may be stale, the object is not.
  const bool squeeze_room = !(config_.use_proprioception && motor_.known() && motor_.squeeze_n() >= CeilingN());
  command.grip_effort = ForceLoop(target_n_, grip_n, dt_s, diagnostics_.saturated_units == 0 && squeeze_room);
  return command;
}

hand::HandCommand GripSlipController::Release(double time_s) {
  target_n_ = 0.0;
  integrator_ = 0.0;
  hand::HandCommand command;
  command.grip_effort = -config_.open_effort;
  if (time_s - phase_start_s_ >= config_.release_time_s) Enter(Phase::kOpen, time_s);
  return command;
}

hand::HandCommand GripSlipController::Report(const hand::HandCommand& command, bool slip_now, bool data_ok,
                                             double time_s) {
  // Outside the phases that watch for slip the cues are silent: a ratio cue up again later rose anew.
  if (phase_ != Phase::kLoading && phase_ != Phase::kHolding && phase_ != Phase::kSlip) {
    ratio_was_up_ = false;
    ratio_fall_s_ = kNeverS;
    ratio_counts_ = false;
    centroid_counts_ = false;
    learned_counts_ = false;
    flag_until_s_ = kNeverS;
  }
  // The reported flag is held past the last frame a cue counted (slip_flag_hold_s): a cue flickering
  // about its threshold within one episode is one flag; the response follows the cues.
  const SlipSignals& signals = detector_.signals();
  if (slip_now) {
    flag_until_s_ = time_s + config_.slip_flag_hold_s;
    flag_cues_ = CueNames(ratio_counts_, signals.vibration_slip, centroid_counts_, learned_counts_);
  }
  const bool flag_up = slip_now || time_s < flag_until_s_ - kTimeToleranceS;
  if (data_ok) last_good_command_ = command;
  telemetry_.phase = PhaseName(phase_);
  telemetry_.grip_target_n = target_n_;
  telemetry_.friction_estimate = friction_;
  telemetry_.slip_detected = flag_up;
  telemetry_.slip_cues = flag_up ? flag_cues_ : "";
  diagnostics_.effort = command.grip_effort;
  diagnostics_.integrator = integrator_;
  diagnostics_.ceiling_n = SensedCeilingN();
  diagnostics_.slip_floor_n = slip_floor_n_;
  diagnostics_.signals = signals;
  return command;
}

hand::HandCommand GripSlipController::Update(const TactileState& state, const hand::HandState& hand,
                                             double time_s) {
  const double dt_s = AdvanceClock(time_s);
  FollowIntent(time_s);
  const bool releasing = phase_ == Phase::kReleasing || phase_ == Phase::kOpen;
  const bool data_ok = !state.stale && state.valid_count >= config_.min_valid_units;
  if (!data_ok && !releasing) return SafeHold();
  const bool new_frame = TakeFrame(state, data_ok, time_s);
  if (config_.use_proprioception) {
    const bool calm = (phase_ == Phase::kLoading || phase_ == Phase::kHolding) &&
                      time_s - flag_until_s_ >= kCalmAfterSlipS && time_s - refractory_until_s_ >= kCalmAfterSlipS;
    motor_.Update(hand, last_good_command_.grip_effort, diagnostics_.measured_grip_n, calm, dt_s);
    diagnostics_.motor_squeeze_n = motor_.squeeze_n();
    // The targets are kept in the units' measure: a new share rescales them, so the squeeze they
    // stand for does not jump (a share halving at once doubled the feed-forward: a cup crushed).
    const double rescale = motor_.sensed_share() / diagnostics_.sensed_share;
    load_target_n_ *= rescale;
    coupled_target_n_ *= rescale;
    slip_floor_n_ *= rescale;
    target_n_ *= rescale;
    diagnostics_.sensed_share = motor_.sensed_share();
  }
  bool slip_now = false;
  hand::HandCommand command;
  switch (phase_) {
    case Phase::kClosing:
      command = Close(new_frame, time_s);
      break;
    case Phase::kLoading:
    case Phase::kHolding:
    case Phase::kSlip:
      command = Hold(time_s, dt_s, &slip_now);
      break;
    case Phase::kReleasing:
      command = Release(time_s);
      break;
    case Phase::kIdle:
    case Phase::kMissed:
    case Phase::kOpen:
      target_n_ = 0.0;
      break;
  }
  return Report(command, slip_now, data_ok, time_s);
}

}  // namespace graspbed::controller
