#pragma once
/// Readout: RawFrame -> relative resistance change dR/R per channel, against a tare baseline, with
/// per-unit validity. Identical for simulated and hardware frames.

#include <array>
#include <cstdint>
#include <span>

#include "common/field_table.h"
#include "common/yaml_map.h"
#include "sensor/raw_frame.h"
#include "sensor/tactile_state.h"

namespace graspbed::sensor {

/// dR/R of every channel for one frame, plus validity.
struct ReadoutFrame {
  uint32_t sequence = 0;
  double time_s = 0.0;  ///< sample time of the frame [s]
  int unit_count = 0;
  std::array<double, kMaxUnits> dr1_rel{};  ///< (R1 - R1_baseline) / R1_baseline
  std::array<double, kMaxUnits> dr2_rel{};  ///< (R2 - R2_baseline) / R2_baseline
  std::array<UnitValidity, kMaxUnits> validity{};
  /// Noise measured during the last tare (Readout::noise_known() and the arrays below); copied into
  /// every frame so the inversion can report it in N.
  bool noise_known = false;
  /// Which tare the noise arrays below come from (Readout::noise_generation()); Process() copies
  /// them only when this differs, so the per-frame cost stays flat.
  uint32_t noise_generation = 0;
  std::array<double, kMaxUnits> r1_noise_ohm{};  ///< standard deviation of R1 over the tare [Ohm]
  std::array<double, kMaxUnits> r2_noise_ohm{};  ///< standard deviation of R2 over the tare [Ohm]
  /// Standard deviation of s = (dR1/R1 + dR2/R2) / 2 and d = (dR1/R1 - dR2/R2) / 2 over the tare,
  /// with the R1-R2 covariance (the inversion's Fn and Ft are s / (G kn) and d / (G kt)) [-].
  std::array<double, kMaxUnits> sum_noise_rel{};
  std::array<double, kMaxUnits> diff_noise_rel{};
};

/// Readout settings. Resistance bounds are fractions of the nominal R0 so they follow the gauge.
struct ReadoutConfig {
  /// Frames averaged for the tare baseline after construction or Reset() [frames, >= 1].
  int baseline_frames = 100;
  /// A channel at or below this reads as a short circuit [Ohm].
  double short_circuit_ohm = 1.0;
  /// A channel at or above this (or infinite) reads as open circuit [Ohm].
  double open_circuit_ohm = 1e6;
  /// Channel resistance outside [min, max] x nominal R0 (but not open/short) is implausible [-].
  double min_plausible_fraction = 0.2;
  double max_plausible_fraction = 3.0;
  /// A tare baseline further than this from nominal R0 is implausible (bad tare, wrong gauge) [-].
  double max_baseline_deviation_fraction = 0.3;
  /// Mean dR/R of a unit below this is implausible: the mesa would be pulled hard, which the
  /// frame cannot transmit (the paper's -Fn) [-]; -0.1 is about -1.8 N at paper sensitivities.
  double min_mean_dr_rel = -0.1;
  /// |dR/R| of a channel above this is out of the gauge's linear range [-]; paper max is 0.96.
  double max_abs_dr_rel = 1.5;
  /// ADC full scale of the source [Ohm]; a channel at or above it is clipped and marked out of
  /// range. 0 = unknown (no check).
  double adc_full_scale_ohm = 0.0;
  /// Bottom of the source's ADC window [Ohm]; a channel at or below it is clipped and marked out of
  /// range. 0 = none (a divider reads down to 0 Ohm, which is a short).
  double adc_min_ohm = 0.0;

  /// Checks every field against ReadoutConfigFields().
  /// @throws common::ConfigError "readout.KEY = VALUE: reason".
  void Validate() const;
};

/// The fields of ReadoutConfig: keys, rules, units, docs; its loader, Validate(), emitter (Emit) and
/// reference table (`graspbed config-reference`) all come from it.
const common::FieldTable<ReadoutConfig>& ReadoutConfigFields();

/// Reads a ReadoutConfig from its own YAML section (field names as keys; unknown keys refused).
/// Keys absent from `map` keep their value in `defaults`.
/// @throws common::ConfigError naming file, line, key and value.
ReadoutConfig LoadReadoutConfig(const common::YamlMap& map, const ReadoutConfig& defaults = {});

/// Tare + dR/R + per-unit validity + channel noise. Holds the baseline; Process() allocates nothing.
///
/// Noise estimate: over the tare window each channel's readings are fitted with a straight line
/// (a slow drift, e.g. temperature, is not noise) and the residual standard deviation of R1, R2
/// and of the inversion's sum s and difference d is kept (sample statistics, n - 2 degrees of
/// freedom). It assumes the unit is unloaded and still during the tare, as the baseline does.
/// A quantised, noiseless channel honestly reports 0: a threshold built on it needs a floor.
class Readout {
 public:
  /// Throws std::invalid_argument for an invalid config, unit_count outside 1..kMaxUnits or a
  /// non-positive nominal R0.
  Readout(const ReadoutConfig& config, int unit_count, double nominal_r0_ohm);

