#pragma once
/// Inversion (paper eq. 4 with per-unit calibration): ReadoutFrame -> TactileState. Same code for
/// simulated and hardware frames; never sees ground truth. Invert() allocates nothing.

#include <array>
#include <vector>

#include "common/field_table.h"
#include "common/yaml_map.h"
#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "sensor/readout.h"
#include "sensor/tactile_state.h"

namespace graspbed::sensor {

/// Inversion settings.
struct InversionConfig {
  /// A valid unit with Fn above this counts as in contact [N].
  double contact_threshold_n = 0.05;
  /// Rated range of Fn and |Ft| [N] (paper: 10 N).
  double rated_force_n = 10;
  /// An estimate beyond rated_force_n x (1 + margin) is marked out of range [-]; the margin keeps
  /// noise at exactly the rated load from flickering the flag.
  double out_of_range_margin_fraction = 0.05;

  /// Checks every field against InversionConfigFields().
  /// @throws common::ConfigError "inversion.KEY = VALUE: reason".
  void Validate() const;
};

/// The fields of InversionConfig (loader, Validate(), emitter and reference table derive from it).
const common::FieldTable<InversionConfig>& InversionConfigFields();

/// Reads an InversionConfig from its own YAML section (field names as keys; unknown keys refused).
/// @throws common::ConfigError naming file, line, key and value.
InversionConfig LoadInversionConfig(const common::YamlMap& map);

/// Fn and Ft of one unit [N], unit frame.
struct UnitForces {
  double fn_n = 0.0;
  double ft_n = 0.0;
};

/// Eq. 4 for one unit: Fn = (dR1/R1 + dR2/R2) / (2 G kn) - fn_offset, Ft likewise with kt.
UnitForces InvertUnit(const UnitCalibration& calibration, double dr1_rel, double dr2_rel);

/// Per-unit forces and totals over valid units.
class Inversion {
 public:
  /// Throws std::invalid_argument when the calibration's unit count differs from the layout's or
  /// a sensitivity is not > 0.
  Inversion(const Layout& layout, const Calibration& calibration, const InversionConfig& config);

  /// Fills `state` from `frame` (sequence, time, per-unit forces and validity, totals); forces of
  /// invalid units are 0 except out-of-range ones, which keep their estimate (not in the totals).
  /// `state->stale` is left as it was (the loop owns it).
  void Invert(const ReadoutFrame& frame, TactileState* state) const;

  int unit_count() const { return unit_count_; }
  const InversionConfig& config() const { return config_; }

 private:
  InversionConfig config_;
  int unit_count_ = 0;
  std::array<UnitCalibration, kMaxUnits> calibration_{};
  std::array<BeamOrientation, kMaxUnits> orientation_{};
  // +1 or -1: the sign that turns a unit's Ft into the holder-frame total it contributes to
  // (axial: +x; circumferential: +y side of the tangent).
  std::array<double, kMaxUnits> total_sign_{};
};

}  // namespace graspbed::sensor
