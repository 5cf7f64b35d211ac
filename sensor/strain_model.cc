#include "sensor/strain_model.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace graspbed::sensor {
namespace {

using common::NumberRule;

// Spreads are drawn from a normal distribution clipped to +-3 sigma so no R0 or k goes negative.
constexpr double kSpreadClipSigma = 3.0;

std::string Describe(const char* field, double value, const char* reason) {
  std::ostringstream out;
  out << "strain model: " << field << " = " << value << ": " << reason;
  return out.str();
}

void Require(bool ok, const char* field, double value, const char* reason) {
  if (!ok) throw std::invalid_argument(Describe(field, value, reason));
}

double Clip(double value, double limit) { return limit > 0.0 ? std::clamp(value, -limit, limit) : value; }

}  // namespace

GaugeResistances IdealGaugeResistances(const UnitConstants& constants, double fn_n, double ft_n) {
  const double eps_n = constants.kn_per_n * fn_n;
  const double eps_t = constants.kt_per_n * ft_n;
  return {constants.r0_ohm * (1.0 + constants.gauge_factor * (eps_n + eps_t)),
          constants.r0_ohm * (1.0 + constants.gauge_factor * (eps_n - eps_t))};
}

void StrainModelConfig::Validate() const {
  Require(nominal.r0_ohm > 0.0 && std::isfinite(nominal.r0_ohm), "r0_ohm", nominal.r0_ohm, "must be > 0");
  Require(nominal.gauge_factor > 0.0 && std::isfinite(nominal.gauge_factor), "gauge_factor",
          nominal.gauge_factor, "must be > 0");
  Require(nominal.kn_per_n > 0.0 && std::isfinite(nominal.kn_per_n), "kn_per_n", nominal.kn_per_n,
          "must be > 0");
  Require(nominal.kt_per_n > 0.0 && std::isfinite(nominal.kt_per_n), "kt_per_n", nominal.kt_per_n,
          "must be > 0");
  Require(nominal.rated_force_n > 0.0 && std::isfinite(nominal.rated_force_n), "rated_force_n",
          nominal.rated_force_n, "must be > 0");
  Require(r0_spread_fraction >= 0.0 && r0_spread_fraction <= 0.3, "r0_spread_fraction", r0_spread_fraction,
          "must be in [0, 0.3]");
  Require(sensitivity_spread_fraction >= 0.0 && sensitivity_spread_fraction <= 0.3,
          "sensitivity_spread_fraction", sensitivity_spread_fraction, "must be in [0, 0.3]");
  Require(noise_ohm >= 0.0 && std::isfinite(noise_ohm), "noise_ohm", noise_ohm, "must be >= 0");
  Require(adc_bits >= 0 && adc_bits <= 32, "adc_bits", adc_bits, "must be in [0, 32]");
  Require(adc_full_scale_ohm > 0.0 && std::isfinite(adc_full_scale_ohm), "adc_full_scale_ohm",
          adc_full_scale_ohm, "must be > 0");
  Require(adc_min_ohm >= 0.0 && adc_min_ohm < adc_full_scale_ohm, "adc_min_ohm", adc_min_ohm,
          "must be >= 0 and < adc_full_scale_ohm");
  Require(std::isfinite(temperature_coefficient_per_k) && std::abs(temperature_coefficient_per_k) < 0.1,
          "temperature_coefficient_per_k", temperature_coefficient_per_k, "must be in (-0.1, 0.1)");
  Require(std::isfinite(temperature_offset_k), "temperature_offset_k", temperature_offset_k,
          "must be finite");
  Require(std::isfinite(temperature_ramp_k_per_s), "temperature_ramp_k_per_s", temperature_ramp_k_per_s,
          "must be finite");
  Require(saturation_force_n >= 0.0 && std::isfinite(saturation_force_n), "saturation_force_n",
          saturation_force_n, "must be >= 0 (0 = off)");
  Require(std::isfinite(cross_talk_shear_fraction) && std::abs(cross_talk_shear_fraction) <= 1.0,
          "cross_talk_shear_fraction", cross_talk_shear_fraction, "must be in [-1, 1]");
  Require(std::isfinite(cross_talk_offset_per_mm) && std::abs(cross_talk_offset_per_mm) <= 10.0,
          "cross_talk_offset_per_mm", cross_talk_offset_per_mm, "must be in [-10, 10]");
  for (int unit : dead_units) Require(unit >= 0 && unit < kMaxUnits, "dead_units[]", unit, "no such unit");
  for (int unit : shorted_units) {
    Require(unit >= 0 && unit < kMaxUnits, "shorted_units[]", unit, "no such unit");
    Require(std::find(dead_units.begin(), dead_units.end(), unit) == dead_units.end(), "shorted_units[]",
            unit, "is also in dead_units");
  }
}

