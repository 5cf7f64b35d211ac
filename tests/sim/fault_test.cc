// Physics failures are values: a NaN or a MuJoCo warning is reported with time and cause, the
// physics stops there, nothing crashes.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <limits>
#include <string>

#include "tests/sim/sim_fixture.h"

namespace graspbed::sim {
namespace {

class FaultTest : public test_support::MujocoTest {};

TEST_F(FaultTest, NanVelocityIsReportedWithTimeAndCause) {
  Simulation& simulation = MakeSimulation(DefaultLayout(), SceneConfig{});
  ExpectFault(simulation);
  simulation.StepUntil(0.05);
  EXPECT_FALSE(simulation.fault().occurred);
  const double fault_time = simulation.time_s();
  simulation.mutable_data()->qvel[0] = std::numeric_limits<double>::quiet_NaN();
  simulation.Step();
  ASSERT_TRUE(simulation.fault().occurred);
  EXPECT_NEAR(simulation.fault().time_s, fault_time, 2 * simulation.timestep_s());
  const std::string cause = simulation.fault().cause_text();
  EXPECT_NE(cause.find("MuJoCo warning"), std::string::npos) << cause;
  EXPECT_NE(cause.find("QVEL"), std::string::npos) << cause;
  EXPECT_GE(simulation.fault().warning_count, 1u);
  // MuJoCo reset the state; the physics stops at the fault (StepUntil returns at once) and the first
  // fault is kept.
  simulation.StepUntil(0.1);
  EXPECT_TRUE(std::isfinite(simulation.truth().object_position_m[2]));
  EXPECT_NEAR(simulation.fault().time_s, fault_time, 2 * simulation.timestep_s());
}

TEST_F(FaultTest, ContactOverflowIsReported) {
  Simulation& simulation = MakeSimulation(DefaultLayout(), SceneConfig{});
  ExpectFault(simulation);
  // Shrink the contact buffer below what a pinch needs: MuJoCo warns, the run survives.
  simulation.SetGripEffort(0.5);
  simulation.mutable_model()->nconmax = 2;
  simulation.StepUntil(1.0);
  ASSERT_TRUE(simulation.fault().occurred);
  EXPECT_NE(std::string(simulation.fault().cause_text()).find("contact"), std::string::npos)
      << simulation.fault().cause_text();
}

TEST_F(FaultTest, BadScriptValuesAreRefused) {
  Simulation& simulation = MakeSimulation(DefaultLayout(), SceneConfig{});
  EXPECT_THROW(simulation.SetObjectMass(-0.1), std::invalid_argument);
  EXPECT_THROW(simulation.SetObjectFriction(0.0), std::invalid_argument);
  EXPECT_THROW(simulation.SetObjectExternalForce({std::nan(""), 0.0, 0.0}), std::invalid_argument);
  simulation.SetGripEffort(std::nan(""));
  EXPECT_EQ(simulation.grip_effort(), 0.0);
  simulation.SetGripEffort(3.0);
  EXPECT_EQ(simulation.grip_effort(), 1.0);
}

}  // namespace
}  // namespace graspbed::sim
