#include "sensor/readout.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace graspbed::sensor {
namespace {

using common::NumberRule;

using common::Require;

// Severity order when two channels disagree: the more specific hardware fault wins.
int Severity(UnitValidity validity) {
  switch (validity) {
    case UnitValidity::kOpen:
      return 5;
    case UnitValidity::kShort:
      return 4;
    case UnitValidity::kNotTared:
      return 3;
    case UnitValidity::kImplausible:
      return 2;
    case UnitValidity::kOutOfRange:
      return 1;
    case UnitValidity::kValid:
      return 0;
  }
  return 0;
}

UnitValidity Worse(UnitValidity a, UnitValidity b) { return Severity(a) >= Severity(b) ? a : b; }

}  // namespace

const common::FieldTable<ReadoutConfig>& ReadoutConfigFields() {
  using Table = common::FieldTable<ReadoutConfig>;
  using C = ReadoutConfig;
  static const Table table(
      "readout",
      {
          Table::Integer("baseline_frames", &C::baseline_frames, 1, 1000000, "frames",
                         "frames averaged for the tare after construction or `Reset()`; validity "
                         "`not_tared` meanwhile; contact before they have arrived biases the estimate"),
          Table::Number("short_circuit_ohm", &C::short_circuit_ohm, NumberRule::Between(0.0, 1e6), "Ohm",
                        "at or below: `short`"),
          Table::Number("open_circuit_ohm", &C::open_circuit_ohm, {0.0, 1e9, true}, "Ohm",
                        "at or above (or inf): `open`")
              .Note("> `short_circuit_ohm`"),
          Table::Number("min_plausible_fraction", &C::min_plausible_fraction, NumberRule::Between(0.0, 0.999),
                        "-", "channel below this x R0 (not a short): `implausible`"),
          Table::Number("max_plausible_fraction", &C::max_plausible_fraction, {1.0, 1000.0, true}, "-",
                        "channel above this x R0 (not open): `implausible`"),
          Table::Number("max_baseline_deviation_fraction", &C::max_baseline_deviation_fraction,
                        {0.0, 100.0, true}, "-",
                        "tare further than this from R0 (or a channel without good readings in half the tare "
                        "window): `implausible` until re-tared"),
          Table::Number("min_mean_dr_rel", &C::min_mean_dr_rel, NumberRule::Between(-10.0, -1e-9), "-",
                        "mean dR/R of a unit below this (mesa pulled; -0.1 is about -1.8 N at paper "
                        "sensitivities): `implausible`"),
          Table::Number("max_abs_dr_rel", &C::max_abs_dr_rel, {0.0, 1000.0, true}, "-",
                        "abs(dR/R) above this: `out_of_range` (the paper's maximum is 0.96)"),
          Table::Number("adc_full_scale_ohm", &C::adc_full_scale_ohm, NumberRule::Between(0.0, 1e8), "Ohm",
                        "the source's ADC full scale; a channel at it is `out_of_range`; 0 = unknown"),
          Table::Number("adc_min_ohm", &C::adc_min_ohm, NumberRule::Between(0.0, 1e8), "Ohm",
                        "bottom of the source's ADC window; a channel at or below it is `out_of_range`; "
                        "0 = none")
              .Note("< `adc_full_scale_ohm` when that is > 0"),
      },
      [](const C& c) {
        if (!(c.open_circuit_ohm > c.short_circuit_ohm)) {
          common::FieldError("open_circuit_ohm", c.open_circuit_ohm, "must be > short_circuit_ohm");
        }
        if (c.adc_full_scale_ohm > 0.0 && !(c.adc_min_ohm < c.adc_full_scale_ohm)) {
          common::FieldError("adc_min_ohm", c.adc_min_ohm, "needs adc_min_ohm < adc_full_scale_ohm");
        }
      });
  return table;
}

void ReadoutConfig::Validate() const { ReadoutConfigFields().Validate(*this); }

ReadoutConfig LoadReadoutConfig(const common::YamlMap& map, const ReadoutConfig& defaults) {
  ReadoutConfig config = defaults;
  ReadoutConfigFields().Load(map, &config);
  return config;
}

Readout::Readout(const ReadoutConfig& config, int unit_count, double nominal_r0_ohm)
    : config_(config), unit_count_(unit_count), nominal_r0_ohm_(nominal_r0_ohm) {
  config_.Validate();
  if (unit_count < 1 || unit_count > kMaxUnits) {
    throw std::invalid_argument("readout: unit count " + std::to_string(unit_count) + " outside 1.." +
                                std::to_string(kMaxUnits));
  }
  Require(nominal_r0_ohm > 0.0 && std::isfinite(nominal_r0_ohm), "nominal_r0_ohm", nominal_r0_ohm,
          "must be finite and > 0");
  Reset();
}

void Readout::Reset() {
  tared_ = false;
  frames_seen_ = 0;
  sum_r1_.fill(0.0);
  sum_r2_.fill(0.0);
  count_r1_.fill(0);
  count_r2_.fill(0);
  baseline_r1_.fill(nominal_r0_ohm_);
  baseline_r2_.fill(nominal_r0_ohm_);
  baseline_ok_.fill(false);
  noise_sums_.fill(NoiseSums{});
}

