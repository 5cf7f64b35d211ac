#include "sensor/sensor_profile.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace graspbed::sensor {
namespace {

constexpr double kBoltzmannJ_K = 1.380649e-23;

// The gauge behind every realistic chain; docs/sensor.md gives the source of each number.
GaugeNonIdeal RealGauge() {
  GaugeNonIdeal gauge;
  gauge.r0_spread_fraction = 0.02;               // silicon gauges from one lot, +-6 % at 3 sigma
  gauge.sensitivity_spread_fraction = 0.05;      // beam thickness +-5 um (strain ~ 1/t^2) and G spread
  gauge.temperature_coefficient_per_k = 1.5e-3;  // p-type silicon piezoresistor, ~1e19 /cm^3
  gauge.temperature_ramp_k_per_s = 0.01;         // fingertip warming 0.6 K/min after the tare
  gauge.cross_talk_shear_fraction = 0.035;       // gauge bonded by hand, +-2 deg: sin 2 deg
  gauge.cross_talk_offset_per_mm = 0.0;          // not derived (needs the FEA's off-centre case)
  gauge.ambient_range_k = 10.0;
  gauge.overload_factor = 1.2;
  return gauge;
}

std::vector<SensorProfile> MakeProfiles() {
  std::vector<SensorProfile> profiles;
  SensorProfile ideal;
  ideal.name = "ideal";
  ideal.summary = "the paper's gauge read perfectly: no noise, no ADC, no spread, drift or cross-talk";
  ideal.ideal = true;
  profiles.push_back(ideal);

  SensorProfile divider;
  divider.name = "divider_12bit";
  divider.summary = "each gauge in a divider from 3.3 V straight into a microcontroller's 12-bit SAR ADC";
  divider.chain.topology = ChainTopology::kDivider;
  divider.chain.excitation_v = 3.3;
  divider.chain.max_gain = 1.0;
  divider.chain.adc_bits = 12;
  divider.chain.adc_span_v = 3.3;
  divider.chain.adc_enob_bits = 10.5;
  divider.chain.noise_bandwidth_hz = 785.0;  // first-order RC anti-alias at 500 Hz: pi/2 x 500
  divider.gauge = RealGauge();
  profiles.push_back(divider);

  SensorProfile inamp;
  inamp.name = "inamp_16bit";
  inamp.summary = "quarter bridge at 2.5 V, INA333-class zero-drift in-amp, 16-bit multiplexed SAR ADC";
  inamp.chain.topology = ChainTopology::kQuarterBridge;
  inamp.chain.excitation_v = 2.5;
  inamp.chain.amplifier_input_noise_nv_rthz = 50.0;
  inamp.chain.amplifier_output_noise_nv_rthz = 200.0;
  inamp.chain.max_gain = 1000.0;
  inamp.chain.adc_bits = 16;
  inamp.chain.adc_span_v = 5.12;  // +-2.56 V range
  inamp.chain.adc_enob_bits = 14.5;
  inamp.chain.noise_bandwidth_hz = 785.0;
  inamp.gauge = RealGauge();
  profiles.push_back(inamp);

  SensorProfile delta_sigma;
  delta_sigma.name = "bridge_24bit";
  delta_sigma.summary =
      "quarter bridge at 2.5 V straight into an ADS131M08-class 24-bit delta-sigma ADC with PGA, 1 kSPS";
  delta_sigma.chain.topology = ChainTopology::kQuarterBridge;
  delta_sigma.chain.excitation_v = 2.5;
  delta_sigma.chain.max_gain = 128.0;
  delta_sigma.chain.adc_bits = 24;
  delta_sigma.chain.adc_span_v = 2.4;  // +-1.2 V / gain
  delta_sigma.chain.adc_noise_floor_uv_rms = 0.9;
  delta_sigma.chain.adc_noise_gain1_uv_rms = 3.3;
  delta_sigma.chain.noise_bandwidth_hz = 500.0;
  delta_sigma.gauge = RealGauge();
  profiles.push_back(delta_sigma);
  return profiles;
}

const std::vector<SensorProfile>& Profiles() {
  static const std::vector<SensorProfile> profiles = MakeProfiles();
  return profiles;
}

// Input voltage of a channel at resistance r, relative to the mid-scale the chain reads against.
double InputVolts(const ReadoutChain& chain, double r_ref_ohm, double r_ohm) {
  return chain.excitation_v * (r_ohm / (r_ohm + r_ref_ohm) - 0.5);
}

// Resistance at which the input reaches u (inverse of InputVolts); infinite at or past +Vex/2.
double ResistanceAt(const ReadoutChain& chain, double r_ref_ohm, double u_v) {
  const double fraction = u_v / chain.excitation_v;
  if (fraction >= 0.5) return std::numeric_limits<double>::infinity();
  if (fraction <= -0.5) return 0.0;
  return r_ref_ohm * (0.5 + fraction) / (0.5 - fraction);
}

}  // namespace

std::vector<std::string> SensorProfileNames() {
  std::vector<std::string> names;
  for (const SensorProfile& profile : Profiles()) names.push_back(profile.name);
  return names;
}

const SensorProfile& FindSensorProfile(const std::string& name) {
  for (const SensorProfile& profile : Profiles()) {
    if (profile.name == name) return profile;
  }
  std::string valid;
  for (const std::string& known : SensorProfileNames()) valid += (valid.empty() ? "" : ", ") + known;
  throw std::invalid_argument("no sensor profile '" + name + "'; valid profiles: " + valid);
}

