#pragma once
/// Checks of a simulated scene's starting state that no YAML loader can make, because they need the
/// generated model: bodies that start inside each other. Independent of how the hand is built: the
/// object is the body "object", the table any world geom (table_geom), the hand every other body.

#include "sim/simulation.h"

namespace graspbed::sim {

/// Deepest overlap allowed between two bodies in the starting state [m]: 0.1 mm, well below any
/// geometric clearance a scene is built with and above floating-point noise of touching geoms.
inline constexpr double kMaxInitialPenetrationM = 1e-4;

/// Throws std::invalid_argument when, in `simulation`'s current (starting) state, the object and a
/// hand geom, the hand and the table, or the object and the table overlap by more than
/// kMaxInitialPenetrationM. The message names the overlap in mm, the geoms, and the scene keys
/// that set the positions (e.g. object.size_m and hand.open_gap_m for an object wider than the
/// pre-shape). Reads the contacts of the last mj_forward/mj_step; allocates only to throw.
void CheckInitialPenetration(const Simulation& simulation);

}  // namespace graspbed::sim
