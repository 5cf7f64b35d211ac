#include "sim/physics_checks.h"

#include <algorithm>

#include <mujoco/mujoco.h>

#include <array>
#include <cmath>

#include "sim/simulation.h"

namespace graspbed::sim {
namespace {

constexpr double kPinchEffort = 0.5;  // half of the 20 N stall pinch

// The object pinched at half effort in zero gravity, no table: the only tangential load is the
// external force a check applies.
SceneConfig FloatingPinchScene(SceneConfig scene) {
  scene.physics.gravity_m_s2 = 0.0;
  scene.physics.table = false;
  scene.object.initial_position_m = {0.0, 0.0, 0.04};
  return scene;
}

void PinchAndBrake(Simulation& simulation) {
  simulation.SetGripEffort(kPinchEffort);
  simulation.StepUntil(1.0);
  // Brakes on: the digits hold their posture, so the squeeze stays what it is while the object is
  // loaded along the pad (a back-drivable finger would otherwise yield to the pull and change the
  // normal force; that is the hand's behaviour, not the contact's).
  simulation.SetGripBrake(true);
  simulation.StepUntil(1.2);
}

// Object position relative to the holder along world z [m].
double ObjectAlongPad(const Simulation& simulation) {
  const mjModel* m = simulation.model();
  const mjData* d = simulation.data();
  return d->xpos[3 * mj_name2id(m, mjOBJ_BODY, "object") + 2] -
         d->xpos[3 * mj_name2id(m, mjOBJ_BODY, "holder") + 2];
}

// Coulomb's limit of the pinch: friction x the normal force of both digits [N].
double CoulombLimitN(const Simulation& simulation) {
  const GroundTruth truth = simulation.truth();
  return simulation.scene().object.friction * (truth.finger_normal_force_n + truth.thumb_normal_force_n);
}

}  // namespace

CreepCheck MeasureCreep(const sensor::Layout& layout, const SceneConfig& scene) {
  Simulation simulation(layout, FloatingPinchScene(scene));
  PinchAndBrake(simulation);
  // A steady load of half Coulomb's limit along the pad, as a held weight would be.
  simulation.SetObjectExternalForce({0.0, 0.0, -0.5 * CoulombLimitN(simulation)});
  simulation.StepUntil(simulation.time_s() + 0.3);  // the contact takes up the load
  const double start = ObjectAlongPad(simulation);
  const double t0 = simulation.time_s();
  double slip_speed_sum = 0.0;
  double max_share = 0.0;
  int steps = 0;
  while (simulation.time_s() < t0 + 2.0 && !simulation.fault().occurred) {
    simulation.Step();
    const GroundTruth truth = simulation.truth();
    slip_speed_sum += truth.mean_slip_speed_m_s;
    max_share = std::max(max_share, truth.sliding_load_share);
    ++steps;
  }
  CreepCheck check;
  check.max_sliding_load_share = max_share;
  check.drift_m_s = std::abs(ObjectAlongPad(simulation) - start) / (simulation.time_s() - t0);
  check.contact_slip_m_s = steps > 0 ? slip_speed_sum / steps : 0.0;
  check.fault = simulation.fault().occurred;
  return check;
}

SlipOnsetCheck MeasureSlipOnset(const sensor::Layout& layout, const SceneConfig& scene) {
  // Slip starts when the object leaves the pad at 1 mm/s; at that instant the pull is compared with
  // friction x the normal force of both digits then (a tilted pad wedges the object a little and
  // raises the normal force while it is pulled, so the limit is taken when it matters).
  Simulation simulation(layout, FloatingPinchScene(scene));
  PinchAndBrake(simulation);
  const double initial_limit = CoulombLimitN(simulation);
  const double t0 = simulation.time_s();
  constexpr double kRampS = 2.0;
  constexpr double kWindowS = 0.01;  // speed over 10 ms: the contact's elastic take-up is not slip
  constexpr double kSlipSpeedM_S = 1e-3;
  double window_start_position = ObjectAlongPad(simulation);
  double window_start_s = t0;
  while (simulation.time_s() < t0 + kRampS && !simulation.fault().occurred) {
    const double pull = 2.0 * initial_limit * (simulation.time_s() - t0) / kRampS;
    simulation.SetObjectExternalForce({0.0, 0.0, -pull});
    simulation.Step();
    if (simulation.time_s() - window_start_s < kWindowS) continue;
    const double now = ObjectAlongPad(simulation);
    const double speed = std::abs(now - window_start_position) / (simulation.time_s() - window_start_s);
    window_start_position = now;
    window_start_s = simulation.time_s();
    if (speed > kSlipSpeedM_S) {
      const GroundTruth& truth = simulation.truth();
      return {pull / CoulombLimitN(simulation), truth.sliding_load_share, truth.sliding_speed_m_s,
              truth.finger_sliding_speed_m_s, truth.thumb_sliding_speed_m_s};
    }
  }
  return {};
}

PinchCheck MeasurePinch(const sensor::Layout& layout, const SceneConfig& scene, double settle_s,
                        double average_s) {
  Simulation simulation(layout, scene);
  simulation.SetGripEffort(kPinchEffort);
  simulation.StepUntil(settle_s);
  std::array<sensor::UnitLoad, sensor::kMaxUnits> loads{};
  const int units = simulation.unit_count();
  double moment = 0.0;
  double total = 0.0;
  double share_sum = 0.0;
  int steps = 0;
  while (simulation.time_s() < settle_s + average_s && !simulation.fault().occurred) {
    simulation.Step();
    simulation.ComputeUnitLoads({loads.data(), static_cast<size_t>(units)});
    for (int i = 0; i < units; ++i) {
      moment += loads[i].fn_n * layout.units[i].position_m.x();
      total += loads[i].fn_n;
    }
    share_sum += simulation.truth().sensed_share;
    ++steps;
  }
  PinchCheck check;
  check.centroid_axial_m = total > 0.0 ? moment / total : 0.0;
  check.sensed_share = steps > 0 ? share_sum / steps : 0.0;
  check.squeeze_n = simulation.truth().object_squeeze_n;
  check.fault = simulation.fault().occurred;
  return check;
}

}  // namespace graspbed::sim