  /// Forgets the baseline; the next baseline_frames frames tare again (validity kNotTared).
  void Reset();
  /// True once a baseline exists (averaged or set).
  bool tared() const { return tared_; }
  /// Uses a stored baseline [Ohm] instead of averaging; sizes must equal unit_count and values be
  /// finite and > 0 (std::invalid_argument otherwise).
  void SetBaseline(std::span<const double> r1_ohm, std::span<const double> r2_ohm);

  /// One frame -> dR/R and validity. While taring, validity is kNotTared (open/short still shown)
  /// and dR/R is 0. A frame whose unit_count differs marks every unit implausible.
  void Process(const RawFrame& frame, ReadoutFrame* out);

  int unit_count() const { return unit_count_; }
  double nominal_r0_ohm() const { return nominal_r0_ohm_; }
  /// Baseline per unit [Ohm] (meaningful once tared()).
  const std::array<double, kMaxUnits>& baseline_r1_ohm() const { return baseline_r1_; }
  const std::array<double, kMaxUnits>& baseline_r2_ohm() const { return baseline_r2_; }
  /// Frames averaged so far in the current tare window.
  int baseline_frames_seen() const { return frames_seen_; }
  /// True once a tare window of >= 3 frames produced a noise estimate (not after SetBaseline()).
  bool noise_known() const { return noise_known_; }
  /// Changes whenever the noise figures change (each finished tare, SetBaseline()); never 0.
  uint32_t noise_generation() const { return noise_generation_; }
  /// Residual standard deviation of each channel over the last tare window [Ohm].
  const std::array<double, kMaxUnits>& r1_noise_ohm() const { return r1_noise_ohm_; }
  const std::array<double, kMaxUnits>& r2_noise_ohm() const { return r2_noise_ohm_; }
  /// Standard deviation of (dR1/R1 + dR2/R2) / 2 and (dR1/R1 - dR2/R2) / 2 over the tare [-].
  const std::array<double, kMaxUnits>& sum_noise_rel() const { return sum_noise_rel_; }
  const std::array<double, kMaxUnits>& diff_noise_rel() const { return diff_noise_rel_; }

 private:
  // Validity of one channel value before any baseline is involved.
  UnitValidity ChannelValidity(double resistance_ohm) const;
  void FinishBaseline();
  void FinishNoise(int unit);

  ReadoutConfig config_;
  int unit_count_ = 0;
  double nominal_r0_ohm_ = 0.0;
  bool tared_ = false;
  int frames_seen_ = 0;
  std::array<double, kMaxUnits> sum_r1_{}, sum_r2_{};
  std::array<int, kMaxUnits> count_r1_{}, count_r2_{};
  std::array<double, kMaxUnits> baseline_r1_{}, baseline_r2_{};
  std::array<bool, kMaxUnits> baseline_ok_{};
  // Tare-window statistics for the noise estimate: readings relative to the channel's first good
  // reading (no cancellation against R0^2), against the frame index k, over frames where both
  // channels were good.
  struct NoiseSums {
    int count = 0;
    double first_r1 = 0.0, first_r2 = 0.0;
    double k = 0.0, kk = 0.0;
    double x = 0.0, xx = 0.0, xk = 0.0;  // x = R1 - first_r1
    double y = 0.0, yy = 0.0, yk = 0.0;  // y = R2 - first_r2
    double xy = 0.0;
  };
  std::array<NoiseSums, kMaxUnits> noise_sums_{};
  bool noise_known_ = false;
  uint32_t noise_generation_ = 1;
  std::array<double, kMaxUnits> r1_noise_ohm_{}, r2_noise_ohm_{}, sum_noise_rel_{}, diff_noise_rel_{};
};

}  // namespace graspbed::sensor
