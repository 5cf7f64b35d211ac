// EmulatedHand (the simulated hand behind `graspbed emulate`) on the real simulation, driven as the
// emulator's thread drives it: frames before and after the host starts streaming, motor commands,
// the outcome frozen when the host stops. And RigConfigFor, the one scenario-to-rig mapping it
// shares with RunScenario.
#include "testbed/emulated_hand.h"

#include <gtest/gtest.h>

#include "sensor/layout.h"
#include "sim/sim_rig.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed::testbed {
namespace {

constexpr double kFramePeriodS = 0.001;  // the scenario's 1 kHz sensor
// Simulated time moves in physics steps: a frame's target is reached to within one step.
const double kStepS = sim::PhysicsConfig{}.timestep_s;
constexpr int kCloseFrames = 600;  // 0.6 s of closing: the 5 mm gap is long closed and settled
constexpr double kCloseEffort = 0.3;

class EmulatedHandTest : public ::testing::Test {
 protected:
  EmulatedHandTest()
      : config_(LoadScenarioFromString(test_support::HeldBoxScenario(2.0), "held_box.yaml")),
        layout_(sensor::LoadLayout(ResolveLayoutPath(config_))) {}

  sensor::RawFrame EmptyFrame() const {
    sensor::RawFrame frame;
    frame.unit_count = layout_.unit_count();
    return frame;
  }

  ScenarioConfig config_;
  sensor::Layout layout_;
};

TEST_F(EmulatedHandTest, WaitsForTheStreamThenAdvancesOnePeriodPerFrame) {
  EmulatedHand hand(config_, layout_);
  sensor::RawFrame frame = EmptyFrame();
  hand.Frame(false, &frame);
  EXPECT_FALSE(hand.started());
  EXPECT_EQ(hand.sim_time_s(), 0.0) << "simulated time moved before the host streamed";
  // Unloaded gauges before anything was sampled.
  const double r0_ohm = config_.sensor.strain_model.nominal.r0_ohm;
  EXPECT_EQ(frame.r1_ohm[0], r0_ohm);

  for (int k = 0; k < 10; ++k) hand.Frame(true, &frame);
  EXPECT_TRUE(hand.started());
  EXPECT_NEAR(hand.sim_time_s(), 10 * kFramePeriodS, kStepS);
  EXPECT_FALSE(hand.host_done());
}

TEST_F(EmulatedHandTest, TheHostsMotorGraspsAndItsStreamStopFreezesTheOutcome) {
  EmulatedHand hand(config_, layout_);
  sensor::RawFrame frame = EmptyFrame();
  hand.Frame(true, &frame);
  hand.Motor({.grip_effort = kCloseEffort, .enable = true, .brake = false});
  for (int k = 0; k < kCloseFrames; ++k) hand.Frame(true, &frame);
  const nlohmann::json held = hand.Summary();
  EXPECT_NEAR(held.at("host_close_time_s").get<double>(), kFramePeriodS, kStepS);
  EXPECT_TRUE(held.at("metrics").at("grasped").get<bool>()) << held.dump(2);
  EXPECT_GT(held.at("final_squeeze_n").get<double>(), 0.5);
  EXPECT_GT(held.at("finger_contacts").get<int>(), 0);
  // The sensed frame shows the load: some unit's R1 has left its unloaded value.
  double largest_change_ohm = 0.0;
  for (int u = 0; u < frame.unit_count; ++u) {
    largest_change_ohm =
        std::max(largest_change_ohm, std::abs(frame.r1_ohm[u] - config_.sensor.strain_model.nominal.r0_ohm));
  }
  EXPECT_GT(largest_change_ohm, 10.0);
  // Only the host's controller scores its estimates.
  for (const char* key : {"fn_rmse_n", "false_slip_flags", "false_slip_flag_s"}) {
    EXPECT_FALSE(held.at("metrics").contains(key)) << key;
  }

  // The host stops streaming: the outcome is the one it left, however long the device runs on.
  hand.Frame(false, &frame);
  EXPECT_TRUE(hand.host_done());
  const double frozen_s = hand.Summary().at("sim_time_s").get<double>();
  hand.Motor({.grip_effort = -1.0, .enable = true, .brake = false});
  for (int k = 0; k < 100; ++k) hand.Frame(false, &frame);
  EXPECT_EQ(hand.Summary().at("sim_time_s").get<double>(), frozen_s);
}

TEST(RigConfigForTest, MapsTheScenarioOntoTheRig) {
  ScenarioConfig config = LoadScenarioFromString(test_support::HeldBoxScenario(1.0), "held_box.yaml");
  config.sensor.drop_probability = 0.25;
  config.sensor.latency_s = 0.002;
  config.controller.rate_hz = 500.0;
  config.controller.stale_timeout_s = 0.03;
  config.seed = 42;
  const sim::SimRigConfig rig = RigConfigFor(config);
  EXPECT_EQ(rig.backend.drop_probability, 0.25);
  EXPECT_EQ(rig.backend.latency_s, 0.002);
  EXPECT_EQ(rig.backend.max_latency_s, MaxLatencyS(config));
  EXPECT_EQ(rig.backend.sample_rate_hz, config.sensor.sample_rate_hz);
  EXPECT_EQ(rig.control_rate_hz, 500.0);
  EXPECT_EQ(rig.loop.stale_timeout_s, 0.03);
  EXPECT_EQ(rig.loop.readout.baseline_frames, config.sensor.readout.baseline_frames);
  EXPECT_EQ(rig.seed, 42u);
  EXPECT_EQ(rig.scene.object.mass_kg, config.scene.object.mass_kg);
  EXPECT_NO_THROW(rig.Validate());
}

}  // namespace
}  // namespace graspbed::testbed
