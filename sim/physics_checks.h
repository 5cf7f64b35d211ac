#pragma once
/// The contact model's promises, measured: residual creep in a static hold, the onset of slip
/// against Coulomb's limit, and the share of a pinch the mesas sense. The tests assert them on the
/// default physics (tests/sim/hand_test.cc) and bench/sim_bench prints them beside the speed of each
/// physics option, so a faster setting is only taken with its fidelity figures in view.

#include "sensor/layout.h"
#include "sim/scene_config.h"

namespace graspbed::sim {

/// Creep of the object of `scene` (by default the 100 g box) pinched at half effort, brakes on, in
/// zero gravity without the table (the scene's physics and contact parameters otherwise), under a
/// steady pull of half Coulomb's limit along the pad, over 2 s after 0.3 s of take-up.
struct CreepCheck {
  double drift_m_s = 0.0;         ///< the object's drift along the pad, relative to the holder [m/s]
  double contact_slip_m_s = 0.0;  ///< mean relative speed at the finger/thumb contacts [m/s]
  /// Largest GroundTruth::sliding_load_share over the hold: how much of a digit's force was on
  /// contacts at the edge of their friction cone [0..1].
  double max_sliding_load_share = 0.0;
  bool fault = false;  ///< a physics fault ended the check
};
CreepCheck MeasureCreep(const sensor::Layout& layout, const SceneConfig& scene);

/// The same pinch under a pull along the pad ramped from 0 to twice the initial Coulomb limit in
/// 2 s, at the moment the object first moves at > 1 mm/s (speed over 10 ms windows).
struct SlipOnsetCheck {
  /// pull / (friction x both digits' normal force) then; 0 when it never slipped or the physics
  /// faulted.
  double ratio = 0.0;
  /// GroundTruth::sliding_load_share then: the share of a digit's force on sliding contacts [0..1].
  double sliding_load_share = 0.0;
  /// GroundTruth::sliding_speed_m_s and its per-digit parts then [m/s].
  double sliding_speed_m_s = 0.0;
  double finger_sliding_speed_m_s = 0.0;
  double thumb_sliding_speed_m_s = 0.0;
};
SlipOnsetCheck MeasureSlipOnset(const sensor::Layout& layout, const SceneConfig& scene);

/// A pinch at half effort (10 N on the default motors) of `object`, settled for `settle_s` and
/// averaged over `average_s`.
struct PinchCheck {
  double sensed_share = 0.0;      ///< mean sensed / holder normal force [0..1]
  double centroid_axial_m = 0.0;  ///< normal-load centroid along the holder axis, holder frame [m]
  double squeeze_n = 0.0;         ///< squeeze on the object at the end [N]
  bool fault = false;
};
PinchCheck MeasurePinch(const sensor::Layout& layout, const SceneConfig& scene, double settle_s,
                        double average_s);

}  // namespace graspbed::sim
