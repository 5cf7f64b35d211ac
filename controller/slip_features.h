#pragma once
/// SlipFeatures: the per-tick input of the learned slip cue, computed from what a controller sees
/// (TactileState and time). One function for both sides: `graspbed dataset` runs it over the states a
/// run logged and writes the features Python trains on; LearnedSlipCue runs it live. So a model is
/// trained on exactly the numbers it is later fed (docs/training-slip-detector.md).
///
/// The feature set is declared once, in kSlipFeatures (name, unit, meaning); its name and version
/// (kSlipFeatureSet) go into every dataset and model file, and a model trained on another set is
/// refused. Adding an input (e.g. the hand's proprioception, HandState, once GraspController::Update
/// receives it) means: a row in kSlipFeatures, a line in SlipFeatureExtractor::Update, and a new
/// kSlipFeatureSet version.
///
/// Reads only these TactileState fields, all of which signals.csv logs: unit_count, stale, fn_n,
/// ft_n, validity, total_fn_n, total_shear_axial_n, total_shear_circumferential_n.

#include <array>
#include <cstddef>
#include <span>

#include "controller/filters.h"
#include "sensor/tactile_state.h"

namespace graspbed::controller {

/// One input column of the learned cue.
struct SlipFeatureSpec {
  const char* name;  ///< column name in datasets and model files
  const char* doc;   ///< meaning, with its unit
};

/// Name of the feature set; a model file must name the same (with the same feature names in order).
inline constexpr const char* kSlipFeatureSet = "tactile_v1";

/// The features, in the order SlipFeatureExtractor::Update writes them.
inline constexpr SlipFeatureSpec kSlipFeatures[] = {
    {"total_fn_n", "sum of Fn over valid units [N]"},
    {"shear_n", "magnitude of the summed shear (axial, circumferential) [N]"},
    {"shear_ratio", "shear_n / max(total_fn_n, 0.2 N) [-]"},
    {"ratio_lp", "shear_ratio low-passed, 10 ms [-]"},
    {"ratio_rise", "ratio_lp now minus 10 ms ago [-]"},
    {"ratio_above_slow", "ratio_lp minus shear_ratio low-passed over 0.5 s [-]"},
    {"fn_rate_n_s", "rate of total_fn_n (5 ms low-pass) over 10 ms [N/s]"},
    {"shear_rate_n_s", "rate of shear_n (5 ms low-pass) over 10 ms [N/s]"},
    {"vibration_ft_n", "RMS (10 ms) of 40 Hz high-passed Ft, Fn-weighted over contact units [N]"},
    {"vibration_fn_n", "RMS (10 ms) of 40 Hz high-passed Fn, Fn-weighted over contact units [N]"},
    {"noise_ft_n", "RMS (50 ms) of 40 Hz high-passed Ft over valid units off the contact [N]"},
    {"vibration_over_noise", "vibration_ft_n / max(noise_ft_n, 1 mN) [-]"},
    {"centroid_speed_pitch_s", "speed of the Fn centroid (3 ms low-pass) over 20 ms [unit pitches/s]"},
    {"centroid_drift_pitch", "distance of the Fn centroid from its 0.2 s low-pass [unit pitches]"},
    {"contact_units", "valid units with Fn above 0.15 N [-]"},
    {"valid_fraction", "valid units / units [-]"},
    {"contact_time_s", "time since total_fn_n rose above 0.3 N, at most 2 s [s]"},
    {"fn_over_peak", "total_fn_n over its largest value since contact [-]"},
    {"stale", "1 when the state is stale [-]"},
};

/// Number of features.
inline constexpr size_t kSlipFeatureCount = std::size(kSlipFeatures);

/// Where the units sit on a grid in layout order (unit = row * columns + column): the centroid
/// features need it. The shipped layouts: default_20 has 4 columns, paper_3x3 has 3.
struct SlipFeatureLayout {
  int units = 20;    ///< units in the layout
  int columns = 4;   ///< units per row in layout order
};

/// The grid of the shipped layout with `units` units (20: 4 columns, 9: 3; otherwise one row).
SlipFeatureLayout SlipFeatureLayoutFor(int units);

/// Computes kSlipFeatures tick by tick. Fixed-size state, no allocation after construction.
class SlipFeatureExtractor {
 public:
  /// `tick_period_s` [s]: the control period the filters are designed for (1 ms at 1 kHz).
  /// @throws std::invalid_argument for a period <= 0 or a layout outside 1..kMaxUnits units.
  SlipFeatureExtractor(const SlipFeatureLayout& layout, double tick_period_s);

  /// Forgets everything (a new grasp, a new run).
  void Reset();
  /// One control tick with the newest state at `time_s` [s]; writes kSlipFeatureCount values into
  /// `features` (its size must be at least that). Allocates nothing.
  void Update(const sensor::TactileState& state, double time_s, std::span<double> features);

  const SlipFeatureLayout& layout() const { return layout_; }
  double tick_period_s() const { return tick_period_s_; }

 private:
  /// Longest delay the rate and speed features look back [ticks].
  static constexpr int kMaxDelayTicks = 64;
  struct Centroid {
    double row = 0.0;
    double column = 0.0;
  };

  /// The vibration statistics of this tick: Fn-weighted contact Ft and Fn energy, off-contact Ft.
  void UpdateVibration(const sensor::TactileState& state, double total_fn_n, double* features);
  /// Centroid speed and drift.
  void UpdateCentroid(const sensor::TactileState& state, double total_fn_n, double* features);

  SlipFeatureLayout layout_;
  double tick_period_s_;
  int delay_ticks_ = 10;           ///< 10 ms [ticks]
  int centroid_delay_ticks_ = 20;  ///< 20 ms [ticks]

  LowPassFilter ratio_fast_, ratio_slow_, fn_lp_, shear_lp_;
  LowPassFilter vibration_ft_, vibration_fn_, noise_ft_;
  LowPassFilter centroid_row_, centroid_column_, centroid_row_slow_, centroid_column_slow_;
  std::array<HighPassBiquad, sensor::kMaxUnits> ft_highpass_{}, fn_highpass_{};
  std::array<bool, sensor::kMaxUnits> primed_{};
  DelayLine<double, kMaxDelayTicks> ratio_history_, fn_history_, shear_history_;
  DelayLine<Centroid, kMaxDelayTicks> centroid_history_;
  double contact_start_s_ = -1.0;
  double peak_fn_n_ = 0.0;
};

}  // namespace graspbed::controller