StrainModelConfig LoadStrainModelConfig(const common::YamlMap& map, int unit_count,
                                        const StrainModelConfig& defaults) {
  StrainModelConfig config = defaults;
  const StrainModelConfig& d = defaults;
  UnitConstants& nominal = config.nominal;
  nominal.r0_ohm = map.GetNumber("r0_ohm", d.nominal.r0_ohm, {0.0, 1e7, true});
  nominal.gauge_factor = map.GetNumber("gauge_factor", d.nominal.gauge_factor, {0.0, 1000.0, true});
  nominal.kn_per_n = map.GetNumber("kn_per_n", d.nominal.kn_per_n, {0.0, 1.0, true});
  nominal.kt_per_n = map.GetNumber("kt_per_n", d.nominal.kt_per_n, {0.0, 1.0, true});
  nominal.rated_force_n = map.GetNumber("rated_force_n", d.nominal.rated_force_n, {0.0, 1000.0, true});
  config.r0_spread_fraction =
      map.GetNumber("r0_spread_fraction", d.r0_spread_fraction, NumberRule::Between(0.0, 0.3));
  config.sensitivity_spread_fraction = map.GetNumber(
      "sensitivity_spread_fraction", d.sensitivity_spread_fraction, NumberRule::Between(0.0, 0.3));
  config.noise_ohm = map.GetNumber("noise_ohm", d.noise_ohm, NumberRule::Between(0.0, 1e6));
  config.adc_bits = map.GetInt("adc_bits", d.adc_bits, 0, 32);
  config.adc_full_scale_ohm = map.GetNumber("adc_full_scale_ohm", d.adc_full_scale_ohm, {0.0, 1e8, true});
  config.adc_min_ohm = map.GetNumber("adc_min_ohm", d.adc_min_ohm, NumberRule::Between(0.0, 1e8));
  if (!(config.adc_min_ohm < config.adc_full_scale_ohm)) {
    map.Fail(map.Has("adc_min_ohm") ? "adc_min_ohm" : "adc_full_scale_ohm",
             "the ADC window needs adc_min_ohm < adc_full_scale_ohm (" + std::to_string(config.adc_min_ohm) +
                 " vs " + std::to_string(config.adc_full_scale_ohm) + ")");
  }
  config.temperature_coefficient_per_k = map.GetNumber(
      "temperature_coefficient_per_k", d.temperature_coefficient_per_k, NumberRule::Between(-0.0999, 0.0999));
  config.temperature_offset_k =
      map.GetNumber("temperature_offset_k", d.temperature_offset_k, NumberRule::Between(-200.0, 200.0));
  config.temperature_ramp_k_per_s = map.GetNumber("temperature_ramp_k_per_s", d.temperature_ramp_k_per_s,
                                                  NumberRule::Between(-100.0, 100.0));
  config.saturation_force_n =
      map.GetNumber("saturation_force_n", d.saturation_force_n, NumberRule::Between(0.0, 1000.0));
  config.cross_talk_shear_fraction =
      map.GetNumber("cross_talk_shear_fraction", d.cross_talk_shear_fraction, NumberRule::Between(-1, 1));
  config.cross_talk_offset_per_mm =
      map.GetNumber("cross_talk_offset_per_mm", d.cross_talk_offset_per_mm, NumberRule::Between(-10, 10));
  const auto read_units = [&](const char* key) {
    std::vector<int> units;
    for (double value : map.GetNumberList(key, {}, 0, NumberRule::Between(0, unit_count - 1))) {
      if (value != std::floor(value)) map.Fail(key, "unit indices must be whole numbers");
      const int unit = static_cast<int>(value);
      if (std::find(units.begin(), units.end(), unit) != units.end()) {
        map.Fail(key, "unit " + std::to_string(unit) + " listed twice");
      }
      units.push_back(unit);
    }
    return units;
  };
  if (map.Has("dead_units")) config.dead_units = read_units("dead_units");
  if (map.Has("shorted_units")) config.shorted_units = read_units("shorted_units");
  for (int unit : config.shorted_units) {
    if (std::find(config.dead_units.begin(), config.dead_units.end(), unit) != config.dead_units.end()) {
      map.Fail("shorted_units", "unit " + std::to_string(unit) + " is also in dead_units");
    }
  }
  map.RejectUnknownKeys();
  return config;
}

