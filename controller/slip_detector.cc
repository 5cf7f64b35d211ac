#include "controller/slip_detector.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/config_error.h"

namespace graspbed::controller {
namespace {

using common::Require;

using sensor::TactileState;
using sensor::UnitValidity;

/// Shear totals recomputed from the units must match the state's own totals this closely [N];
/// both are sums of the same doubles, so only rounding separates them when the layout matches.
constexpr double kOrientationCheckTolN = 1e-6;
/// Below this summed normal force an orientation set contributes no ratio component [N].
constexpr double kMinSetNormalN = 0.1;
/// Frames averaged without clipping when the noise floor starts (after Reset()).
constexpr long kNoisePrimeFrames = 50;
/// Centroid weights start at this fraction of the contact threshold (noise on unloaded units
/// carries no weight, light contacts still count).
constexpr double kCentroidDeadbandFraction = 0.5;
/// Units under this fraction of the contact threshold are off the contact (the noise reference).
constexpr double kReferenceFraction = 0.5;
/// A measured grip above this multiple of the per-unit contact threshold also means contact.
constexpr double kContactSumFactor = 3.0;
/// Below this sum of squared weights a set carries no vibration estimate [N^2].
constexpr double kMinWeightEnergyN2 = 1e-4;
/// Most samples of the high-pass impulse response summed for its noise power gain; the sum stops
/// earlier once a stretch of kImpulseTailSamples adds less than kImpulseTailFraction of it (at
/// 40 Hz / 1 kHz after a few hundred samples: the whole loop cost 5 % of a short scenario run).
constexpr int kImpulseResponseSamples = 20000;
constexpr int kImpulseTailSamples = 32;
constexpr double kImpulseTailFraction = 1e-20;

}  // namespace

void SlipDetectorConfig::Validate() const {
  Require(std::isfinite(sample_rate_hz) && sample_rate_hz > 0.0, "sample_rate_hz", sample_rate_hz,
          "must be > 0");
  Require(grid_columns >= 1 && grid_columns <= sensor::kMaxUnits, "grid_columns", grid_columns,
          "must be in [1, 64]");
  Require(contact_noise_sigmas >= 0.0, "contact_noise_sigmas", contact_noise_sigmas, "must be >= 0");
  Require(contact_unit_threshold_n > 0.0, "contact_unit_threshold_n", contact_unit_threshold_n,
          "must be > 0");
  Require(ratio_filter_s >= 0.0, "ratio_filter_s", ratio_filter_s, "must be >= 0");
  Require(ratio_slip_fraction > 0.0, "ratio_slip_fraction", ratio_slip_fraction, "must be > 0");
  Require(ratio_release_fraction > 0.0 && ratio_release_fraction <= 1.0, "ratio_release_fraction",
          ratio_release_fraction, "must be in (0, 1]");
  Require(shear_blind_noise_n >= 0.0, "shear_blind_noise_n", shear_blind_noise_n, "must be >= 0");
  Require(ratio_noise_sigmas >= 0.0, "ratio_noise_sigmas", ratio_noise_sigmas, "must be >= 0");
  Require(ratio_min_grip_n > 0.0, "ratio_min_grip_n", ratio_min_grip_n, "must be > 0");
  Require(vibration_highpass_hz > 0.0 && vibration_highpass_hz < 0.45 * sample_rate_hz,
          "vibration_highpass_hz", vibration_highpass_hz, "must be in (0, 0.45 x sample_rate_hz)");
  Require(vibration_window_s > 0.0, "vibration_window_s", vibration_window_s, "must be > 0");
  Require(vibration_factor >= 1.0, "vibration_factor", vibration_factor, "must be >= 1");
  Require(vibration_confirm_frames >= 1, "vibration_confirm_frames", vibration_confirm_frames,
          "must be >= 1");
  Require(vibration_min_rms_n > 0.0, "vibration_min_rms_n", vibration_min_rms_n, "must be > 0");
  Require(vibration_noise_sigmas >= 0.0 && std::isfinite(vibration_noise_sigmas), "vibration_noise_sigmas",
          vibration_noise_sigmas, "must be >= 0");
  Require(noise_floor_time_s > 0.0, "noise_floor_time_s", noise_floor_time_s, "must be > 0");
  Require(centroid_filter_s >= 0.0, "centroid_filter_s", centroid_filter_s, "must be >= 0");
  const double window_samples = centroid_window_s * sample_rate_hz;
  Require(window_samples >= 1.0 && window_samples < kMaxWindowSamples, "centroid_window_s", centroid_window_s,
          "must span 1 to 511 frames at sample_rate_hz");
  Require(centroid_shift_units > 0.0, "centroid_shift_units", centroid_shift_units, "must be > 0");
  Require(centroid_drift_units > 0.0, "centroid_drift_units", centroid_drift_units, "must be > 0");
  Require(centroid_noise_sigmas >= 0.0, "centroid_noise_sigmas", centroid_noise_sigmas, "must be >= 0");
  Require(centroid_min_weight_n > 0.0, "centroid_min_weight_n", centroid_min_weight_n, "must be > 0");
  Require(centroid_grip_band >= 0.0, "centroid_grip_band", centroid_grip_band, "must be >= 0");
  Require(centroid_load_fraction >= 0.0, "centroid_load_fraction", centroid_load_fraction, "must be >= 0");
  Require(centroid_rolling_preload_n >= 0.0, "centroid_rolling_preload_n", centroid_rolling_preload_n,
          "must be >= 0");
  Require(settle_s >= 0.0, "settle_s", settle_s, "must be >= 0");
  Require(settle_max_s >= settle_s, "settle_max_s", settle_max_s, "must be >= settle_s");
}

SlipDetector::SlipDetector(const SlipDetectorConfig& config) : config_(config) {
  config_.Validate();
  const double period_s = 1.0 / config_.sample_rate_hz;
  centroid_window_samples_ = std::max(1, static_cast<int>(std::lround(config_.centroid_window_s / period_s)));
  settle_samples_ = static_cast<int>(std::lround(config_.settle_s / period_s));
  settle_max_samples_ = static_cast<int>(std::lround(config_.settle_max_s / period_s));
  noise_floor_alpha_ = 1.0 - std::exp(-period_s / config_.noise_floor_time_s);
  ratio_filter_ = LowPassFilter(config_.ratio_filter_s, period_s);
  ratio_circumferential_filter_ = LowPassFilter(config_.ratio_filter_s, period_s);
  // Variance of a first-order low-pass output over that of its white input: alpha / (2 - alpha).
  const double ratio_alpha =
      config_.ratio_filter_s > 0.0 ? 1.0 - std::exp(-period_s / config_.ratio_filter_s) : 1.0;
  ratio_variance_reduction_ = ratio_alpha / (2.0 - ratio_alpha);
  for (auto& filter : shear_highpass_)
    filter = HighPassBiquad(config_.vibration_highpass_hz, config_.sample_rate_hz);
  // White noise power the high-pass keeps: the energy of its impulse response.
  HighPassBiquad impulse(config_.vibration_highpass_hz, config_.sample_rate_hz);
  highpass_power_fraction_ = 0.0;
  double tail = 0.0;
  for (int n = 0; n < kImpulseResponseSamples; ++n) {
    const double h = impulse.Update(n == 0 ? 1.0 : 0.0);
    highpass_power_fraction_ += h * h;
    tail += h * h;
    if ((n + 1) % kImpulseTailSamples == 0) {
      if (n > kImpulseTailSamples && tail < kImpulseTailFraction * highpass_power_fraction_) break;
      tail = 0.0;
    }
  }
  vibration_energy_ = LowPassFilter(config_.vibration_window_s, period_s);
  reference_energy_ = LowPassFilter(config_.vibration_window_s, period_s);
  centroid_row_filter_ = LowPassFilter(config_.centroid_filter_s, period_s);
  const double centroid_alpha =
      config_.centroid_filter_s > 0.0 ? 1.0 - std::exp(-period_s / config_.centroid_filter_s) : 1.0;
  centroid_variance_reduction_ = centroid_alpha / (2.0 - centroid_alpha);
  centroid_column_filter_ = LowPassFilter(config_.centroid_filter_s, period_s);
  Reset();
}

void SlipDetector::Reset() {
  // Start the floor where the threshold equals its lower bound; it adapts to the real noise within
  // a few hundred frames (while the hand is open or closing).
  const double start_rms = config_.vibration_min_rms_n / config_.vibration_factor;
  noise_energy_ = start_rms * start_rms;
  noise_samples_ = 0;
  signals_ = SlipSignals{};
  settle_threshold_n_ = 0.0;
  noise_known_seen_ = false;
  noise_generation_seen_ = 0;
  ResetContactThresholds();
  RestartContact();
}

void SlipDetector::Restart() {
  restart_pending_ = true;
  settle_remaining_ = settle_samples_;
  settle_max_remaining_ = settle_max_samples_;
  signals_.settled = false;
  ratio_filter_.Clear();
  ratio_circumferential_filter_.Clear();
  vibration_energy_.Reset(0.0);
  reference_energy_.Clear();
  centroid_row_filter_.Clear();
  centroid_column_filter_.Clear();
  centroid_history_.Clear();
  have_reference_ = false;
}

void SlipDetector::RestartContact() {
  Restart();
  have_preload_ = false;
  preload_frames_ = 0;
  signals_.preload_shear_axial_n = 0.0;
  signals_.preload_shear_circumferential_n = 0.0;
}

void SlipDetector::ResetContactThresholds() {
  unit_contact_threshold_n_.fill(config_.contact_unit_threshold_n);
  contact_sum_threshold_n_ = kContactSumFactor * config_.contact_unit_threshold_n;
  signals_.contact_threshold_n = config_.contact_unit_threshold_n;
}

bool SlipDetector::IsAxial(int unit) const {
  const int row = unit / config_.grid_columns;
  const int column = unit % config_.grid_columns;
  return ((row + column) % 2 == 0) == config_.even_units_axial;
}

const SlipSignals& SlipDetector::Update(const TactileState& state, double grip_n, double friction_estimate,
                                        bool armed, bool learn_noise) {
  const int count = std::clamp(state.unit_count, 0, sensor::kMaxUnits);
  // A unit that (re)appears or drops out changes the sums and the centroid: restart its filter and
  // the centroid history instead of reading the jump as slip.
  bool validity_changed = false;
  for (int i = 0; i < count; ++i) {
    const bool valid = state.validity[static_cast<size_t>(i)] == UnitValidity::kValid;
    if (valid && (!was_valid_[static_cast<size_t>(i)] || restart_pending_)) {
      shear_highpass_[static_cast<size_t>(i)].Reset(state.ft_n[static_cast<size_t>(i)]);
    }
    if (valid != was_valid_[static_cast<size_t>(i)]) validity_changed = true;
    was_valid_[static_cast<size_t>(i)] = valid;
  }
  if (validity_changed && !restart_pending_) {
    centroid_row_filter_.Clear();
    centroid_column_filter_.Clear();
    centroid_history_.Clear();
    have_reference_ = false;
  }
  restart_pending_ = false;

  // The readout's own noise figure, RMS over the valid units: it changes only with a new tare or a
  // unit changing validity.
  const bool noise_changed =
      state.noise_known != noise_known_seen_ || state.noise_generation != noise_generation_seen_;
  if (noise_changed || validity_changed) {
    noise_known_seen_ = state.noise_known;
    noise_generation_seen_ = state.noise_generation;
    UpdateSensorNoise(state);
  }

  signals_.contact_units = 0;
  for (int i = 0; i < count; ++i) {
    if (state.validity[static_cast<size_t>(i)] == UnitValidity::kValid &&
        state.fn_n[static_cast<size_t>(i)] > unit_contact_threshold_n_[static_cast<size_t>(i)]) {
      ++signals_.contact_units;
    }
  }
  // A light, broad contact may leave every unit below the threshold while the sum is clearly there.
  signals_.in_contact = signals_.contact_units > 0 || grip_n > contact_sum_threshold_n_;

  if (settle_remaining_ > 0) --settle_remaining_;
  if (settle_max_remaining_ > 0) --settle_max_remaining_;
  // Settled: settle_s over and the contact quiet (last frame's vibration statistic under its
  // threshold), or settle_max_s over. Once settled it stays so until the next Restart().
  if (!signals_.settled) {
    // Against the threshold without the live noise reference, which would call the contact quiet
    // while the seating still rings (it knows the noise before the learned floor has converged).
    const bool quiet = signals_.vibration_rms_n <= settle_threshold_n_;
    signals_.settled = settle_remaining_ == 0 && (quiet || settle_max_remaining_ == 0);
  }
  const bool live = armed && signals_.settled && signals_.in_contact;

  UpdateRatio(state, grip_n, friction_estimate, live);
  // The contact's seating transient (armed, not yet settled) is not noise: the floor learns before
  // contact and once the grasp has settled.
  UpdateVibration(state, learn_noise && (!armed || signals_.settled));
  UpdateCentroid(state, grip_n, live);
  // Hysteresis: once fired, the cue holds until the ratio falls below ratio_release_fraction of the
  // threshold, so a load hovering at the threshold (a grip pinned at its ceiling) is one flag, not a
  // flag at every noise crossing.
  const double ratio_bar = signals_.ratio_slip ? config_.ratio_release_fraction * signals_.ratio_threshold
                                               : signals_.ratio_threshold;
  signals_.ratio_slip = live && config_.ratio_enabled && !signals_.shear_blind &&
                        grip_n > config_.ratio_min_grip_n && signals_.load_ratio > ratio_bar;
  // A single frame over the threshold is a noise peak of the averaged statistic far more often than
  // slip, which keeps the statistic up for many frames.
  vibration_frames_ = signals_.vibration_rms_n > signals_.vibration_threshold_n ? vibration_frames_ + 1 : 0;
  signals_.vibration_slip = live && config_.vibration_enabled && !signals_.shear_blind &&
                            vibration_frames_ >= config_.vibration_confirm_frames;
  // The centroid moves with load and squeeze on a soft pad: with a shear estimate to check it
  // against, the movement is slip only while the load is a good part of the way to the friction limit.
  const bool rolling_pad =
      have_preload_ && std::hypot(signals_.preload_shear_axial_n, signals_.preload_shear_circumferential_n) >=
                           config_.centroid_rolling_preload_n;
  const bool load_corroborates =
      signals_.shear_blind || !config_.ratio_enabled || !rolling_pad ||
      signals_.load_ratio >= config_.centroid_load_fraction * signals_.ratio_threshold;
  signals_.centroid_slip = live && config_.centroid_enabled && load_corroborates &&
                           (signals_.centroid_shift_units > signals_.centroid_shift_threshold ||
                            signals_.centroid_drift_units > signals_.centroid_drift_threshold);
  if (signals_.centroid_slip) {
    // A drift is reported once; the next one is measured from here.
    centroid_reference_ = {signals_.centroid_row, signals_.centroid_column};
    centroid_reference_grip_n_ = grip_n;
  }
  return signals_;
}

void SlipDetector::UpdateSensorNoise(const TactileState& state) {
  signals_.sensor_shear_noise_n = 0.0;
  signals_.sensor_normal_noise_n = 0.0;
  signals_.shear_blind = false;
  ResetContactThresholds();
  if (!state.noise_known) return;
  const int count = std::clamp(state.unit_count, 0, sensor::kMaxUnits);
  double shear_sum = 0.0, normal_sum = 0.0;
  int valid = 0;
  for (int i = 0; i < count; ++i) {
    if (state.validity[static_cast<size_t>(i)] != UnitValidity::kValid) continue;
    const double fn_noise = state.fn_noise_n[static_cast<size_t>(i)];
    shear_sum += state.ft_noise_n[static_cast<size_t>(i)] * state.ft_noise_n[static_cast<size_t>(i)];
    normal_sum += fn_noise * fn_noise;
    ++valid;
    double& threshold = unit_contact_threshold_n_[static_cast<size_t>(i)];
    threshold = std::max(threshold, config_.contact_noise_sigmas * fn_noise);
    signals_.contact_threshold_n = std::max(signals_.contact_threshold_n, threshold);
  }
  // The summed normal force's noise: the units' noises add in quadrature.
  contact_sum_threshold_n_ =
      std::max(contact_sum_threshold_n_, config_.contact_noise_sigmas * std::sqrt(normal_sum));
  if (valid > 0) {
    signals_.sensor_shear_noise_n = std::sqrt(shear_sum / valid);
    signals_.sensor_normal_noise_n = std::sqrt(normal_sum / valid);
  }
  signals_.shear_blind =
      config_.shear_blind_noise_n > 0.0 && signals_.sensor_shear_noise_n > config_.shear_blind_noise_n;
}

void SlipDetector::UpdateRatio(const TactileState& state, double grip_n, double friction_estimate,
                               bool live) {
  const int count = std::clamp(state.unit_count, 0, sensor::kMaxUnits);
  // Normal-weighted ratio per beam orientation: sum(fn ft) / sum(fn^2) equals the traction ratio
  // when shear is proportional to pressure, and gives units without contact (noise only) no weight.
  double weighted_shear[2] = {0.0, 0.0};
  double weighted_normal[2] = {0.0, 0.0};
  double normal_sum[2] = {0.0, 0.0};
  double plain_shear[2] = {0.0, 0.0};
  for (int i = 0; i < count; ++i) {
    if (state.validity[static_cast<size_t>(i)] != UnitValidity::kValid) continue;
    const int set = IsAxial(i) ? 0 : 1;
    const double fn = state.fn_n[static_cast<size_t>(i)];
    const double ft = state.ft_n[static_cast<size_t>(i)];
    plain_shear[set] += ft;
    const double weight = std::max(fn, 0.0);
    weighted_shear[set] += weight * ft;
    weighted_normal[set] += weight * fn;
    normal_sum[set] += weight;
  }
  signals_.orientation_consistent =
      std::abs(plain_shear[0] - state.total_shear_axial_n) <= kOrientationCheckTolN * (1.0 + count) &&
      std::abs(plain_shear[1] - state.total_shear_circumferential_n) <= kOrientationCheckTolN * (1.0 + count);

  // Components are filtered before they are combined so noise on an unloaded component does not
  // bias the magnitude upwards.
  double component[2] = {0.0, 0.0};
  double variance_per_noise[2] = {0.0, 0.0};  // variance of each component per unit shear noise power
  if (signals_.orientation_consistent) {
    for (int set = 0; set < 2; ++set) {
      if (normal_sum[set] > kMinSetNormalN) {
        component[set] = weighted_shear[set] / weighted_normal[set];
        variance_per_noise[set] = 1.0 / weighted_normal[set];
      }
    }
  } else if (state.total_fn_n > kMinSetNormalN) {
    // Unknown orientations: each total sees about half of the contact, hence the factor 2.
    component[0] =
        2.0 * std::hypot(state.total_shear_axial_n, state.total_shear_circumferential_n) / state.total_fn_n;
    variance_per_noise[0] = 4.0 * count / (state.total_fn_n * state.total_fn_n);
  }
  double noise_sigma = 0.0;
  if (grip_n > config_.ratio_min_grip_n) {
    const double axial = ratio_filter_.Update(component[0]);
    const double circumferential = ratio_circumferential_filter_.Update(component[1]);
    signals_.ratio = std::hypot(axial, circumferential);
    signals_.instant_ratio = std::hypot(component[0], component[1]);
    ratio_axial_ = axial;
    ratio_circumferential_ = circumferential;
    // Delta method: variance of the magnitude from the components' variances, reduced by the
    // low-pass; the learned shear noise sets the scale.
    if (signals_.ratio > 0.0) {
      const double variance = (axial * axial * variance_per_noise[0] +
                               circumferential * circumferential * variance_per_noise[1]) /
                              (signals_.ratio * signals_.ratio);
      noise_sigma = signals_.noise_rms_n * std::sqrt(variance * ratio_variance_reduction_);
    }
  } else {
    ratio_filter_.Clear();
    ratio_circumferential_filter_.Clear();
    signals_.ratio = 0.0;
    signals_.instant_ratio = 0.0;
    ratio_axial_ = 0.0;
    ratio_circumferential_ = 0.0;
  }
  // The preload: shear the contact locks in as it squeezes. On a flexing finger the pad meets the
  // object obliquely and slides into place as the finger flexes, so the grasp settles with shear
  // in it; the contact then sticks, and a sticking contact keeps that shear whatever the grip does
  // (more squeeze adds no tangential force). So the preload is a shear [N], the mean of each
  // set's ratio x grip over the first settle_s of live frames, and the load is the shear on top of
  // it: load ratio = |shear - preload| / grip. (Taken as a ratio instead, a grip raised after a
  // slip lowers the ratio under the preload ratio and reads as more load: positive feedback to the
  // ceiling, with the flag held up.) A load already on when the grasp settles is taken as preload
  // too. Until the window is over there is no load estimate. Taken once per contact
  // (RestartContact()), kept over a stale gap.
  const double grip_for_load_n = std::max(grip_n, config_.ratio_min_grip_n);
  if (config_.preload_reference && live && !have_preload_ && grip_n > config_.ratio_min_grip_n) {
    ++preload_frames_;
    const double weight = 1.0 / preload_frames_;
    signals_.preload_shear_axial_n += weight * (ratio_axial_ * grip_n - signals_.preload_shear_axial_n);
    signals_.preload_shear_circumferential_n +=
        weight * (ratio_circumferential_ * grip_n - signals_.preload_shear_circumferential_n);
    have_preload_ = preload_frames_ >= std::max(settle_samples_, 1);
  }
  const bool no_estimate =
      (config_.preload_reference && !have_preload_) || grip_n <= config_.ratio_min_grip_n;
  const auto load_ratio = [&](double axial, double circumferential) {
    return std::hypot(axial * grip_for_load_n - signals_.preload_shear_axial_n,
                      circumferential * grip_for_load_n - signals_.preload_shear_circumferential_n) /
           grip_for_load_n;
  };
  signals_.load_ratio = no_estimate ? 0.0 : load_ratio(ratio_axial_, ratio_circumferential_);
  signals_.instant_load_ratio = no_estimate ? 0.0 : load_ratio(component[0], component[1]);
  signals_.tangential_load_n = signals_.shear_blind ? 0.0 : signals_.load_ratio * std::max(grip_n, 0.0);
  signals_.contact_shear_n = signals_.shear_blind ? 0.0 : signals_.ratio * std::max(grip_n, 0.0);
  signals_.ratio_threshold =
      config_.ratio_slip_fraction * friction_estimate + config_.ratio_noise_sigmas * noise_sigma;
}

void SlipDetector::UpdateVibration(const TactileState& state, bool learn_noise) {
  const int count = std::clamp(state.unit_count, 0, sensor::kMaxUnits);
  // Matched filter: stick-slip moves the whole contact together, so the high-passed shear of the
  // units is summed with weights equal to their normal force (per beam orientation, since each set
  // sees its own component). Normalised by the weights' energy, the statistic has the per-unit
  // noise power as its expectation whatever the contact size, and coherent vibration gains by the
  // square root of the number of loaded units.
  double weighted[2] = {0.0, 0.0};
  double weight_energy[2] = {0.0, 0.0};
  double reference_square_sum = 0.0;  // off-contact units: noise only
  int reference_units = 0;
  for (int i = 0; i < count; ++i) {
    if (state.validity[static_cast<size_t>(i)] != UnitValidity::kValid) continue;
    const double highpassed =
        shear_highpass_[static_cast<size_t>(i)].Update(state.ft_n[static_cast<size_t>(i)]);
    if (state.fn_n[static_cast<size_t>(i)] <
        kReferenceFraction * unit_contact_threshold_n_[static_cast<size_t>(i)]) {
      reference_square_sum += highpassed * highpassed;
      ++reference_units;
    }
    const double weight = std::max(state.fn_n[static_cast<size_t>(i)], 0.0);
    const int set = (!signals_.orientation_consistent || IsAxial(i)) ? 0 : 1;
    weighted[set] += weight * highpassed;
    weight_energy[set] += weight * weight;
  }
  double sample = 0.0;  // sum over the two sets of (sum w hp)^2 / sum w^2 [N^2]
  int sets = 0;
  for (int set = 0; set < 2; ++set) {
    if (weight_energy[set] <= kMinWeightEnergyN2) continue;
    sample += weighted[set] * weighted[set] / weight_energy[set];
    ++sets;
  }
  if (sets == 0) {
    vibration_energy_.Reset(0.0);
    signals_.vibration_rms_n = 0.0;
  } else {
    // Per set, so the numbers read as the RMS of one unit's high-passed shear noise.
    sample /= sets;
    signals_.vibration_rms_n = std::sqrt(vibration_energy_.Update(sample));
    // Noise floor: slow average of the same statistic. Samples are clipped at the current
    // threshold so a transient raises the floor only slowly, while a real rise of the noise is
    // still followed; a running mean without clipping gives a fast start.
    if (learn_noise) {
      ++noise_samples_;
      const double threshold_energy = config_.vibration_factor * config_.vibration_factor * noise_energy_;
      const double clipped =
          noise_samples_ <= kNoisePrimeFrames ? sample : std::min(sample, threshold_energy);
      const double alpha = std::max(noise_floor_alpha_, 1.0 / static_cast<double>(noise_samples_));
      noise_energy_ += alpha * (clipped - noise_energy_);
    }
  }
  signals_.noise_rms_n = std::sqrt(noise_energy_);
  // The floor: the fixed bound (the contact's own mechanical vibration, noise-free signals) or, on a
  // noisier readout, a multiple of the noise the readout measured at its tare (known from the first
  // frame of contact, before the learned floor has converged, and untouched by the contact).
  const double floor_n =
      std::max(config_.vibration_min_rms_n, config_.vibration_noise_sigmas * signals_.sensor_shear_noise_n *
                                                std::sqrt(highpass_power_fraction_));
  signals_.vibration_threshold_n = std::max(config_.vibration_factor * signals_.noise_rms_n, floor_n);
  settle_threshold_n_ = signals_.vibration_threshold_n;
  // The live noise reference: a noise burst (EMI, a loose connector) raises every unit's noise at
  // once, faster than the slow floor follows and while a slip response has it frozen; the units off
  // the contact show it, and a slip's vibration on the loaded units leaves them quiet.
  if (config_.vibration_noise_reference && reference_units >= SlipDetectorConfig::kMinReferenceUnits) {
    signals_.vibration_reference_rms_n =
        std::sqrt(reference_energy_.Update(reference_square_sum / reference_units));
    signals_.vibration_threshold_n = std::max(signals_.vibration_threshold_n,
                                              config_.vibration_factor * signals_.vibration_reference_rms_n);
  } else {
    reference_energy_.Clear();
    signals_.vibration_reference_rms_n = 0.0;
  }
}

void SlipDetector::UpdateCentroid(const TactileState& state, double grip_n, bool live) {
  const int count = std::clamp(state.unit_count, 0, sensor::kMaxUnits);
  // Weights fall continuously to zero at the contact threshold, so units entering or leaving the
  // contact do not make the centroid jump, and noise on unloaded units carries no weight.
  double weight_sum = 0.0;
  double row_sum = 0.0;
  double column_sum = 0.0;
  // Unweighted moments of the units that carry weight, for the centroid's noise.
  int loaded = 0;
  double position_sum[2] = {0.0, 0.0};
  double position_square_sum = 0.0;
  for (int i = 0; i < count; ++i) {
    if (state.validity[static_cast<size_t>(i)] != UnitValidity::kValid) continue;
    const double weight =
        std::max(state.fn_n[static_cast<size_t>(i)] -
                     kCentroidDeadbandFraction * unit_contact_threshold_n_[static_cast<size_t>(i)],
                 0.0);
    if (weight <= 0.0) continue;
    const double row = i / config_.grid_columns;
    const double column = i % config_.grid_columns;
    weight_sum += weight;
    row_sum += weight * row;
    column_sum += weight * column;
    ++loaded;
    position_sum[0] += row;
    position_sum[1] += column;
    position_square_sum += row * row + column * column;
  }
  if (weight_sum < config_.centroid_min_weight_n && signals_.in_contact && centroid_history_.size() > 0) {
    // A light contact dipping below the minimum for a moment: hold the last centroid.
    centroid_history_.Push(centroid_history_.Delayed(0));
    return;
  }
  if (weight_sum < config_.centroid_min_weight_n) {
    centroid_row_filter_.Clear();
    centroid_column_filter_.Clear();
    centroid_history_.Clear();
    have_reference_ = false;
    signals_.centroid_shift_units = 0.0;
    signals_.centroid_drift_units = 0.0;
    return;
  }
  const Centroid raw{row_sum / weight_sum, column_sum / weight_sum};
  const Centroid now{centroid_row_filter_.Update(raw.row), centroid_column_filter_.Update(raw.column)};
  // Noise of the centroid from the normal-force noise of the loaded units (from the readout's figures
  // when it has them, else taken equal to the learned shear noise, an upper bound for this sensor
  // where k_t < k_n): sigma_c = sigma_fn x
  // sqrt(sum |p - c|^2) / sum w, through the low-pass, and x sqrt(2) for a difference of two samples.
  const double spread =
      std::max(0.0, position_square_sum - 2.0 * (raw.row * position_sum[0] + raw.column * position_sum[1]) +
                        loaded * (raw.row * raw.row + raw.column * raw.column));
  // With the readout's figures the learned (live) shear noise is scaled by their normal/shear ratio,
  // so the centroid follows a noise burst as the learned floor does, with the right proportion.
  const double normal_noise_n =
      signals_.sensor_normal_noise_n > 0.0 && signals_.sensor_shear_noise_n > 0.0
          ? std::max(signals_.sensor_normal_noise_n,
                     signals_.noise_rms_n / std::sqrt(highpass_power_fraction_) *
                         (signals_.sensor_normal_noise_n / signals_.sensor_shear_noise_n))
          : signals_.noise_rms_n;
  const double difference_sigma =
      normal_noise_n * std::sqrt(spread * centroid_variance_reduction_ * 2.0) / weight_sum;
  signals_.centroid_shift_threshold =
      config_.centroid_shift_units + config_.centroid_noise_sigmas * difference_sigma;
  signals_.centroid_drift_threshold =
      config_.centroid_drift_units + config_.centroid_noise_sigmas * difference_sigma;
  centroid_history_.Push(now);
  signals_.centroid_row = now.row;
  signals_.centroid_column = now.column;
  // The drift reference follows the contact until the cues are armed, then stays put.
  // On a flexing finger the contact rolls along the pad as the grip changes: a grip relaxed by more
  // than the band below the reference's grip takes a new reference. A rising grip does not: it is
  // the controller answering a growing load or a slip, when a slide must still be measured whole.
  const bool grip_moved =
      config_.centroid_grip_band > 0.0 &&
      centroid_reference_grip_n_ - grip_n > config_.centroid_grip_band * centroid_reference_grip_n_;
  if (!live || !have_reference_ || grip_moved) {
    centroid_reference_ = now;
    centroid_reference_grip_n_ = grip_n;
    have_reference_ = true;
  }
  signals_.centroid_drift_units =
      std::hypot(now.row - centroid_reference_.row, now.column - centroid_reference_.column);
  if (centroid_history_.size() > centroid_window_samples_) {
    const Centroid& then = centroid_history_.Delayed(centroid_window_samples_);
    signals_.centroid_shift_units = std::hypot(now.row - then.row, now.column - then.column);
  } else {
    signals_.centroid_shift_units = 0.0;
  }
}

}  // namespace graspbed::controller