ChainDerivation DeriveChain(const ReadoutChain& chain, const GaugeNonIdeal& gauge,
                            const UnitConstants& nominal) {
  ChainDerivation d;
  const double r0 = nominal.r0_ohm;
  const double r_ref = chain.reference_fraction * r0;
  d.slope_v_per_ohm = chain.excitation_v * r_ref / ((r0 + r_ref) * (r0 + r_ref));
  const double node_ohm = r0 * r_ref / (r0 + r_ref);
  d.source_ohm = chain.topology == ChainTopology::kDivider ? node_ohm : node_ohm + 0.5 * r_ref;

  // The range a channel can take: the largest spread R0 (3 sigma, as the strain model clips it)
  // and an ambient change, at the overload factor times the rated force, with the most sensitive
  // unit; R1 under Fn and +Ft is the highest, R2 under +Ft alone the lowest.
  const double force_n = nominal.rated_force_n * gauge.overload_factor;
  const double sensitivity = 1.0 + 3.0 * gauge.sensitivity_spread_fraction;
  const double r0_high = r0 * (1.0 + 3.0 * gauge.r0_spread_fraction);
  const double r0_low = r0 * (1.0 - 3.0 * gauge.r0_spread_fraction);
  const double thermal = std::abs(gauge.temperature_coefficient_per_k) * gauge.ambient_range_k;
  const double g = nominal.gauge_factor;
  d.range_high_ohm =
      r0_high * (1.0 + thermal) * (1.0 + g * (nominal.kn_per_n + nominal.kt_per_n) * sensitivity * force_n);
  d.range_low_ohm =
      std::max(0.0, r0_low * (1.0 - thermal) * (1.0 - g * nominal.kt_per_n * sensitivity * force_n));

  // Largest power-of-two gain that keeps that range inside the ADC span around mid-scale.
  const double half_span_v = 0.5 * chain.adc_span_v;
  const double needed_v = std::max(std::abs(InputVolts(chain, r_ref, d.range_high_ohm)),
                                   std::abs(InputVolts(chain, r_ref, d.range_low_ohm)));
  d.gain = 1.0;
  while (d.gain * 2.0 <= chain.max_gain && needed_v * d.gain * 2.0 <= half_span_v) d.gain *= 2.0;

  // Where the ADC clips; the strain model quantises linearly in Ohm between these (capped at
  // 4 R0, where a divider's top code would be at infinity).
  const double clip_v = half_span_v / d.gain;
  d.window_low_ohm = ResistanceAt(chain, r_ref, -clip_v);
  d.window_high_ohm = std::min(4.0 * r0, ResistanceAt(chain, r_ref, clip_v));
  const double lsb_v = chain.adc_span_v / std::ldexp(1.0, chain.adc_bits);
  d.lsb_at_r0_ohm = lsb_v / d.gain / d.slope_v_per_ohm;

  const double bandwidth_hz = chain.noise_bandwidth_hz;
  d.johnson_uv_rms = 1e6 * std::sqrt(4.0 * kBoltzmannJ_K * chain.temperature_k * d.source_ohm * bandwidth_hz);
  const double amplifier_nv =
      std::hypot(chain.amplifier_input_noise_nv_rthz, chain.amplifier_output_noise_nv_rthz / d.gain);
  d.amplifier_uv_rms = 1e-3 * amplifier_nv * std::sqrt(bandwidth_hz);
  if (chain.adc_enob_bits > 0.0) {
    // ENOB counts quantisation too: total rms error 2^(bits - ENOB) / sqrt(12) LSB; the strain
    // model quantises separately, so only the rest is noise.
    const double total_lsb = std::pow(2.0, chain.adc_bits - chain.adc_enob_bits) / std::sqrt(12.0);
    const double extra_lsb = std::sqrt(std::max(0.0, total_lsb * total_lsb - 1.0 / 12.0));
    d.adc_uv_rms = 1e6 * extra_lsb * lsb_v / d.gain;
  } else {
    d.adc_uv_rms = std::hypot(chain.adc_noise_floor_uv_rms, chain.adc_noise_gain1_uv_rms / d.gain);
  }
  const double total_uv = std::sqrt(d.johnson_uv_rms * d.johnson_uv_rms +
                                    d.amplifier_uv_rms * d.amplifier_uv_rms + d.adc_uv_rms * d.adc_uv_rms);
  d.noise_ohm = 1e-6 * total_uv / d.slope_v_per_ohm;
  return d;
}

StrainModelConfig ProfileStrainModel(const SensorProfile& profile, const UnitConstants& nominal) {
  StrainModelConfig config;
  config.nominal = nominal;
  if (profile.ideal) return config;
  const ChainDerivation d = DeriveChain(profile.chain, profile.gauge, nominal);
  config.noise_ohm = d.noise_ohm;
  config.adc_bits = profile.chain.adc_bits;
  config.adc_full_scale_ohm = d.window_high_ohm;
  config.adc_min_ohm = d.window_low_ohm;
  const GaugeNonIdeal& gauge = profile.gauge;
  config.r0_spread_fraction = gauge.r0_spread_fraction;
  config.sensitivity_spread_fraction = gauge.sensitivity_spread_fraction;
  config.temperature_coefficient_per_k = gauge.temperature_coefficient_per_k;
  config.temperature_ramp_k_per_s = gauge.temperature_ramp_k_per_s;
  config.cross_talk_shear_fraction = gauge.cross_talk_shear_fraction;
  config.cross_talk_offset_per_mm = gauge.cross_talk_offset_per_mm;
  return config;
}

ReadoutConfig ProfileReadout(const SensorProfile& profile, const UnitConstants& nominal) {
  ReadoutConfig config;
  if (profile.ideal) return config;
  const ChainDerivation d = DeriveChain(profile.chain, profile.gauge, nominal);
  config.adc_full_scale_ohm = d.window_high_ohm;
  config.adc_min_ohm = d.window_low_ohm;
  return config;
}

}  // namespace graspbed::sensor