StrainModel::StrainModel(const Layout& layout, const StrainModelConfig& config, uint64_t seed)
    : config_(config), unit_count_(layout.unit_count()), rng_(seed) {
  config_.Validate();
  if (unit_count_ < 1 || unit_count_ > kMaxUnits) {
    throw std::invalid_argument("strain model: layout has " + std::to_string(unit_count_) +
                                " units; expected 1.." + std::to_string(kMaxUnits));
  }
  // Codes 0 .. 2^bits - 1 span min .. full scale; the top code also means "at or above full scale".
  adc_max_code_ = std::ldexp(1.0, config_.adc_bits) - 1.0;
  adc_lsb_ohm_ =
      config_.adc_bits > 0 ? (config_.adc_full_scale_ohm - config_.adc_min_ohm) / adc_max_code_ : 0.0;
  const size_t count = static_cast<size_t>(unit_count_);
  r0_r1_.resize(count);
  r0_r2_.resize(count);
  kn_.resize(count);
  kt_.resize(count);
  bias_r1_.assign(count, 0.0);
  bias_r2_.assign(count, 0.0);
  faults_.assign(count, UnitFault::kNone);
  const auto spread = [&](double fraction) {
    if (fraction == 0.0) return 1.0;
    return 1.0 + fraction * std::clamp(normal_(rng_), -kSpreadClipSigma, kSpreadClipSigma);
  };
  for (size_t unit = 0; unit < count; ++unit) {
    r0_r1_[unit] = config_.nominal.r0_ohm * spread(config_.r0_spread_fraction);
    r0_r2_[unit] = config_.nominal.r0_ohm * spread(config_.r0_spread_fraction);
    kn_[unit] = config_.nominal.kn_per_n * spread(config_.sensitivity_spread_fraction);
    kt_[unit] = config_.nominal.kt_per_n * spread(config_.sensitivity_spread_fraction);
  }
  for (int unit : config_.dead_units) SetUnitFault(unit, UnitFault::kOpen);
  for (int unit : config_.shorted_units) SetUnitFault(unit, UnitFault::kShort);
}

void StrainModel::SetUnitFault(int unit, UnitFault fault) {
  if (unit < 0 || unit >= unit_count_) {
    throw std::invalid_argument("strain model: unit " + std::to_string(unit) + " outside 0.." +
                                std::to_string(unit_count_ - 1));
  }
  faults_[static_cast<size_t>(unit)] = fault;
}

void StrainModel::SetBiasOhm(int unit, double r1_bias_ohm, double r2_bias_ohm) {
  if (unit < 0 || unit >= unit_count_) {
    throw std::invalid_argument("strain model: unit " + std::to_string(unit) + " outside 0.." +
                                std::to_string(unit_count_ - 1));
  }
  if (!std::isfinite(r1_bias_ohm) || !std::isfinite(r2_bias_ohm)) {
    throw std::invalid_argument("strain model: bias must be finite");
  }
  bias_r1_[static_cast<size_t>(unit)] = r1_bias_ohm;
  bias_r2_[static_cast<size_t>(unit)] = r2_bias_ohm;
}

