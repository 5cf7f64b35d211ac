#pragma once
/// Sensor profiles: named, realistic settings of the strain model, each derived from a real readout
/// chain for the 3.4 kOhm gauges (excitation, divider or bridge, amplifier, ADC) and the gauge's
/// own non-idealities (spreads, temperature coefficient, cross-talk), plus `ideal` (the paper's
/// gauge read perfectly). A scenario picks one with `sensor: {profile: NAME}`; explicit
/// strain_model / readout keys override what the profile sets. docs/sensor.md tables every profile
/// with the source of each number; tests/sensor/sensor_profile_test.cc prints and checks what the
/// strain model then produces.
///
/// The chain's gain and window depend on the gauge's sensitivities: a board is designed for the
/// sensor it reads (the paper's constants or the unit FEA's, 16-65x smaller), so the profile is
/// resolved against the nominal constants the scenario uses.

#include <string>
#include <vector>

#include "sensor/readout.h"
#include "sensor/strain_model.h"

namespace graspbed::sensor {

/// How each gauge resistor becomes a voltage.
enum class ChainTopology {
  /// R_i in series with a reference resistor R_ref across the excitation, the midpoint read
  /// single-ended against the ADC's reference (= the excitation, ratiometric).
  kDivider,
  /// R_i and R_ref as one half bridge, read differentially against a reference half bridge of two
  /// R_ref (a quarter bridge per channel), through an amplifier or an ADC's own PGA.
  kQuarterBridge,
};

/// One readout chain, in datasheet figures. Units in the names.
struct ReadoutChain {
  ChainTopology topology = ChainTopology::kQuarterBridge;
  double excitation_v = 2.5;  ///< bridge/divider excitation, also the ADC reference [V]
  /// Reference (completion) resistor as a fraction of the nominal R0 [-]; 1 = matched.
  double reference_fraction = 1.0;
  /// Amplifier input-referred voltage noise density eNI and output noise density eNO (referred to
  /// the input as eNO / gain) [nV/sqrt(Hz)]; 0, 0 = no separate amplifier.
  double amplifier_input_noise_nv_rthz = 0.0;
  double amplifier_output_noise_nv_rthz = 0.0;
  /// Largest gain the amplifier or PGA offers [-]; the chain uses the largest power of two that
  /// keeps the channel's whole range (see ChainDerivation) inside the ADC span. 1 = no gain stage.
  double max_gain = 1.0;
  int adc_bits = 16;        ///< ADC resolution [bits]
  double adc_span_v = 5.0;  ///< ADC input span at gain 1, peak to peak [V]
  /// SAR-class ADC: effective number of bits (datasheet SINAD), giving its noise beyond
  /// quantisation; 0 = use the delta-sigma figures below.
  double adc_enob_bits = 0.0;
  /// Delta-sigma-class ADC at the chosen data rate: input-referred noise sqrt(floor^2 +
  /// (gain1 / gain)^2) [uV rms] (a fit to the datasheet's noise-vs-gain table).
  double adc_noise_floor_uv_rms = 0.0;
  double adc_noise_gain1_uv_rms = 0.0;
  /// Equivalent noise bandwidth for the analog noise densities (anti-alias or digital filter) [Hz].
  double noise_bandwidth_hz = 500.0;
  double temperature_k = 300.0;  ///< board temperature for the resistors' Johnson noise [K]
};

/// The gauge's own non-idealities (the same gauge behind every chain).
struct GaugeNonIdeal {
  double r0_spread_fraction = 0.0;           ///< per channel, 1 sigma [-]
  double sensitivity_spread_fraction = 0.0;  ///< per unit kn, kt, 1 sigma [-]
  double temperature_coefficient_per_k = 0.0;
  double temperature_ramp_k_per_s = 0.0;
  double cross_talk_shear_fraction = 0.0;
  double cross_talk_offset_per_mm = 0.0;
  /// The chain's window must also hold an ambient change of this much from the tare [K].
  double ambient_range_k = 0.0;
  /// The chain's window must hold loads up to this multiple of the rated force [-].
  double overload_factor = 1.2;
};

/// A named profile: `ideal` has neither chain nor non-idealities.
struct SensorProfile {
  std::string name;
  std::string summary;  ///< one line for messages and docs
  bool ideal = false;
  ReadoutChain chain;
  GaugeNonIdeal gauge;
};

/// What a chain works out to for given gauge constants (all at the operating point R0).
struct ChainDerivation {
  double slope_v_per_ohm = 0.0;   ///< d(input voltage)/dR at R0 [V/Ohm]
  double source_ohm = 0.0;        ///< resistance the amplifier/ADC input sees (Johnson noise) [Ohm]
  double range_low_ohm = 0.0;     ///< lowest channel resistance the window must hold [Ohm]
  double range_high_ohm = 0.0;    ///< highest [Ohm]
  double gain = 1.0;              ///< amplifier/PGA gain chosen [-]
  double window_low_ohm = 0.0;    ///< where the ADC clips, low (>= 0) [Ohm]
  double window_high_ohm = 0.0;   ///< where the ADC clips, high (<= 4 R0) [Ohm]
  double lsb_at_r0_ohm = 0.0;     ///< one ADC step at R0, referred to the gauge [Ohm]
  double johnson_uv_rms = 0.0;    ///< source resistance noise over the bandwidth [uV rms]
  double amplifier_uv_rms = 0.0;  ///< amplifier noise over the bandwidth, input-referred [uV rms]
  double adc_uv_rms = 0.0;        ///< ADC noise (beyond quantisation), input-referred [uV rms]
  double noise_ohm = 0.0;         ///< all of it at R0, referred to the gauge (strain model noise_ohm) [Ohm]
};

/// Names of the shipped profiles, `ideal` first.
std::vector<std::string> SensorProfileNames();
/// The profile called `name`; throws std::invalid_argument listing the valid names.
const SensorProfile& FindSensorProfile(const std::string& name);

/// Works out a chain for gauges with the `nominal` constants and the gauge non-idealities.
ChainDerivation DeriveChain(const ReadoutChain& chain, const GaugeNonIdeal& gauge,
                            const UnitConstants& nominal);

/// The strain model settings of a profile for gauges with `nominal` constants (kept in the
/// result). `ideal` returns the default (all effects off) config.
StrainModelConfig ProfileStrainModel(const SensorProfile& profile, const UnitConstants& nominal);
/// The readout settings that match: the ADC window, so a clipped channel reads out of range.
ReadoutConfig ProfileReadout(const SensorProfile& profile, const UnitConstants& nominal);

}  // namespace graspbed::sensor
