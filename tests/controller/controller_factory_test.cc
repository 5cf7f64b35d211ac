#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>
#include <set>
#include <stdexcept>
#include <string>

#include "controller/grasp_controller.h"
#include "controller/grip_slip_controller.h"
#include "controller/open_loop_controller.h"
#include "tests/support/allocation_counter.h"
#include "tests/controller/synthetic_tactile.h"
#include "tests/support/error_of.h"

namespace graspbed::controller {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;

// The errors refused here are std::invalid_argument; one of another type fails the test.
std::string ErrorOf(const std::function<void()>& action) {
  return graspbed::test_support::ErrorOf<std::invalid_argument>(action);
}

TEST(ControllerFactoryTest, KnowsGripSlipOpenLoopAndConstantGrip) {
  EXPECT_THAT(ControllerNames(), Contains("grip_slip"));
  EXPECT_THAT(ControllerNames(), Contains("open_loop"));
  EXPECT_THAT(ControllerNames(), Contains("constant_grip"));
  EXPECT_EQ(MakeController("grip_slip", {})->name(), "grip_slip");
  EXPECT_EQ(MakeController("constant_grip", {{"grip_n", 3.0}})->name(), "constant_grip");
  EXPECT_THAT(ErrorOf([] { MakeController("grip_slap", {}); }),
              HasSubstr("unknown controller 'grip_slap'; valid controllers: constant_grip, grip_slip, learned_slip, open_loop"));
  EXPECT_THAT(ErrorOf([] { MakeController("constant_grip", {{"grip_n", -1.0}}); }),
              HasSubstr("grip_n = -1: must be in [0.01, 500] N"));
  EXPECT_THAT(ErrorOf([] { MakeController("constant_grip", {{"contact_confirm_frames", 2.5}}); }),
              HasSubstr("contact_confirm_frames = 2.5: must be a whole number"));
}

TEST(ControllerFactoryTest, GripSlipParametersAreDeclaredWithDefaultsFromTheConfig) {
  const std::vector<ControllerParameter> parameters = ControllerParameters("grip_slip");
  const GripSlipConfig defaults;
  std::set<std::string> names;
  for (const ControllerParameter& parameter : parameters) {
    EXPECT_TRUE(names.insert(parameter.name).second) << "declared twice: " << parameter.name;
    EXPECT_FALSE(parameter.doc.empty()) << parameter.name;
    EXPECT_LE(parameter.min, parameter.default_value) << parameter.name;
    EXPECT_GE(parameter.max, parameter.default_value) << parameter.name;
  }
  EXPECT_GE(parameters.size(), 40u);
  const auto value_of = [&](const std::string& name) {
    for (const ControllerParameter& parameter : parameters) {
      if (parameter.name == name) return parameter.default_value;
    }
    ADD_FAILURE() << "not declared: " << name;
    return 0.0;
  };
  EXPECT_DOUBLE_EQ(value_of("max_grip_n"), defaults.max_grip_n);
  EXPECT_DOUBLE_EQ(value_of("safety_margin"), defaults.safety_margin);
  EXPECT_DOUBLE_EQ(value_of("vibration_factor"), defaults.slip.vibration_factor);
  EXPECT_DOUBLE_EQ(value_of("grid_columns"), 4.0);
  EXPECT_DOUBLE_EQ(value_of("even_units_axial"), 1.0);
}

TEST(ControllerFactoryTest, ParametersReachTheController) {
  const GripSlipConfig config = GripSlipController::ConfigFromParams(
      {{"max_grip_n", 8.0}, {"grid_columns", 3.0}, {"vibration_detector", 0.0}, {"safety_margin", 2.0}});
  EXPECT_DOUBLE_EQ(config.max_grip_n, 8.0);
  EXPECT_EQ(config.slip.grid_columns, 3);
  EXPECT_FALSE(config.slip.vibration_enabled);
  EXPECT_DOUBLE_EQ(config.safety_margin, 2.0);
  EXPECT_DOUBLE_EQ(config.min_grip_n, GripSlipConfig{}.min_grip_n);
}

TEST(ControllerFactoryTest, UnknownParameterIsNamed) {
  EXPECT_THAT(
      ErrorOf([] {
        MakeController("grip_slip", {{"safety_margn", 1.5}});
      }),
      HasSubstr("controller 'grip_slip': safety_margn: no such parameter; valid parameters: close_effort"));
}

TEST(ControllerFactoryTest, OutOfRangeParameterNamesValueAndRange) {
  EXPECT_THAT(ErrorOf([] {
                MakeController("grip_slip", {{"safety_margin", 0.5}});
              }),
              HasSubstr("controller 'grip_slip': safety_margin = 0.5: must be in [1, 5]"));
  EXPECT_THAT(ErrorOf([] {
                MakeController("grip_slip", {{"max_grip_n", -3.0}});
              }),
              HasSubstr("controller 'grip_slip': max_grip_n = -3: must be in [0.1, 200] N"));
}

TEST(ControllerFactoryTest, CountsMustBeWholeNumbers) {
  EXPECT_THAT(ErrorOf([] {
                MakeController("grip_slip", {{"grid_columns", 2.5}});
              }),
              HasSubstr("controller 'grip_slip': grid_columns = 2.5: must be a whole number"));
  EXPECT_THAT(ErrorOf([] {
                MakeController("grip_slip", {{"ratio_detector", 0.5}});
              }),
              HasSubstr("controller 'grip_slip': ratio_detector = 0.5: must be a whole number"));
}

TEST(ControllerFactoryTest, InconsistentParametersAreRejected) {
  EXPECT_THAT(ErrorOf([] {
                MakeController("grip_slip", {{"min_grip_n", 5.0}, {"max_grip_n", 3.0}});
              }),
              HasSubstr("controller 'grip_slip': min_grip_n = 5: must not exceed max_grip_n"));
  EXPECT_THAT(ErrorOf([] {
                MakeController("grip_slip", {{"friction_min", 0.6}});
              }),
              HasSubstr("controller 'grip_slip': friction_min = 0.6: must not exceed friction_initial"));
  EXPECT_THAT(ErrorOf([] {
                MakeController("grip_slip", {{"centroid_window_s", 0.5}, {"sample_rate_hz", 2000}});
              }),
              HasSubstr("centroid_window_s = 0.5: must span 1 to 511 frames"));
}

TEST(ControllerFactoryTest, GripSlipUpdateAllocatesNothing) {
  std::unique_ptr<GraspController> controller = MakeController("grip_slip", {});
  test_support::SyntheticTactile sensor({});
  test_support::HandPlant plant({});
  // Frames made up front: the generator itself may allocate, the controller may not.
  std::vector<sensor::TactileState> frames;
  std::vector<double> loads;
  for (int i = 0; i < 3000; ++i) loads.push_back(i < 2000 ? 0.5 : 2.5);  // ends in a slip
  controller->SetIntent(GraspIntent::kClose);
  hand::HandCommand command;
  long allocations = 0;
  for (int i = 0; i < 3000; ++i) {
    const double t = (i + 1) * 1e-3;
    plant.Step(command, loads[static_cast<size_t>(i)], 1e-3);
    sensor::TactileState state = sensor.Frame(plant.Contact(), t);
    if (i >= 2500 && i < 2600) state.stale = true;
    const long before = graspbed::test_support::AllocationCount();
    command = controller->Update(state, {}, t);
    allocations += graspbed::test_support::AllocationCount() - before;
  }
  EXPECT_GT(controller->telemetry().slip_events, 0) << "the run should have exercised the slip path";
  EXPECT_EQ(allocations, 0);
}

TEST(OpenLoopControllerTest, FixedEffortsBlindToTheSensor) {
  std::unique_ptr<GraspController> controller = MakeController("open_loop", {{"close_effort", 0.4}});
  test_support::SyntheticTactile sensor({});
  test_support::SyntheticContact contact;
  contact.grip_n = 5.0;
  contact.load_axial_n = 4.0;  // slipping by any measure; the baseline cannot tell
  EXPECT_DOUBLE_EQ(controller->Update(sensor.Frame(contact, 0.001), {}, 0.001).grip_effort, 0.0);
  controller->SetIntent(GraspIntent::kClose);
  EXPECT_DOUBLE_EQ(controller->Update(sensor.Frame(contact, 0.002), {}, 0.002).grip_effort, 0.4);
  EXPECT_FALSE(controller->telemetry().slip_detected);
  controller->SetIntent(GraspIntent::kOpen);
  EXPECT_DOUBLE_EQ(controller->Update(sensor.Frame(contact, 0.003), {}, 0.003).grip_effort, -0.5);
}

}  // namespace
}  // namespace graspbed::controller
