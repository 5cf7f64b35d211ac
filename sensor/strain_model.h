#pragma once
/// The forward model of the sensing units (paper eqs. 1-3): per-unit loads -> strains -> R1/R2, with
/// the non-ideal effects of real hardware as seeded, switchable options. Used by the simulated
/// backend; the readout downstream never sees anything but the RawFrame it produces.

#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include "common/field_table.h"
#include "common/yaml_map.h"
#include "sensor/layout.h"
#include "sensor/raw_frame.h"

namespace graspbed::sensor {

/// Load on one unit's mesa, resolved in the unit frame.
struct UnitLoad {
  double fn_n = 0.0;                 ///< normal force along the inward normal, + pressing in [N]
  double ft_n = 0.0;                 ///< shear along the beam axis [N]
  double cross_shear_n = 0.0;        ///< shear across the beam axis (normal x beam) [N]
  double offset_along_beam_m = 0.0;  ///< where the normal load acts, from the mesa centre [m]
};

/// Paper constants of one unit (eqs. 1-2).
struct UnitConstants {
  double r0_ohm = 3400.0;     ///< unstrained resistance of R1 and R2 [Ohm]
  double gauge_factor = 100;  ///< G, dR/R per strain
  double kn_per_n = 5.5e-4;   ///< strain per N of normal force [1/N]
  double kt_per_n = 4.1e-4;   ///< strain per N of shear along the beam [1/N]
  double rated_force_n = 10;  ///< rated range of Fn and |Ft| [N]
};

/// Runtime fault of one unit (scenario fault injection, or set in the config).
enum class UnitFault : uint8_t { kNone, kOpen, kShort };

/// R1 and R2 of one unit [Ohm].
struct GaugeResistances {
  double r1_ohm = 0.0;
  double r2_ohm = 0.0;
};

/// The paper's ideal forward model (eqs. 1-3) for one unit: R_i = R0 (1 + G eps_i) with
/// eps_1 = kn Fn + kt Ft, eps_2 = kn Fn - kt Ft. Loads in the unit frame [N].
GaugeResistances IdealGaugeResistances(const UnitConstants& constants, double fn_n, double ft_n);

/// The forward model's settings: the paper's constants plus non-ideal effects of real hardware,
/// every one off by default. Loaded from its own YAML section by LoadStrainModelConfig (keys are
/// the field names; docs/sensor.md lists them with units and defaults).
struct StrainModelConfig {
  UnitConstants nominal;  ///< paper values unless overridden

  /// Per-channel R0 spread: R0 = nominal (1 + f z), z ~ N(0, 1) clipped to +-3, drawn once from
  /// the seed [fraction of R0; 0 = off].
  double r0_spread_fraction = 0.0;
  /// Per-unit spread of kn and kt (manufacturing), same form as the R0 spread [fraction; 0 = off].
  double sensitivity_spread_fraction = 0.0;
  /// Gaussian noise added to every channel every sample, standard deviation [Ohm; 0 = off].
  double noise_ohm = 0.0;
  /// ADC resolution [bits]; 0 = ideal (no quantisation, no full-scale clipping).
  int adc_bits = 0;
  /// Top of the ADC input window [Ohm]; readings at or above it report full scale (the readout
  /// marks that channel out of range). Used only when adc_bits > 0.
  double adc_full_scale_ohm = 10000.0;
  /// Bottom of the ADC input window [Ohm]: codes 0 .. 2^bits - 1 span adc_min_ohm ..
  /// adc_full_scale_ohm (a bridge and amplifier read a window around R0, a divider 0 .. full
  /// scale); readings at or below it report the bottom code. Used only when adc_bits > 0.
  double adc_min_ohm = 0.0;
  /// Temperature coefficient of R0 [1/K]: R0(T) = R0 (1 + alpha dT); 0 = off.
  double temperature_coefficient_per_k = 0.0;
  /// Temperature offset from the calibration temperature at t = 0 [K].
  double temperature_offset_k = 0.0;
  /// Temperature ramp: dT(t) = offset + ramp t [K/s].
  double temperature_ramp_k_per_s = 0.0;
  /// Mechanical overload stop: each of Fn, |Ft| and |cross shear| acting on the gauge is clipped
  /// to this load [N]; 0 = off (perfectly linear at any load). The inversion then reports an
  /// estimate above the rated range as out of range.
  double saturation_force_n = 0.0;
  /// Fraction of the cross-axis shear that appears as shear along the beam (eps_t) [-].
  double cross_talk_shear_fraction = 0.0;
  /// Off-centre normal load: fraction of Fn that appears as shear along the beam per mm of
  /// offset of the load from the mesa centre along the beam [1/mm].
  double cross_talk_offset_per_mm = 0.0;
  /// Units whose channels read open circuit (kOpenCircuitOhm) from the start (layout indices).
  std::vector<int> dead_units;
  /// Units whose channels read short circuit (0 Ohm) from the start (layout indices).
  std::vector<int> shorted_units;

