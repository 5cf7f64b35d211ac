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

void Require(bool ok, const char* field, double value, const char* reason) {
  if (ok) return;
  std::ostringstream out;
  out << "readout: " << field << " = " << value << ": " << reason;
  throw std::invalid_argument(out.str());
}

// Severity order when two channels disagree: the more specific hardware fault wins.
int Severity(UnitValidity validity) {
  switch (validity) {
    case UnitValidity::kOpen: return 5;
    case UnitValidity::kShort: return 4;
    case UnitValidity::kNotTared: return 3;
    case UnitValidity::kImplausible: return 2;
    case UnitValidity::kOutOfRange: return 1;
    case UnitValidity::kValid: return 0;
  }
  return 0;
}

UnitValidity Worse(UnitValidity a, UnitValidity b) { return Severity(a) >= Severity(b) ? a : b; }

}  // namespace

void ReadoutConfig::Validate() const {
  Require(baseline_frames >= 1, "baseline_frames", baseline_frames, "must be >= 1");
  Require(short_circuit_ohm >= 0.0 && std::isfinite(short_circuit_ohm), "short_circuit_ohm",
          short_circuit_ohm, "must be finite and >= 0");
  Require(open_circuit_ohm > short_circuit_ohm, "open_circuit_ohm", open_circuit_ohm,
          "must be > short_circuit_ohm");
  Require(min_plausible_fraction >= 0.0 && min_plausible_fraction < 1.0, "min_plausible_fraction",
          min_plausible_fraction, "must be in [0, 1)");
  Require(max_plausible_fraction > 1.0 && std::isfinite(max_plausible_fraction), "max_plausible_fraction",
          max_plausible_fraction, "must be > 1");
  Require(max_baseline_deviation_fraction > 0.0 && std::isfinite(max_baseline_deviation_fraction),
          "max_baseline_deviation_fraction", max_baseline_deviation_fraction, "must be > 0");
  Require(min_mean_dr_rel < 0.0 && std::isfinite(min_mean_dr_rel), "min_mean_dr_rel", min_mean_dr_rel,
          "must be < 0");
  Require(max_abs_dr_rel > 0.0 && std::isfinite(max_abs_dr_rel), "max_abs_dr_rel", max_abs_dr_rel,
          "must be > 0");
  Require(adc_full_scale_ohm >= 0.0 && std::isfinite(adc_full_scale_ohm), "adc_full_scale_ohm",
          adc_full_scale_ohm, "must be >= 0 (0 = unknown)");
}

ReadoutConfig LoadReadoutConfig(const common::YamlMap& map) {
  ReadoutConfig config;
  config.baseline_frames = map.GetInt("baseline_frames", config.baseline_frames, 1, 1000000);
  config.short_circuit_ohm = map.GetNumber("short_circuit_ohm", config.short_circuit_ohm, NumberRule::NonNegative());
  config.open_circuit_ohm = map.GetNumber("open_circuit_ohm", config.open_circuit_ohm, NumberRule::Positive());
  config.min_plausible_fraction =
      map.GetNumber("min_plausible_fraction", config.min_plausible_fraction, NumberRule::Between(0.0, 0.999));
  config.max_plausible_fraction = map.GetNumber("max_plausible_fraction", config.max_plausible_fraction,
                                                {1.0, std::numeric_limits<double>::infinity(), true});
  config.max_baseline_deviation_fraction = map.GetNumber(
      "max_baseline_deviation_fraction", config.max_baseline_deviation_fraction, NumberRule::Positive());
  config.min_mean_dr_rel = map.GetNumber("min_mean_dr_rel", config.min_mean_dr_rel, NumberRule::Between(-10, -1e-9));
  config.max_abs_dr_rel = map.GetNumber("max_abs_dr_rel", config.max_abs_dr_rel, NumberRule::Positive());
  config.adc_full_scale_ohm = map.GetNumber("adc_full_scale_ohm", config.adc_full_scale_ohm, NumberRule::NonNegative());
  map.RejectUnknownKeys();
  if (!(config.open_circuit_ohm > config.short_circuit_ohm)) {
    map.Fail("open_circuit_ohm", "must be > short_circuit_ohm");
  }
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
}

void Readout::SetBaseline(std::span<const double> r1_ohm, std::span<const double> r2_ohm) {
  if (r1_ohm.size() != static_cast<size_t>(unit_count_) || r2_ohm.size() != static_cast<size_t>(unit_count_)) {
    throw std::invalid_argument("readout: baseline has " + std::to_string(r1_ohm.size()) + "/" +
                                std::to_string(r2_ohm.size()) + " values for " + std::to_string(unit_count_) +
                                " units");
  }
  for (size_t unit = 0; unit < r1_ohm.size(); ++unit) {
    Require(r1_ohm[unit] > 0.0 && std::isfinite(r1_ohm[unit]), "baseline r1_ohm", r1_ohm[unit], "must be finite and > 0");
    Require(r2_ohm[unit] > 0.0 && std::isfinite(r2_ohm[unit]), "baseline r2_ohm", r2_ohm[unit], "must be finite and > 0");
  }
  Reset();
  const double limit_ohm = config_.max_baseline_deviation_fraction * nominal_r0_ohm_;
  for (size_t unit = 0; unit < r1_ohm.size(); ++unit) {
    baseline_r1_[unit] = r1_ohm[unit];
    baseline_r2_[unit] = r2_ohm[unit];
    baseline_ok_[unit] = std::abs(r1_ohm[unit] - nominal_r0_ohm_) <= limit_ohm &&
                         std::abs(r2_ohm[unit] - nominal_r0_ohm_) <= limit_ohm;
  }
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
  }
  tared_ = true;
}

void Readout::Process(const RawFrame& frame, ReadoutFrame* out) {
  out->sequence = frame.sequence;
  out->time_s = frame.time_s;
  out->unit_count = unit_count_;
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
      const UnitValidity worst = Worse(v1, v2);
      out->validity[unit] = worst == UnitValidity::kOpen || worst == UnitValidity::kShort
                                ? worst
                                : UnitValidity::kNotTared;
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
