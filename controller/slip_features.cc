#include "controller/slip_features.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace graspbed::controller {
namespace {

constexpr double kMinRatioGripN = 0.2;      // shear_ratio's denominator floor [N]
constexpr double kContactUnitN = 0.15;      // a unit in contact [N]
constexpr double kContactTotalN = 0.3;      // the contact as a whole [N]
constexpr double kCentroidMinWeightN = 0.2;  // least contact force with a centroid [N]
constexpr double kHighpassHz = 40.0;
constexpr double kMaxContactTimeS = 2.0;
constexpr double kNoiseFloorN = 1e-3;

enum Feature : size_t {
  kTotalFn,
  kShear,
  kShearRatio,
  kRatioLp,
  kRatioRise,
  kRatioAboveSlow,
  kFnRate,
  kShearRate,
  kVibrationFt,
  kVibrationFn,
  kNoiseFt,
  kVibrationOverNoise,
  kCentroidSpeed,
  kCentroidDrift,
  kContactUnits,
  kValidFraction,
  kContactTime,
  kFnOverPeak,
  kStale,
  kFeatureEnd
};
static_assert(kFeatureEnd == kSlipFeatureCount, "kSlipFeatures and the Feature enum must match");

bool Valid(const sensor::TactileState& state, int unit) {
  return state.validity[static_cast<size_t>(unit)] == sensor::UnitValidity::kValid;
}

}  // namespace

SlipFeatureLayout SlipFeatureLayoutFor(int units) {
  if (units == 20) return {20, 4};
  if (units == 9) return {9, 3};
  return {units, std::max(units, 1)};
}

SlipFeatureExtractor::SlipFeatureExtractor(const SlipFeatureLayout& layout, double tick_period_s)
    : layout_(layout), tick_period_s_(tick_period_s) {
  if (!(tick_period_s > 0.0) || tick_period_s > 1.0) {
    throw std::invalid_argument("slip features: tick period " + std::to_string(tick_period_s) +
                                " s: must be in (0, 1]");
  }
  if (layout.units < 1 || layout.units > static_cast<int>(sensor::kMaxUnits) || layout.columns < 1) {
    throw std::invalid_argument("slip features: " + std::to_string(layout.units) + " units in " +
                                std::to_string(layout.columns) + " columns: must be 1.." +
                                std::to_string(sensor::kMaxUnits) + " units, >= 1 column");
  }
  const double rate_hz = 1.0 / tick_period_s;
  delay_ticks_ = std::clamp(static_cast<int>(std::lround(0.010 * rate_hz)), 1, kMaxDelayTicks - 1);
  centroid_delay_ticks_ = std::clamp(static_cast<int>(std::lround(0.020 * rate_hz)), 1, kMaxDelayTicks - 1);
  ratio_fast_ = LowPassFilter(0.010, tick_period_s);
  ratio_slow_ = LowPassFilter(0.5, tick_period_s);
  fn_lp_ = LowPassFilter(0.005, tick_period_s);
  shear_lp_ = LowPassFilter(0.005, tick_period_s);
  vibration_ft_ = LowPassFilter(0.010, tick_period_s);
  vibration_fn_ = LowPassFilter(0.010, tick_period_s);
  noise_ft_ = LowPassFilter(0.050, tick_period_s);
  centroid_row_ = LowPassFilter(0.003, tick_period_s);
  centroid_column_ = LowPassFilter(0.003, tick_period_s);
  centroid_row_slow_ = LowPassFilter(0.2, tick_period_s);
  centroid_column_slow_ = LowPassFilter(0.2, tick_period_s);
  // Above 0.45 of the sampling rate the high-pass is not defined; a slow loop keeps what it can.
  const double cutoff_hz = std::min(kHighpassHz, 0.45 * rate_hz);
  for (size_t u = 0; u < sensor::kMaxUnits; ++u) {
    ft_highpass_[u] = HighPassBiquad(cutoff_hz, rate_hz);
    fn_highpass_[u] = HighPassBiquad(cutoff_hz, rate_hz);
  }
  Reset();
}

void SlipFeatureExtractor::Reset() {
  for (LowPassFilter* filter : {&ratio_fast_, &ratio_slow_, &fn_lp_, &shear_lp_, &vibration_ft_, &vibration_fn_,
                                &noise_ft_, &centroid_row_, &centroid_column_, &centroid_row_slow_,
                                &centroid_column_slow_}) {
    filter->Clear();
  }
  primed_.fill(false);
  ratio_history_.Clear();
  fn_history_.Clear();
  shear_history_.Clear();
  centroid_history_.Clear();
  contact_start_s_ = -1.0;
  peak_fn_n_ = 0.0;
}