void Readout::SetBaseline(std::span<const double> r1_ohm, std::span<const double> r2_ohm) {
  if (r1_ohm.size() != static_cast<size_t>(unit_count_) ||
      r2_ohm.size() != static_cast<size_t>(unit_count_)) {
    throw std::invalid_argument("readout: baseline has " + std::to_string(r1_ohm.size()) + "/" +
                                std::to_string(r2_ohm.size()) + " values for " + std::to_string(unit_count_) +
                                " units");
  }
  for (size_t unit = 0; unit < r1_ohm.size(); ++unit) {
    Require(r1_ohm[unit] > 0.0 && std::isfinite(r1_ohm[unit]), "baseline r1_ohm", r1_ohm[unit],
            "must be finite and > 0");
    Require(r2_ohm[unit] > 0.0 && std::isfinite(r2_ohm[unit]), "baseline r2_ohm", r2_ohm[unit],
            "must be finite and > 0");
  }
  Reset();
  const double limit_ohm = config_.max_baseline_deviation_fraction * nominal_r0_ohm_;
  for (size_t unit = 0; unit < r1_ohm.size(); ++unit) {
    baseline_r1_[unit] = r1_ohm[unit];
    baseline_r2_[unit] = r2_ohm[unit];
    baseline_ok_[unit] = std::abs(r1_ohm[unit] - nominal_r0_ohm_) <= limit_ohm &&
                         std::abs(r2_ohm[unit] - nominal_r0_ohm_) <= limit_ohm;
  }
  // A stored baseline says nothing about this session's noise.
  noise_known_ = false;
  r1_noise_ohm_.fill(0.0);
  r2_noise_ohm_.fill(0.0);
  sum_noise_rel_.fill(0.0);
  diff_noise_rel_.fill(0.0);
  if (++noise_generation_ == 0) noise_generation_ = 1;
  tared_ = true;
}

UnitValidity Readout::ChannelValidity(double resistance_ohm) const {
  if (std::isnan(resistance_ohm)) return UnitValidity::kImplausible;
  if (resistance_ohm >= config_.open_circuit_ohm) return UnitValidity::kOpen;
  if (resistance_ohm <= config_.short_circuit_ohm) return UnitValidity::kShort;
  if (resistance_ohm < config_.min_plausible_fraction * nominal_r0_ohm_ ||
      resistance_ohm > config_.max_plausible_fraction * nominal_r0_ohm_) {
    return UnitValidity::kImplausible;
  }
  if (config_.adc_full_scale_ohm > 0.0 && resistance_ohm >= config_.adc_full_scale_ohm) {
    return UnitValidity::kOutOfRange;
  }
  if (config_.adc_min_ohm > 0.0 && resistance_ohm <= config_.adc_min_ohm) return UnitValidity::kOutOfRange;
  return UnitValidity::kValid;
}

void Readout::FinishBaseline() {
  // A channel needs at least half the window of good readings, else its baseline is unknown.
  const int needed = std::max(1, config_.baseline_frames / 2);
  const double limit_ohm = config_.max_baseline_deviation_fraction * nominal_r0_ohm_;
  for (int unit = 0; unit < unit_count_; ++unit) {
    const bool enough = count_r1_[unit] >= needed && count_r2_[unit] >= needed;
    baseline_r1_[unit] = enough ? sum_r1_[unit] / count_r1_[unit] : nominal_r0_ohm_;
    baseline_r2_[unit] = enough ? sum_r2_[unit] / count_r2_[unit] : nominal_r0_ohm_;
    baseline_ok_[unit] = enough && std::abs(baseline_r1_[unit] - nominal_r0_ohm_) <= limit_ohm &&
                         std::abs(baseline_r2_[unit] - nominal_r0_ohm_) <= limit_ohm;
    FinishNoise(unit);
  }
  noise_known_ = true;
  if (++noise_generation_ == 0) noise_generation_ = 1;
  tared_ = true;
}

