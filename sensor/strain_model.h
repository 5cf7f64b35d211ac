#pragma once
/// The forward model of the sensing units (paper eqs. 1-3): per-unit loads -> strains -> R1/R2, with
/// the non-ideal effects of real hardware as seeded, switchable options. Used by the simulated
/// backend; the readout downstream never sees anything but the RawFrame it produces.

#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include "sensor/layout.h"
#include "sensor/raw_frame.h"

namespace graspbed::sensor {

/// Load on one unit's mesa, resolved in the unit frame.
struct UnitLoad {
  double fn_n = 0.0;            ///< normal force along the inward normal, + pressing in [N]
  double ft_n = 0.0;            ///< shear along the beam axis [N]
  double cross_shear_n = 0.0;   ///< shear across the beam axis (normal x beam) [N]
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

}  // namespace graspbed::sensor