  /// Checks every field against StrainModelConfigFields() and the unit lists against kMaxUnits.
  /// @throws common::ConfigError "strain_model.KEY = VALUE: reason".
  void Validate() const;
};

/// The fields of StrainModelConfig (loader, Validate(), emitter and reference table derive from
/// it); dead_units and shorted_units are its custom fields (bounded by the layout at load).
const common::FieldTable<StrainModelConfig>& StrainModelConfigFields();

/// Reads a StrainModelConfig from its own YAML section (unknown keys are refused); errors are
/// common::ConfigError naming file, line, key and value. `unit_count` bounds dead/shorted units.
/// Keys absent from `map` keep their value in `defaults` (a sensor profile, sensor_profile.h).
/// @throws common::ConfigError naming file, line, key and value.
StrainModelConfig LoadStrainModelConfig(const common::YamlMap& map, int unit_count = kMaxUnits,
                                        const StrainModelConfig& defaults = {});
/// Writes `config` as the keys of the YAML map `out` is in (the keys in `skip` left out), the unit
/// lists included; LoadStrainModelConfig reads it back to the same config.
void EmitStrainModelConfig(const StrainModelConfig& config, YAML::Emitter& out,
                           const std::vector<std::string>& skip = {});

/// Per-unit loads -> RawFrame. Mutable per-run state (RNG, faults, biases) lives here; the layout
/// is only read at construction. Sample() allocates nothing and never throws for valid sizes.
class StrainModel {
 public:
  /// Draws the per-unit spreads from `seed`; the same seed gives identical frames.
  /// Throws std::invalid_argument for an invalid config or a dead/shorted unit outside the layout.
  StrainModel(const Layout& layout, const StrainModelConfig& config, uint64_t seed);

  /// Writes one frame for `loads` (one per unit, layout order) at source time `time_s` [s].
  /// Sequence numbers count up from 0. Throws std::invalid_argument if loads.size() differs from
  /// the unit count (a programming error, not a runtime condition).
  void Sample(std::span<const UnitLoad> loads, double time_s, RawFrame* frame);

  /// Injects or clears a fault on both channels of `unit` (overrides the config lists).
  void SetUnitFault(int unit, UnitFault fault);
  /// Adds a constant offset to each channel of `unit` (drift, bad contact) [Ohm].
  void SetBiasOhm(int unit, double r1_bias_ohm, double r2_bias_ohm);
  /// Multiplies noise_ohm (scenario "noise burst"); 1 = as configured.
  void SetNoiseScale(double scale);
  /// Extra temperature offset on top of the configured offset and ramp [K].
  void SetTemperatureOffsetK(double kelvin);

  int unit_count() const { return unit_count_; }
  const StrainModelConfig& config() const { return config_; }
  /// Unstrained R1 of every unit after the spread, at the calibration temperature [Ohm].
  const std::vector<double>& r0_ohm_r1() const { return r0_r1_; }
  /// Unstrained R2 of every unit after the spread [Ohm].
  const std::vector<double>& r0_ohm_r2() const { return r0_r2_; }
  /// Per-unit kn after the spread [1/N].
  const std::vector<double>& kn_per_n() const { return kn_; }
  /// Per-unit kt after the spread [1/N].
  const std::vector<double>& kt_per_n() const { return kt_; }
  UnitFault fault(int unit) const { return faults_.at(static_cast<size_t>(unit)); }
  /// Temperature offset dT in effect at `time_s` [K].
  double TemperatureOffsetK(double time_s) const;

 private:
  double Quantise(double resistance_ohm) const;

  StrainModelConfig config_;
  int unit_count_ = 0;
  std::vector<double> r0_r1_, r0_r2_, kn_, kt_;
  std::vector<double> bias_r1_, bias_r2_;
  std::vector<UnitFault> faults_;
  double adc_max_code_ = 0.0;  // 2^bits - 1
  double adc_lsb_ohm_ = 0.0;   // (full scale - min) / max code
  double noise_scale_ = 1.0;
  double extra_temperature_k_ = 0.0;
  uint32_t sequence_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace graspbed::sensor