void SlipFeatureExtractor::UpdateVibration(const sensor::TactileState& state, double total_fn_n,
                                           double* features) {
  double contact_ft = 0.0, contact_fn = 0.0, off_ft = 0.0;
  int off_units = 0;
  const int units = std::min(state.unit_count, layout_.units);
  for (int u = 0; u < units; ++u) {
    const size_t i = static_cast<size_t>(u);
    if (!Valid(state, u)) {
      primed_[i] = false;
      continue;
    }
    if (!primed_[i]) {
      // A unit that becomes valid starts its filters in steady state, not with a step.
      ft_highpass_[i].Reset(state.ft_n[i]);
      fn_highpass_[i].Reset(state.fn_n[i]);
      primed_[i] = true;
    }
    const double ft_high = ft_highpass_[i].Update(state.ft_n[i]);
    const double fn_high = fn_highpass_[i].Update(state.fn_n[i]);
    if (state.fn_n[i] > kContactUnitN && total_fn_n > 0.0) {
      const double weight = state.fn_n[i] / total_fn_n;
      contact_ft += weight * ft_high * ft_high;
      contact_fn += weight * fn_high * fn_high;
    } else if (state.fn_n[i] < 0.5 * kContactUnitN) {
      off_ft += ft_high * ft_high;
      ++off_units;
    }
  }
  features[kVibrationFt] = std::sqrt(vibration_ft_.Update(contact_ft));
  features[kVibrationFn] = std::sqrt(vibration_fn_.Update(contact_fn));
  features[kNoiseFt] = std::sqrt(noise_ft_.Update(off_units > 0 ? off_ft / off_units : noise_ft_.value()));
  features[kVibrationOverNoise] = features[kVibrationFt] / std::max(features[kNoiseFt], kNoiseFloorN);
}

void SlipFeatureExtractor::UpdateCentroid(const sensor::TactileState& state, double total_fn_n,
                                          double* features) {
  double weight = 0.0, row = 0.0, column = 0.0;
  int contact_units = 0;
  const int units = std::min(state.unit_count, layout_.units);
  for (int u = 0; u < units; ++u) {
    const size_t i = static_cast<size_t>(u);
    if (!Valid(state, u) || state.fn_n[i] <= kContactUnitN) continue;
    ++contact_units;
    weight += state.fn_n[i];
    row += state.fn_n[i] * (u / layout_.columns);
    column += state.fn_n[i] * (u % layout_.columns);
  }
  features[kContactUnits] = contact_units;
  features[kCentroidSpeed] = 0.0;
  features[kCentroidDrift] = 0.0;
  if (weight < kCentroidMinWeightN || total_fn_n < kCentroidMinWeightN) {
    // No contact to follow: the next one starts its centroid afresh.
    for (LowPassFilter* filter : {&centroid_row_, &centroid_column_, &centroid_row_slow_, &centroid_column_slow_})
      filter->Clear();
    centroid_history_.Clear();
    return;
  }
  const Centroid now{centroid_row_.Update(row / weight), centroid_column_.Update(column / weight)};
  const double slow_row = centroid_row_slow_.Update(now.row);
  const double slow_column = centroid_column_slow_.Update(now.column);
  centroid_history_.Push(now);
  if (centroid_history_.size() > centroid_delay_ticks_) {
    const Centroid& then = centroid_history_.Delayed(centroid_delay_ticks_);
    features[kCentroidSpeed] = std::hypot(now.row - then.row, now.column - then.column) /
                               (centroid_delay_ticks_ * tick_period_s_);
  }
  features[kCentroidDrift] = std::hypot(now.row - slow_row, now.column - slow_column);
}

void SlipFeatureExtractor::Update(const sensor::TactileState& state, double time_s, std::span<double> features) {
  double* f = features.data();
  const double total_fn = state.total_fn_n;
  const double shear = std::hypot(state.total_shear_axial_n, state.total_shear_circumferential_n);
  f[kTotalFn] = total_fn;
  f[kShear] = shear;
  f[kShearRatio] = shear / std::max(total_fn, kMinRatioGripN);
  f[kRatioLp] = ratio_fast_.Update(f[kShearRatio]);
  f[kRatioAboveSlow] = f[kRatioLp] - ratio_slow_.Update(f[kShearRatio]);
  const double fn_lp = fn_lp_.Update(total_fn);
  const double shear_lp = shear_lp_.Update(shear);
  ratio_history_.Push(f[kRatioLp]);
  fn_history_.Push(fn_lp);
  shear_history_.Push(shear_lp);
  const bool have_history = ratio_history_.size() > delay_ticks_;
  const double span_s = delay_ticks_ * tick_period_s_;
  f[kRatioRise] = have_history ? f[kRatioLp] - ratio_history_.Delayed(delay_ticks_) : 0.0;
  f[kFnRate] = have_history ? (fn_lp - fn_history_.Delayed(delay_ticks_)) / span_s : 0.0;
  f[kShearRate] = have_history ? (shear_lp - shear_history_.Delayed(delay_ticks_)) / span_s : 0.0;
  UpdateVibration(state, total_fn, f);
  UpdateCentroid(state, total_fn, f);
  f[kValidFraction] = state.unit_count > 0 ? static_cast<double>(state.valid_count) / state.unit_count : 0.0;
  if (total_fn > kContactTotalN) {
    if (contact_start_s_ < 0.0) contact_start_s_ = time_s;
    peak_fn_n_ = std::max(peak_fn_n_, total_fn);
  } else {
    contact_start_s_ = -1.0;
    peak_fn_n_ = 0.0;
  }
  f[kContactTime] = contact_start_s_ < 0.0 ? 0.0 : std::min(time_s - contact_start_s_, kMaxContactTimeS);
  f[kFnOverPeak] = peak_fn_n_ > 0.0 ? total_fn / peak_fn_n_ : 0.0;
  f[kStale] = state.stale ? 1.0 : 0.0;
}

}  // namespace graspbed::controller
