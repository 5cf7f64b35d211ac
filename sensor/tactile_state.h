#pragma once
/// TactileState: per-unit forces estimated from one RawFrame, the only thing controllers see.

#include <array>
#include <cstdint>

#include "sensor/raw_frame.h"

namespace graspbed::sensor {

/// Why a unit's estimate can or cannot be used.
enum class UnitValidity : uint8_t {
  kValid = 0,
  kOpen,         ///< a channel reads open circuit
  kShort,        ///< a channel reads short circuit
  kOutOfRange,   ///< estimate beyond the rated range (saturated)
  kImplausible,  ///< resistance physically implausible (e.g. far from R0, inconsistent pair)
  kNotTared,     ///< no baseline yet
};

/// Human-readable name of a validity value ("valid", "open", ...). Inline: this header is part of
/// the controller API, which plugins compile against without linking graspbed.
inline const char* ToString(UnitValidity validity) {
  switch (validity) {
    case UnitValidity::kValid:
      return "valid";
    case UnitValidity::kOpen:
      return "open";
    case UnitValidity::kShort:
      return "short";
    case UnitValidity::kOutOfRange:
      return "out_of_range";
    case UnitValidity::kImplausible:
      return "implausible";
    case UnitValidity::kNotTared:
      return "not_tared";
  }
  return "unknown";
}

/// Forces estimated for every unit at one sample time.
struct TactileState {
  uint32_t sequence = 0;  ///< sequence number of the RawFrame this came from
  double time_s = 0.0;    ///< sample time of that frame [s]
  int unit_count = 0;
  bool stale = false;  ///< true when no new frame arrived within the stale timeout
  std::array<double, kMaxUnits>
      fn_n{};  ///< normal force per unit, + pressing into the holder [N], unit frame
  std::array<double, kMaxUnits> ft_n{};  ///< shear per unit along its beam axis [N], unit frame
  std::array<UnitValidity, kMaxUnits> validity{};
  int valid_count = 0;      ///< units with validity == kValid
  double total_fn_n = 0.0;  ///< sum of fn over valid units [N]
  /// Sum of ft over valid units whose beam runs along the holder axis [N], holder frame (+x distal).
  double total_shear_axial_n = 0.0;
  /// Sum of ft over valid units whose beam runs around the circumference [N] (+ towards holder +y).
  double total_shear_circumferential_n = 0.0;
  /// Units with fn above the inversion's contact threshold.
  int contact_count = 0;

  /// Channel noise measured by the readout during its last tare (unit unloaded and still), so a
  /// controller can scale its thresholds to the signal it actually has. False until a tare has
  /// finished (and after a stored baseline, which carries no noise figure).
  bool noise_known = false;
  /// Which readout tare the noise arrays come from (ReadoutFrame::noise_generation): the inversion
  /// converts them only when it changes.
  uint32_t noise_generation = 0;
  /// Standard deviation of R1 and R2 per unit over the tare, a straight-line drift removed [Ohm].
  std::array<double, kMaxUnits> r1_noise_ohm{};
  std::array<double, kMaxUnits> r2_noise_ohm{};
  /// The same noise through the inversion (paper eq. 4 with this unit's calibration): standard
  /// deviation of fn and ft at rest [N]. 0 for a channel the ADC resolves without flicker: use a
  /// floor (e.g. one ADC step through the inversion) before dividing by it.
  std::array<double, kMaxUnits> fn_noise_n{};
  std::array<double, kMaxUnits> ft_noise_n{};
};

}  // namespace graspbed::sensor
