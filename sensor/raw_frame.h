#pragma once
/// RawFrame: one sample of every unit's two gauge resistances, exactly what the readout electronics
/// deliver (docs/protocol.md, TACTILE_FRAME). Simulated and hardware backends both produce it.

#include <array>
#include <cstdint>
#include <limits>

namespace graspbed::sensor {

/// Most units a frame can carry (docs/protocol.md: the unit count field is 1..64). Frames are
/// fixed-size so the per-frame path never allocates.
inline constexpr int kMaxUnits = 64;

/// Resistance value that means "open circuit, no reading" [Ohm].
inline constexpr double kOpenCircuitOhm = std::numeric_limits<double>::infinity();
/// Resistance value that means "short circuit" [Ohm].
inline constexpr double kShortCircuitOhm = 0.0;

/// Frame-level flags (docs/protocol.md, TACTILE_FRAME byte 9).
enum FrameFlag : uint8_t {
  kFrameAdcOverrun = 1u << 0,
  kFrameSupplyFault = 1u << 1,
};

/// One sample of all units. Values are what the ADC reports, never ground truth.
struct RawFrame {
  uint32_t sequence = 0;                   ///< +1 per frame from the source, wraps at 2^16 on the wire
  double time_s = 0.0;                     ///< sample time on the source's clock [s]
  int unit_count = 0;                      ///< number of valid entries in r1_ohm/r2_ohm
  uint8_t flags = 0;                       ///< FrameFlag bits
  std::array<double, kMaxUnits> r1_ohm{};  ///< R1 per unit in layout order [Ohm]; inf = open, 0 = short
  std::array<double, kMaxUnits> r2_ohm{};  ///< R2 per unit in layout order [Ohm]; inf = open, 0 = short
};

}  // namespace graspbed::sensor
