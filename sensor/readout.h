#pragma once
/// Readout: RawFrame -> relative resistance change dR/R per channel, against a tare baseline, with
/// per-unit validity. Identical for simulated and hardware frames.

#include <array>
#include <cstdint>

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
};

}  // namespace graspbed::sensor
