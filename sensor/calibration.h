#pragma once
/// Per-unit calibration of the force inversion (paper eq. 4 with per-unit constants): the
/// sensitivities and zero offsets the inversion uses, their YAML file, and the least-squares fit
/// that produces them from a log of known loads and readings.
///
/// Model per unit, with s = (dR1/R1 + dR2/R2) / 2 and d = (dR1/R1 - dR2/R2) / 2:
///   s = G kn (Fn + fn_offset),   d = G kt (Ft + ft_offset),
/// so the inversion is Fn = s / (G kn) - fn_offset, Ft = d / (G kt) - ft_offset.

#include <string>
#include <vector>

#include "sensor/strain_model.h"

namespace graspbed::sensor {

/// Constants of one unit's inversion.
struct UnitCalibration {
  double gauge_factor = 100;  ///< G [-]
  double kn_per_n = 5.5e-4;   ///< strain per N of normal force [1/N]
  double kt_per_n = 4.1e-4;   ///< strain per N of shear along the beam [1/N]
  double fn_offset_n = 0;     ///< normal-force reading at zero load [N]
  double ft_offset_n = 0;     ///< shear reading at zero load [N]
};

/// Calibration of every unit, in layout order.
struct Calibration {
  std::vector<UnitCalibration> units;
  int unit_count() const { return static_cast<int>(units.size()); }
};

/// The paper's constants (G = 100, kn = 5.5e-4 /N, kt = 4.1e-4 /N, no offsets) for every unit.
Calibration PaperCalibration(int unit_count);
/// The nominal constants of a strain model (G, kn, kt; no offsets) for every unit: what a host
/// that knows only the datasheet of the sensor inverts with. Equals PaperCalibration for the
/// paper's constants.
Calibration NominalCalibration(const UnitConstants& nominal, int unit_count);

/// Loads a calibration YAML (format in docs/sensor.md); throws common::ConfigError naming file,
/// line and key, including when the file holds a different number of units than expected.
Calibration LoadCalibration(const std::string& path, int expected_unit_count);

/// Writes `calibration` as YAML to `path` via a temporary file and rename, so a reader never sees
/// a half-written file. Throws std::runtime_error when the file cannot be written.
void SaveCalibration(const Calibration& calibration, const std::string& path);

/// One row of a calibration log: a known load on one unit and what the readout saw.
struct CalibrationSample {
  int unit = 0;          ///< layout index
  double fn_n = 0.0;     ///< applied normal force [N]
  double ft_n = 0.0;     ///< applied shear along the beam [N]
  double dr1_rel = 0.0;  ///< dR1/R1 read for that load [-]
  double dr2_rel = 0.0;  ///< dR2/R2 read for that load [-]
  int line = 0;          ///< line in the log file (for messages)
};

/// Quality of the fit of one unit.
struct UnitFitReport {
  int samples = 0;
  double rms_fn_residual_n = 0.0;  ///< RMS of (fitted inversion - applied Fn) over the samples [N]
  double rms_ft_residual_n = 0.0;  ///< same for Ft [N]
  /// Cross-coupling found by the fit: d/s per N of the other load, relative to the direct term [-].
  double fn_from_ft_coupling = 0.0;
  double ft_from_fn_coupling = 0.0;
};

/// Result of a calibration fit.
struct CalibrationFit {
  Calibration calibration;
  std::vector<UnitFitReport> reports;
};

/// Reads a calibration log (CSV; format in docs/sensor.md): header naming the columns unit,
/// fn_n, ft_n and either dr1_rel, dr2_rel or r1_ohm, r2_ohm (resistances are referred to the mean
/// of that unit's zero-load rows). Throws common::ConfigError "file:line: column = value: reason".
std::vector<CalibrationSample> LoadCalibrationLog(const std::string& path, int unit_count);

/// Least-squares fit (Eigen, QR) per unit of s = a Fn + c Ft + b and d = a' Ft + c' Fn + b':
/// kn = a / G, fn_offset = b / a, and so on; the cross terms are fitted so they do not bias the
/// sensitivities and are reported. Every unit needs >= 3 samples with independent Fn and Ft
/// variation (std::invalid_argument otherwise, naming the unit). G is taken as `gauge_factor`.
CalibrationFit FitCalibration(const std::vector<CalibrationSample>& samples, int unit_count,
                              double gauge_factor = 100.0);

}  // namespace graspbed::sensor