void Readout::FinishNoise(int unit) {
  const NoiseSums& n = noise_sums_[unit];
  r1_noise_ohm_[unit] = r2_noise_ohm_[unit] = sum_noise_rel_[unit] = diff_noise_rel_[unit] = 0.0;
  // A line through the window takes two degrees of freedom; fewer than three points say nothing.
  if (n.count < 3) return;
  const double count = n.count;
  const double skk = n.kk - n.k * n.k / count;
  const double sxx = n.xx - n.x * n.x / count, syy = n.yy - n.y * n.y / count;
  const double sxk = n.xk - n.x * n.k / count, syk = n.yk - n.y * n.k / count;
  const double sxy = n.xy - n.x * n.y / count;
  // Residuals about the least-squares line in k (variance and covariance).
  const double dof = count - 2.0;
  const double var_x = std::max(0.0, (sxx - (skk > 0.0 ? sxk * sxk / skk : 0.0)) / dof);
  const double var_y = std::max(0.0, (syy - (skk > 0.0 ? syk * syk / skk : 0.0)) / dof);
  const double cov_xy = (sxy - (skk > 0.0 ? sxk * syk / skk : 0.0)) / dof;
  r1_noise_ohm_[unit] = std::sqrt(var_x);
  r2_noise_ohm_[unit] = std::sqrt(var_y);
  // s = (R1/b1 + R2/b2) / 2 - 1 and d = (R1/b1 - R2/b2) / 2 with the baselines b1, b2.
  const double b1 = baseline_r1_[unit], b2 = baseline_r2_[unit];
  const double a = var_x / (b1 * b1), b = var_y / (b2 * b2), c = 2.0 * cov_xy / (b1 * b2);
  sum_noise_rel_[unit] = 0.5 * std::sqrt(std::max(0.0, a + b + c));
  diff_noise_rel_[unit] = 0.5 * std::sqrt(std::max(0.0, a + b - c));
}

void Readout::Process(const RawFrame& frame, ReadoutFrame* out) {
  out->sequence = frame.sequence;
  out->time_s = frame.time_s;
  out->unit_count = unit_count_;
  out->noise_known = noise_known_;
  if (out->noise_generation != noise_generation_) {
    const auto units = static_cast<size_t>(unit_count_);
    std::copy_n(r1_noise_ohm_.begin(), units, out->r1_noise_ohm.begin());
    std::copy_n(r2_noise_ohm_.begin(), units, out->r2_noise_ohm.begin());
    std::copy_n(sum_noise_rel_.begin(), units, out->sum_noise_rel.begin());
    std::copy_n(diff_noise_rel_.begin(), units, out->diff_noise_rel.begin());
    out->noise_generation = noise_generation_;
  }
  if (frame.unit_count != unit_count_) {
    for (int unit = 0; unit < unit_count_; ++unit) {
      out->dr1_rel[unit] = 0.0;
      out->dr2_rel[unit] = 0.0;
      out->validity[unit] = UnitValidity::kImplausible;
    }
    return;
  }
  if (!tared_) {
    for (int unit = 0; unit < unit_count_; ++unit) {
      const double r1 = frame.r1_ohm[unit];
      const double r2 = frame.r2_ohm[unit];
      const UnitValidity v1 = ChannelValidity(r1);
      const UnitValidity v2 = ChannelValidity(r2);
      if (v1 == UnitValidity::kValid) {
        sum_r1_[unit] += r1;
        ++count_r1_[unit];
      }
      if (v2 == UnitValidity::kValid) {
        sum_r2_[unit] += r2;
        ++count_r2_[unit];
      }
      if (v1 == UnitValidity::kValid && v2 == UnitValidity::kValid) {
        NoiseSums& n = noise_sums_[unit];
        if (n.count == 0) {
          n.first_r1 = r1;
          n.first_r2 = r2;
        }
        const double k = frames_seen_, x = r1 - n.first_r1, y = r2 - n.first_r2;
        ++n.count;
        n.k += k;
        n.kk += k * k;
        n.x += x;
        n.xx += x * x;
        n.xk += x * k;
        n.y += y;
        n.yy += y * y;
        n.yk += y * k;
        n.xy += x * y;
      }
      const UnitValidity worst = Worse(v1, v2);
      out->validity[unit] =
          worst == UnitValidity::kOpen || worst == UnitValidity::kShort ? worst : UnitValidity::kNotTared;
      out->dr1_rel[unit] = 0.0;
      out->dr2_rel[unit] = 0.0;
    }
    if (++frames_seen_ >= config_.baseline_frames) FinishBaseline();
    return;
  }
  for (int unit = 0; unit < unit_count_; ++unit) {
    const double r1 = frame.r1_ohm[unit];
    const double r2 = frame.r2_ohm[unit];
    UnitValidity validity = Worse(ChannelValidity(r1), ChannelValidity(r2));
    if (validity == UnitValidity::kOpen || validity == UnitValidity::kShort || std::isnan(r1) ||
        std::isnan(r2)) {
      out->dr1_rel[unit] = 0.0;
      out->dr2_rel[unit] = 0.0;
      out->validity[unit] = validity;
      continue;
    }
    const double dr1 = (r1 - baseline_r1_[unit]) / baseline_r1_[unit];
    const double dr2 = (r2 - baseline_r2_[unit]) / baseline_r2_[unit];
    out->dr1_rel[unit] = dr1;
    out->dr2_rel[unit] = dr2;
    if (!baseline_ok_[unit] || 0.5 * (dr1 + dr2) < config_.min_mean_dr_rel) {
      validity = Worse(validity, UnitValidity::kImplausible);
    }
    if (std::abs(dr1) > config_.max_abs_dr_rel || std::abs(dr2) > config_.max_abs_dr_rel) {
      validity = Worse(validity, UnitValidity::kOutOfRange);
    }
    out->validity[unit] = validity;
  }
}

}  // namespace graspbed::sensor
