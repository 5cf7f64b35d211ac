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

using common::Require;

double Clip(double value, double limit) { return limit > 0.0 ? std::clamp(value, -limit, limit) : value; }

}  // namespace

GaugeResistances IdealGaugeResistances(const UnitConstants& constants, double fn_n, double ft_n) {
  const double eps_n = constants.kn_per_n * fn_n;
  const double eps_t = constants.kt_per_n * ft_n;
  return {constants.r0_ohm * (1.0 + constants.gauge_factor * (eps_n + eps_t)),
          constants.r0_ohm * (1.0 + constants.gauge_factor * (eps_n - eps_t))};
}

const common::FieldTable<StrainModelConfig>& StrainModelConfigFields() {
  using Table = common::FieldTable<StrainModelConfig>;
  using C = StrainModelConfig;
  using U = UnitConstants;
  static const Table table(
      "strain_model",
      {
          Table::Number("r0_ohm", &C::nominal, &U::r0_ohm, {0.0, 1e7, true}, "Ohm", "unstrained R1 = R2"),
          Table::Number("gauge_factor", &C::nominal, &U::gauge_factor, {0.0, 1000.0, true}, "-",
                        "G, dR/R per strain"),
          Table::Number("kn_per_n", &C::nominal, &U::kn_per_n, {0.0, 1.0, true}, "1/N",
                        "strain per N of Fn (set by the FEA with `sensitivities: fea`)"),
          Table::Number("kt_per_n", &C::nominal, &U::kt_per_n, {0.0, 1.0, true}, "1/N",
                        "strain per N of Ft (set by the FEA with `sensitivities: fea`)"),
          Table::Number("rated_force_n", &C::nominal, &U::rated_force_n, {0.0, 1000.0, true}, "N",
                        "rated range of Fn and abs(Ft)"),
          Table::Number(
              "r0_spread_fraction", &C::r0_spread_fraction, NumberRule::Between(0.0, 0.3), "-",
              "per-channel R0 = r0 (1 + f z), z ~ N(0,1) clipped to +-3, drawn once from the seed; 0 = off"),
          Table::Number("sensitivity_spread_fraction", &C::sensitivity_spread_fraction,
                        NumberRule::Between(0.0, 0.3), "-",
                        "per-unit kn, kt spread of the same form; 0 = off"),
          Table::Number("noise_ohm", &C::noise_ohm, NumberRule::Between(0.0, 1e6), "Ohm",
                        "Gaussian noise (standard deviation) per channel per sample, seeded; "
                        "`SetNoiseScale()` scales it; 0 = off"),
          Table::Integer(
              "adc_bits", &C::adc_bits, 0, 32, "bits",
              "0 = ideal; else readings are rounded to the window / (2^bits - 1) and clipped to the window"),
          Table::Number("adc_full_scale_ohm", &C::adc_full_scale_ohm, {0.0, 1e8, true}, "Ohm",
                        "top of the ADC window (only with adc_bits > 0); a channel at full scale is out of "
                        "range to a readout told the same value"),
          Table::Number("adc_min_ohm", &C::adc_min_ohm, NumberRule::Between(0.0, 1e8), "Ohm",
                        "bottom of the ADC window: codes span adc_min_ohm .. adc_full_scale_ohm (a bridge "
                        "reads a window around R0)")
              .Note("< `adc_full_scale_ohm`"),
          Table::Number("temperature_coefficient_per_k", &C::temperature_coefficient_per_k,
                        NumberRule::Between(-0.0999, 0.0999), "1/K",
                        "R0(T) = R0 (1 + alpha dT); untared drift shows as apparent Fn; 0 = off"),
          Table::Number("temperature_offset_k", &C::temperature_offset_k, NumberRule::Between(-200.0, 200.0),
                        "K", "dT at t = 0; `SetTemperatureOffsetK()` adds to it at run time"),
          Table::Number("temperature_ramp_k_per_s", &C::temperature_ramp_k_per_s,
                        NumberRule::Between(-100.0, 100.0), "K/s", "dT(t) = offset + ramp t"),
          Table::Number("saturation_force_n", &C::saturation_force_n, NumberRule::Between(0.0, 1000.0), "N",
                        "0 = off; else Fn, Ft and cross shear reaching the gauge are clipped to +-this "
                        "(overload stop); the inversion flags the estimate out of range"),
          Table::Number("cross_talk_shear_fraction", &C::cross_talk_shear_fraction,
                        NumberRule::Between(-1.0, 1.0), "-",
                        "fraction of the cross-axis shear that appears as Ft"),
          Table::Number("cross_talk_offset_per_mm", &C::cross_talk_offset_per_mm,
                        NumberRule::Between(-10.0, 10.0), "1/mm",
                        "Fn x offset along the beam [mm] x this appears as Ft (off-centre load)"),
          Table::Custom("dead_units", "", "[]", "unit indices of the layout, each once",
                        "those units read open circuit (R = +inf) from the start"),
          Table::Custom("shorted_units", "", "[]", "unit indices of the layout, each once, not dead",
                        "those units read short circuit (R = 0) from the start"),
      },
      [](const C& c) {
        if (!(c.adc_min_ohm < c.adc_full_scale_ohm)) {
          common::FieldError("adc_min_ohm", c.adc_min_ohm,
                             "the ADC window needs adc_min_ohm < adc_full_scale_ohm (" +
                                 common::ReadableNumber(c.adc_min_ohm) + " vs " +
                                 common::ReadableNumber(c.adc_full_scale_ohm) + ")");
        }
      });
  return table;
}

void StrainModelConfig::Validate() const {
  StrainModelConfigFields().Validate(*this);
  for (int unit : dead_units)
    Require(unit >= 0 && unit < kMaxUnits, "strain_model.dead_units[]", unit, "no such unit");
  for (int unit : shorted_units) {
    Require(unit >= 0 && unit < kMaxUnits, "strain_model.shorted_units[]", unit, "no such unit");
    Require(std::find(dead_units.begin(), dead_units.end(), unit) == dead_units.end(),
            "strain_model.shorted_units[]", unit, "is also in dead_units");
  }
}

StrainModelConfig LoadStrainModelConfig(const common::YamlMap& map, int unit_count,
                                        const StrainModelConfig& defaults) {
  StrainModelConfig config = defaults;
  StrainModelConfigFields().Load(map, &config);
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
  return config;
}

void EmitStrainModelConfig(const StrainModelConfig& config, YAML::Emitter& out,
                           const std::vector<std::string>& skip) {
  StrainModelConfigFields().Emit(config, out, skip);
  for (const auto& [key, units] :
       {std::pair{"dead_units", &config.dead_units}, std::pair{"shorted_units", &config.shorted_units}}) {
    out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int unit : *units) out << unit;
    out << YAML::EndSeq;
  }
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