void StrainModel::SetNoiseScale(double scale) {
  if (!(scale >= 0.0) || !std::isfinite(scale)) {
    throw std::invalid_argument("strain model: noise scale must be finite and >= 0");
  }
  noise_scale_ = scale;
}

void StrainModel::SetTemperatureOffsetK(double kelvin) {
  if (!std::isfinite(kelvin)) throw std::invalid_argument("strain model: temperature offset must be finite");
  extra_temperature_k_ = kelvin;
}

double StrainModel::TemperatureOffsetK(double time_s) const {
  return config_.temperature_offset_k + config_.temperature_ramp_k_per_s * time_s + extra_temperature_k_;
}

double StrainModel::Quantise(double resistance_ohm) const {
  if (config_.adc_bits == 0) return resistance_ohm;
  const double code =
      std::clamp(std::nearbyint((resistance_ohm - config_.adc_min_ohm) / adc_lsb_ohm_), 0.0, adc_max_code_);
  return config_.adc_min_ohm + code * adc_lsb_ohm_;
}

void StrainModel::Sample(std::span<const UnitLoad> loads, double time_s, RawFrame* frame) {
  if (loads.size() != static_cast<size_t>(unit_count_)) {
    throw std::invalid_argument("strain model: " + std::to_string(loads.size()) + " loads for " +
                                std::to_string(unit_count_) + " units");
  }
  frame->sequence = sequence_++;
  frame->time_s = time_s;
  frame->unit_count = unit_count_;
  frame->flags = 0;
  const double temperature_factor = 1.0 + config_.temperature_coefficient_per_k * TemperatureOffsetK(time_s);
  const double noise_ohm = config_.noise_ohm * noise_scale_;
  const double limit_n = config_.saturation_force_n;
  for (size_t unit = 0; unit < loads.size(); ++unit) {
    const UnitLoad& load = loads[unit];
    // The overload stop limits what reaches the gauge; cross-talk acts on what the beam carries.
    const double fn_n = Clip(load.fn_n, limit_n);
    const double ft_n = Clip(load.ft_n, limit_n);
    const double cross_n = Clip(load.cross_shear_n, limit_n);
    const double apparent_ft_n = ft_n + config_.cross_talk_shear_fraction * cross_n +
                                 config_.cross_talk_offset_per_mm * (load.offset_along_beam_m * 1e3) * fn_n;
    const double eps_n = kn_[unit] * fn_n;
    const double eps_t = kt_[unit] * apparent_ft_n;
    const double gauge_factor = config_.nominal.gauge_factor;
    double r1 = r0_r1_[unit] * temperature_factor * (1.0 + gauge_factor * (eps_n + eps_t)) + bias_r1_[unit];
    double r2 = r0_r2_[unit] * temperature_factor * (1.0 + gauge_factor * (eps_n - eps_t)) + bias_r2_[unit];
    // Draw noise for every unit, faulty or not, so a fault does not shift the others' noise.
    if (noise_ohm > 0.0) {
      r1 += noise_ohm * normal_(rng_);
      r2 += noise_ohm * normal_(rng_);
    }
    switch (faults_[unit]) {
      case UnitFault::kOpen:
        frame->r1_ohm[unit] = kOpenCircuitOhm;
        frame->r2_ohm[unit] = kOpenCircuitOhm;
        break;
      case UnitFault::kShort:
        frame->r1_ohm[unit] = kShortCircuitOhm;
        frame->r2_ohm[unit] = kShortCircuitOhm;
        break;
      case UnitFault::kNone:
        // A real bridge never reads below zero; quantisation then models the ADC.
        frame->r1_ohm[unit] = Quantise(std::max(r1, 0.0));
        frame->r2_ohm[unit] = Quantise(std::max(r2, 0.0));
        break;
    }
  }
}

}  // namespace graspbed::sensor
