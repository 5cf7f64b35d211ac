// The closed loop on the simulated clock: the open-loop baseline closes on and lifts a box; the
// ground truth's tangential load and required grip of a held object; determinism bit for bit; the
// backend's rate, latency and frame drops; no allocation per step.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "controller/grasp_controller.h"
#include "tests/support/allocation_counter.h"
#include "tests/sim/sim_fixture.h"

namespace graspbed::sim {
namespace {

constexpr double kLiftHeightM = 0.05;
constexpr double kHeightTolM = 0.005;
constexpr double kForceTolN = 0.5;
// Held still, the pinch's tangential load is the weight (measured: 0.981 N of 0.981 N for the box).
constexpr double kWeightRelTol = 0.03;
constexpr double kCloseAtS = 0.15;
constexpr double kTwistNm = 0.02;  // about the vertical: a 0.4 N couple across the 50 mm box

class RigTest : public test_support::MujocoTest {
 protected:
  // Scripted lift: close from t = 0, lift the wrist by kLiftHeightM over 0.5 s from t = 1.5 s.
  static void CloseAndLift(SimRig& rig, double end_s) {
    const std::array<double, 3> start = rig.simulation().wrist_target();
    while (rig.time_s() < end_s) {
      const double t = rig.time_s();
      // Close after the readout's 0.1 s tare, as the scenarios do: the prosthetic finger reaches the
      // object within 0.1 s, and a tare under load would offset every estimate.
      if (t >= kCloseAtS) rig.controller().SetIntent(controller::GraspIntent::kClose);
      std::array<double, 3> target = start;
      target[2] += kLiftHeightM * std::clamp((t - 1.5) / 0.5, 0.0, 1.0);
      rig.simulation().SetWristTarget(target);
      rig.Step();
    }
  }
};

TEST_F(RigTest, OpenLoopBaselineClosesOnAndLiftsABox) {
  SimRig& rig = MakeRig(SimRigConfig{}, "open_loop", {{"close_effort", 0.5}});
  CloseAndLift(rig, 3.0);
  const GroundTruth truth = rig.simulation().truth();
  EXPECT_NEAR(truth.object_height_above_table_m, kLiftHeightM, kHeightTolM);
  EXPECT_NEAR(truth.object_squeeze_n, 10.0, kForceTolN);
  EXPECT_LT(truth.slip_speed_m_s, 1e-4);
  // The controller's view, through the backend, readout and inversion: the units' true normal
  // loads (ideal sensor: to the inversion's rounding), and those carry the whole finger contact.
  const sensor::TactileState& state = rig.loop().state();
  EXPECT_FALSE(state.stale);
  EXPECT_GT(state.contact_count, 0);
  double true_fn = 0.0;
  for (const sensor::UnitLoad& load : rig.backend().last_loads()) true_fn += load.fn_n;
  EXPECT_NEAR(state.total_fn_n, true_fn, 1e-6 * true_fn);
  EXPECT_GT(truth.sensed_share, 0.95);
  EXPECT_EQ(rig.loop().command().grip_effort, 0.5);
}

TEST_F(RigTest, AStillPinchCarriesTheWeightAndItsLoadBoundIsWeightOverTwoMu) {
  // The default object: a 100 g box at friction 0.8, lifted and then held still (no pull, no
  // acceleration), so the pinch carries exactly its weight by friction.
  SimRigConfig config;
  const double mass_kg = config.scene.object.mass_kg;
  const double friction = config.scene.object.friction;
  ASSERT_EQ(config.scene.object.shape, ObjectShape::kBox);
  ASSERT_DOUBLE_EQ(mass_kg, 0.1);
  ASSERT_DOUBLE_EQ(friction, 0.8);
  // The symmetric bench fixture: the share is a property of the ground truth here, not of the hand.
  config.scene.hand.model = HandModel::kJaw;
  config.scene.hand.open_gap_m = 0.065;
  SimRig& rig = MakeRig(config, "open_loop", {{"close_effort", 0.5}});
  CloseAndLift(rig, 3.0);
  const GroundTruth truth = rig.simulation().truth();
  ASSERT_NEAR(truth.object_height_above_table_m, kLiftHeightM, kHeightTolM);
  const double weight_n = mass_kg * config.scene.physics.gravity_m_s2;
  EXPECT_NEAR(truth.object_tangential_load_n, weight_n, kWeightRelTol * weight_n);
  EXPECT_NEAR(truth.object_tangential_force_n[2], weight_n, kWeightRelTol * weight_n);  // holds it up
  EXPECT_NEAR(truth.hand_load_n[2], weight_n, kWeightRelTol * weight_n);
  EXPECT_NEAR(truth.load_bound_grip_n, weight_n / (2.0 * friction), kWeightRelTol * weight_n / (2.0 * friction));
}

TEST_F(RigTest, TheLoadBoundDoesNotGrowWithTheSqueezeOnTheFlexingFinger) {
  // On the prosthetic hand the pads are not antipodal: part of each digit's tangential force comes
  // from the squeeze itself. The net force of the hand does not: twice the squeeze, the same bound.
  SimRigConfig config;
  const double weight_n = config.scene.object.mass_kg * config.scene.physics.gravity_m_s2;
  const double even_share_n = weight_n / (2.0 * config.scene.object.friction);
  double squeeze_n[2] = {0.0, 0.0};
  const double efforts[2] = {0.25, 0.5};
  for (int i = 0; i < 2; ++i) {
    SCOPED_TRACE(efforts[i]);
    SimRig& rig = MakeRig(config, "open_loop", {{"close_effort", efforts[i]}});
    CloseAndLift(rig, 3.0);
    const GroundTruth truth = rig.simulation().truth();
    ASSERT_NEAR(truth.object_height_above_table_m, kLiftHeightM, kHeightTolM);
    squeeze_n[i] = truth.object_squeeze_n;
    EXPECT_NEAR(truth.load_bound_grip_n, even_share_n, kWeightRelTol * even_share_n);
  }
  EXPECT_GT(squeeze_n[1], 1.5 * squeeze_n[0]) << "the premise: the second grip squeezes harder";
}

TEST_F(RigTest, TheTangentialForceIsOnTheObjectWhicheverGeomOfTheContactItIs) {
  // MuJoCo orders a contact's geoms by type, and a cylinder comes before the digits' boxes: the
  // object is geom1, and mj_contactForce's force on geom2 is the digit's share, not the object's.
  SimRigConfig config;
  config.scene.object.shape = ObjectShape::kCylinder;
  config.scene.object.size_m = {0.05, 0.0, 0.08};
  SimRig& rig = MakeRig(config, "open_loop", {{"close_effort", 0.5}});
  CloseAndLift(rig, 3.0);
  const mjModel* m = rig.simulation().model();
  const mjData* d = rig.simulation().data();
  const int object_geom = mj_name2id(m, mjOBJ_GEOM, "object_geom");
  int object_first = 0;
  for (int c = 0; c < d->ncon; ++c) object_first += d->contact[c].geom1 == object_geom ? 1 : 0;
  ASSERT_GT(object_first, 0) << "the premise: MuJoCo put the object first in its contacts";
  const GroundTruth truth = rig.simulation().truth();
  ASSERT_NEAR(truth.object_height_above_table_m, kLiftHeightM, kHeightTolM);
  const double weight_n = config.scene.object.mass_kg * config.scene.physics.gravity_m_s2;
  EXPECT_NEAR(truth.object_tangential_force_n[2], weight_n, kWeightRelTol * weight_n);
}

TEST_F(RigTest, ATwistHeldByACoupleIsCarriedByBothDigitsFriction) {
  // A torque about the vertical on the held box is carried by opposite horizontal friction forces
  // at the finger and the thumb: they cancel in the total (which stays the weight), but each digit
  // must hold its own inside its friction cone.
  SimRigConfig config;
  const double friction = config.scene.object.friction;
  const double lever_m = config.scene.object.size_m[0];  // between the pinched faces
  SimRig& rig = MakeRig(config, "open_loop", {{"close_effort", 0.5}});
  CloseAndLift(rig, 2.5);
  const int object_body = mj_name2id(rig.simulation().model(), mjOBJ_BODY, "object");
  rig.simulation().mutable_data()->xfrc_applied[6 * object_body + 5] = kTwistNm;  // about world z
  rig.AdvanceTo(3.0);  // the wrist stays where the lift left it
  const GroundTruth truth = rig.simulation().truth();
  ASSERT_NEAR(truth.object_height_above_table_m, kLiftHeightM, kHeightTolM);
  const double weight_n = config.scene.object.mass_kg * config.scene.physics.gravity_m_s2;
  const double couple_n = kTwistNm / lever_m;
  EXPECT_NEAR(truth.object_tangential_load_n, weight_n, kWeightRelTol * weight_n);
  // Each digit must hold its share of the couple inside its cone as well: the hand's net force (the
  // load bound's) does not carry a couple, so what a twist needs is the oracle's to find.
  for (const double digit : {truth.finger_normal_force_n, truth.thumb_normal_force_n})
    EXPECT_GE(digit * friction, couple_n * (1.0 - kWeightRelTol));
}

TEST_F(RigTest, SameSeedGivesIdenticalFramesDifferentSeedDoesNot) {
  SimRigConfig config;
  config.backend.strain_model.noise_ohm = 2.0;
  config.backend.strain_model.r0_spread_fraction = 0.01;
  config.seed = 7;
  SimRig& a = MakeRig(config, "open_loop", {{"close_effort", 0.5}});
  SimRig& b = MakeRig(config, "open_loop", {{"close_effort", 0.5}});
  config.seed = 8;
  SimRig& c = MakeRig(config, "open_loop", {{"close_effort", 0.5}});
  for (SimRig* rig : {&a, &b, &c}) rig->controller().SetIntent(controller::GraspIntent::kClose);
  int compared = 0;
  bool seed_differs = false;
  while (a.time_s() < 1.0) {
    const bool ticked = a.Step();
    ASSERT_EQ(ticked, b.Step());
    c.Step();
    if (!ticked) continue;
    const sensor::RawFrame& fa = a.loop().frame();
    const sensor::RawFrame& fb = b.loop().frame();
    ASSERT_EQ(fa.sequence, fb.sequence);
    ASSERT_EQ(std::memcmp(&fa.time_s, &fb.time_s, sizeof(double)), 0);
    ASSERT_EQ(std::memcmp(fa.r1_ohm.data(), fb.r1_ohm.data(), sizeof(double) * fa.unit_count), 0)
        << "t = " << a.time_s();
    ASSERT_EQ(std::memcmp(fa.r2_ohm.data(), fb.r2_ohm.data(), sizeof(double) * fa.unit_count), 0)
        << "t = " << a.time_s();
    const GroundTruth ta = a.simulation().truth();
    const GroundTruth tb = b.simulation().truth();
    ASSERT_EQ(std::memcmp(ta.object_position_m.data(), tb.object_position_m.data(), sizeof(double) * 3), 0);
    if (std::memcmp(fa.r1_ohm.data(), c.loop().frame().r1_ohm.data(), sizeof(double) * fa.unit_count) != 0) {
      seed_differs = true;
    }
    ++compared;
  }
  EXPECT_GE(compared, 999);
  EXPECT_TRUE(seed_differs);
}

TEST_F(RigTest, BackendSamplesAtItsRateWithLatencyAndDrops) {
  SimRigConfig config;
  config.backend.sample_rate_hz = 500.0;
  config.backend.latency_s = 0.004;
  SimRig& rig = MakeRig(config, "open_loop", {{"close_effort", 0.5}});
  SimBackend& backend = rig.backend();
  sensor::RawFrame frame;
  std::vector<uint32_t> sequences;
  std::vector<double> lags;
  rig.simulation().StepUntil(0.0);  // nothing
  while (rig.simulation().time_s() < 0.2) {
    rig.simulation().Step();
    backend.Poll(rig.simulation().time_s());
    if (rig.simulation().time_s() > 0.1 && rig.simulation().time_s() < 0.1005) backend.DropNextFrames(3);
    if (backend.Read(&frame) == sensor::ReadStatus::kOk) {
      sequences.push_back(frame.sequence);
      lags.push_back(rig.simulation().time_s() - frame.time_s);
    }
  }
  ASSERT_GT(sequences.size(), 90u);
  for (double lag : lags) EXPECT_NEAR(lag, 0.004, 1e-6);
  int gaps = 0;
  for (size_t i = 1; i < sequences.size(); ++i) {
    if (sequences[i] != sequences[i - 1] + 1) {
      EXPECT_EQ(sequences[i], sequences[i - 1] + 4);
      ++gaps;
    }
  }
  EXPECT_EQ(gaps, 1);
  EXPECT_EQ(backend.counters().dropped, 3u);
  // 0.2 s at 500 Hz, minus the latency and the drops.
  EXPECT_NEAR(static_cast<double>(sequences.size()), 0.196 * 500 - 3, 2.0);
}

TEST_F(RigTest, AControlLoopFasterThanThePhysicsTicksBetweenStepsOnTheLastStepsState) {
  SimRigConfig config;
  config.scene.physics.timestep_s = 0.002;
  config.scene.object.solref_timeconst_s = 0.004;
  config.control_rate_hz = 1000.0;
  config.backend.sample_rate_hz = 1000.0;
  config.backend.latency_s = 0.0;
  SimRig& rig = MakeRig(config, "open_loop", {{"close_effort", 0.5}});
  rig.controller().SetIntent(controller::GraspIntent::kClose);
  rig.AdvanceTo(0.5);  // closed on the box: the loads change from step to step
  const uint64_t ticks_before = rig.loop().counters().ticks;
  int between_steps = 0;
  int on_steps = 0;
  for (int i = 0; i < 200; ++i) {
    const double physics_before_s = rig.simulation().time_s();
    const sensor::RawFrame previous = rig.loop().frame();
    ASSERT_TRUE(rig.Step()) << "every 1 ms instant is a control tick";
    const sensor::RawFrame& frame = rig.loop().frame();
    EXPECT_EQ(frame.sequence, previous.sequence + 1);
    EXPECT_NEAR(frame.time_s, rig.time_s(), 1e-9);
    EXPECT_NEAR(rig.time_s() - previous.time_s, 0.001, 1e-9);
    if (rig.simulation().time_s() == physics_before_s) {
      // Between physics steps: the clock is 1 ms ahead of the state, the sample is the last step's.
      ++between_steps;
      EXPECT_NEAR(rig.time_s() - rig.simulation().time_s(), 0.001, 1e-9);
      for (int u = 0; u < frame.unit_count; ++u) EXPECT_EQ(frame.r1_ohm[u], previous.r1_ohm[u]) << u;
    } else {
      ++on_steps;
      EXPECT_NEAR(rig.time_s(), rig.simulation().time_s(), 1e-12);
    }
  }
  EXPECT_EQ(between_steps, 100);
  EXPECT_EQ(on_steps, 100);
  EXPECT_EQ(rig.loop().counters().ticks - ticks_before, 200u);
  EXPECT_GT(rig.loop().state().contact_count, 0);
}

TEST_F(RigTest, StepSamplingAndControlAllocateNothing) {
  SimRigConfig config;
  config.backend.strain_model.noise_ohm = 1.0;
  config.backend.latency_s = 0.002;
  SimRig& rig = MakeRig(config, "open_loop", {{"close_effort", 0.5}});
  rig.controller().SetIntent(controller::GraspIntent::kClose);
  rig.AdvanceTo(0.9);  // in contact, tared
  std::vector<sensor::UnitLoad> loads(rig.simulation().unit_count());
  const long before = graspbed::test_support::AllocationCount();
  for (int i = 0; i < 400; ++i) {
    rig.Step();
    rig.simulation().ComputeUnitLoads(loads);
    (void)rig.simulation().truth();
  }
  EXPECT_EQ(graspbed::test_support::AllocationCount() - before, 0);
  EXPECT_GT(rig.loop().state().contact_count, 0);
}

}  // namespace
}  // namespace graspbed::sim
