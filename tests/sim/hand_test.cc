// The prosthetic hand: its planar kinematics against the generated model, the force coverage of a
// 10 N pinch of each shipped shape, and the load moving over the fingertip with the object's width.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <array>
#include <cmath>
#include <numbers>

#include "sim/hand_kinematics.h"
#include "sim/model_generator.h"
#include "tests/sim/sim_fixture.h"

namespace graspbed::sim {
namespace {

constexpr double kAngleTolRad = 1e-9;
// The generated model carries 8 significant digits; site positions come back within microns.
constexpr double kSiteTolM = 5e-6;
// Half effort of a 20 N stall pinch.
constexpr double kPinchEffort = 0.5;
constexpr double kPinchN = 10.0;
// Force coverage the hand must keep: the sensed share of the fingertip's contact force in a 10 N
// pinch (the jaw fixture's flat pad had 100 %; below 95 % the estimate misses a twentieth of the grip).
constexpr double kMinCoverage = 0.95;
// A 30 mm and a 70 mm box must put the time-averaged load centroid at least half a unit pitch apart
// (the array resolves 5 mm rows), or the flexing finger shows the array nothing new.
constexpr double kMinCentroidShiftM = 2.5e-3;

class HandTest : public test_support::MujocoTest {
 protected:
  static ProstheticKinematics DefaultKinematics(const SceneConfig& scene) {
    const sensor::Layout& layout = DefaultLayout();
    return ProstheticKinematics(scene.hand.finger, scene.hand.thumb, layout.holder.length_m,
                                0.5 * layout.holder.minor_axis_m, layout.unit.mesa_height_m);
  }
  // Pinches the object of `scene` at half effort for `settle_s`, then averages the units' normal
  // loads over `average_s`: the load centroid along the holder axis [m] and the sensed share.
  struct Pinch {
    double centroid_axial_m = 0.0;
    double sensed_share = 0.0;
    double squeeze_n = 0.0;
  };
  Pinch PinchAndAverage(const SceneConfig& scene, double settle_s, double average_s) {
    Simulation& simulation = MakeSimulation(DefaultLayout(), scene);
    simulation.SetGripEffort(kPinchEffort);
    simulation.StepUntil(settle_s);
    std::array<sensor::UnitLoad, sensor::kMaxUnits> loads{};
    const int units = simulation.unit_count();
    double moment = 0.0;
    double total = 0.0;
    double share_sum = 0.0;
    int steps = 0;
    while (simulation.time_s() < settle_s + average_s) {
      simulation.Step();
      simulation.ComputeUnitLoads({loads.data(), static_cast<size_t>(units)});
      for (int i = 0; i < units; ++i) {
        moment += loads[i].fn_n * DefaultLayout().units[i].position_m.x();
        total += loads[i].fn_n;
      }
      share_sum += simulation.truth().sensed_share;
      ++steps;
    }
    Pinch pinch;
    pinch.centroid_axial_m = total > 0.0 ? moment / total : 0.0;
    pinch.sensed_share = share_sum / steps;
    pinch.squeeze_n = simulation.truth().object_squeeze_n;
    return pinch;
  }
};

TEST_F(HandTest, TheNominalPinchMeetsTheObjectSquarelyAtHalfItsWidth) {
  const SceneConfig scene;
  const ProstheticKinematics kin = DefaultKinematics(scene);
  const double half = 0.5 * ProstheticKinematics::kNominalWidthM;
  const double mcp = kin.McpForPadX(-half);
  EXPECT_NEAR(kin.IndexPad(mcp).point_xz.x(), -half, 1e-9);
  EXPECT_NEAR(kin.IndexPad(mcp).normal_angle_rad, 0.0, kAngleTolRad) << "pad square to a vertical face";
  const double thumb = kin.ThumbForTipX(half);
  EXPECT_NEAR(kin.ThumbTip(thumb).point_xz.x(), half, 1e-9);
  EXPECT_NEAR(kin.ThumbTip(thumb).point_xz.y(), kin.IndexPad(mcp).point_xz.y(), 1e-9) << "contacts level";
  // The lever arm is the derivative of the pad's travel: a small MCP step moves the pad by arm x step.
  const double step = 1e-3;
  EXPECT_NEAR(kin.IndexPad(mcp + step).point_xz.x() - kin.IndexPad(mcp).point_xz.x(),
              kin.PadLeverArmM(mcp) * step,
              1e-6 * step + 0.5 * std::abs(kin.PadLeverArmM(mcp + step) - kin.PadLeverArmM(mcp)) * step);
}

TEST_F(HandTest, TheGeneratedModelStandsInThePreShapeTheKinematicsComputed) {
  // The finger_pad and thumb_pad sites of the generated model, at t = 0, are the pre-shape's pad
  // and thumb contact points: the aperture is the configured pre-shape.
  SceneConfig scene;
  scene.object.size_m = {0.04, 0.05, 0.08};
  const HandPlacement place = PlaceHand(DefaultLayout(), scene);
  Simulation& simulation = MakeSimulation(DefaultLayout(), scene);
  const mjModel* m = simulation.model();
  const mjData* d = simulation.data();
  const mjtNum* pad = d->site_xpos + 3 * mj_name2id(m, mjOBJ_SITE, "finger_pad");
  const mjtNum* tip = d->site_xpos + 3 * mj_name2id(m, mjOBJ_SITE, "thumb_pad");
  EXPECT_NEAR(pad[0], -0.5 * place.open_gap_m, kSiteTolM);
  // The thumb site marks the tip's face in the nominal posture; in another it is within the tip's
  // radius x the flexion difference of the contact point.
  EXPECT_NEAR(tip[0], 0.5 * place.open_gap_m, 0.5e-3);
  EXPECT_NEAR(place.open_gap_m, 0.04 + 2.0 * scene.hand.preshape_clearance_m, 1e-12) << "follows the object";
}

TEST_F(HandTest, ATenNewtonPinchOfEachShippedShapeIsSensedByTheMesas) {
  const std::array<std::pair<ObjectShape, std::array<double, 3>>, 3> objects = {{
      {ObjectShape::kBox, {0.05, 0.05, 0.08}},
      {ObjectShape::kCylinder, {0.055, 0.0, 0.09}},
      {ObjectShape::kSphere, {0.045, 0.0, 0.0}},
  }};
  for (const auto& [shape, size] : objects) {
    SceneConfig scene;
    scene.object.shape = shape;
    scene.object.size_m = size;
    const Pinch pinch = PinchAndAverage(scene, 0.8, 0.2);
    EXPECT_GE(pinch.sensed_share, kMinCoverage) << ToString(shape);
    // A 10 N-class pinch: the motors are sized from the kinematics' contact points; a round object
    // meets the thumb elsewhere on its rounded tip, which changes its lever arm (cylinder: +12 %).
    EXPECT_NEAR(pinch.squeeze_n, kPinchN, 0.15 * kPinchN) << ToString(shape);
  }
}

TEST_F(HandTest, TheLoadMovesAlongTheFingertipWithTheObjectsWidth) {
  // Only object.size_m changes: the pre-shape and the pinch follow it, the finger flexes more for
  // the narrow box and less for the wide one, and the pad meets each at another tilt.
  SceneConfig narrow;
  narrow.object.size_m = {0.03, 0.05, 0.08};
  SceneConfig wide;
  wide.object.size_m = {0.07, 0.05, 0.08};
  const Pinch a = PinchAndAverage(narrow, 0.8, 0.4);
  const Pinch b = PinchAndAverage(wide, 0.8, 0.4);
  RecordProperty("centroid_narrow_mm", std::to_string(a.centroid_axial_m * 1e3));
  RecordProperty("centroid_wide_mm", std::to_string(b.centroid_axial_m * 1e3));
  EXPECT_GE(std::abs(a.centroid_axial_m - b.centroid_axial_m), kMinCentroidShiftM)
      << "narrow " << a.centroid_axial_m * 1e3 << " mm, wide " << b.centroid_axial_m * 1e3 << " mm";
  EXPECT_GE(a.sensed_share, kMinCoverage);
  EXPECT_GE(b.sensed_share, kMinCoverage);
}

// Physics stays honest on the flexing finger: a held object does not creep, and it slips where
// Coulomb friction says it must (docs/simulation.md, "Contact and solver parameters").
class FrictionTest : public test_support::MujocoTest {
 protected:
  // A 100 g box pinched at half effort in zero gravity, no table: the only tangential load is the
  // external force a test applies.
  Simulation& Pinched() {
    SceneConfig scene;
    scene.physics.gravity_m_s2 = 0.0;
    scene.physics.table = false;
    scene.object.initial_position_m = {0.0, 0.0, 0.04};
    Simulation& simulation = MakeSimulation(DefaultLayout(), scene);
    simulation.SetGripEffort(kPinchEffort);
    simulation.StepUntil(1.0);
    // Brakes on: the digits hold their posture, so the squeeze stays what it is while the object is
    // loaded along the pad (a back-drivable finger would otherwise yield to the pull and change
    // the normal force; that is the hand's behaviour, not the contact's).
    simulation.SetGripBrake(true);
    simulation.StepUntil(1.2);
    return simulation;
  }
  // Object position relative to the holder along world z [m].
  static double ObjectAlongPad(const Simulation& simulation) {
    const mjModel* m = simulation.model();
    const mjData* d = simulation.data();
    return d->xpos[3 * mj_name2id(m, mjOBJ_BODY, "object") + 2] -
           d->xpos[3 * mj_name2id(m, mjOBJ_BODY, "holder") + 2];
  }
  // Coulomb's limit of the pinch: friction x the normal force of both digits [N].
  static double CoulombLimitN(const Simulation& simulation) {
    const GroundTruth truth = simulation.truth();
    return simulation.scene().object.friction * (truth.finger_normal_force_n + truth.thumb_normal_force_n);
  }
  // Slides the object along the pad with `fraction` x Coulomb's limit for `duration_s`: distance [m].
  double SlideUnder(double fraction, double duration_s) {
    Simulation& simulation = Pinched();
    const double limit = CoulombLimitN(simulation);
    const double start = ObjectAlongPad(simulation);
    simulation.SetObjectExternalForce({0.0, 0.0, -fraction * limit});
    simulation.StepUntil(simulation.time_s() + duration_s);
    return std::abs(ObjectAlongPad(simulation) - start);
  }
};

// Residual creep allowed in a static hold: 1 mm in 200 s, far below the 0.5 mm/s the metrics count.
constexpr double kMaxCreepM_S = 5e-6;
// Slip must start within 5 % of Coulomb's limit, the contact model's promise (docs/simulation.md).
constexpr double kCoulombBand = 0.05;

TEST_F(FrictionTest, AHeldObjectDoesNotCreep) {
  Simulation& simulation = Pinched();
  // A steady load of half Coulomb's limit along the pad, as a held weight would be.
  simulation.SetObjectExternalForce({0.0, 0.0, -0.5 * CoulombLimitN(simulation)});
  simulation.StepUntil(simulation.time_s() + 0.3);  // the contact takes up the load
  const double start = ObjectAlongPad(simulation);
  const double t0 = simulation.time_s();
  double slip_speed_sum = 0.0;
  int steps = 0;
  while (simulation.time_s() < t0 + 2.0) {
    simulation.Step();
    slip_speed_sum += simulation.truth().mean_slip_speed_m_s;
    ++steps;
  }
  // Both ways: the object's drift along the pad and the contacts' mean relative speed.
  const double drift = std::abs(ObjectAlongPad(simulation) - start) / (simulation.time_s() - t0);
  RecordProperty("creep_um_s", std::to_string(drift * 1e6));
  EXPECT_LT(drift, kMaxCreepM_S) << drift * 1e6 << " um/s";
  EXPECT_LT(slip_speed_sum / steps, kMaxCreepM_S) << slip_speed_sum / steps * 1e6 << " um/s at the contacts";
}

TEST_F(FrictionTest, TheObjectSlipsWithinFivePercentOfCoulombsLimit) {
  // A pull along the pad that ramps slowly from 0 to twice the pinch's initial Coulomb limit.
  // Slip starts when the object leaves the pad at 1 mm/s; at that instant the pull is compared
  // with friction x the normal force of both digits then (a tilted pad wedges the object a little
  // and raises the normal force while it is pulled, so the limit is taken when it matters).
  Simulation& simulation = Pinched();
  const double initial_limit = CoulombLimitN(simulation);
  const double t0 = simulation.time_s();
  constexpr double kRampS = 2.0;
  constexpr double kWindowS = 0.01;  // speed over 10 ms: the contact's elastic take-up is not slip
  double window_start_position = ObjectAlongPad(simulation);
  double window_start_s = t0;
  double ratio_at_onset = 0.0;
  while (simulation.time_s() < t0 + kRampS) {
    const double pull = 2.0 * initial_limit * (simulation.time_s() - t0) / kRampS;
    simulation.SetObjectExternalForce({0.0, 0.0, -pull});
    simulation.Step();
    if (simulation.time_s() - window_start_s < kWindowS) continue;
    const double now = ObjectAlongPad(simulation);
    const double speed = std::abs(now - window_start_position) / (simulation.time_s() - window_start_s);
    window_start_position = now;
    window_start_s = simulation.time_s();
    if (speed > 1e-3) {
      ratio_at_onset = pull / CoulombLimitN(simulation);
      break;
    }
  }
  ASSERT_GT(ratio_at_onset, 0.0) << "never slipped up to twice the initial limit";
  RecordProperty("ratio_at_onset", std::to_string(ratio_at_onset));
  EXPECT_NEAR(ratio_at_onset, 1.0, kCoulombBand) << "pull / (mu x normal force) at the onset of slip";
}

}  // namespace
}  // namespace graspbed::sim
