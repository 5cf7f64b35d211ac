// The constant-grip baseline on a synthetic hand: closes at its closing effort until the units report
// contact, then holds grip_n with its force loop whatever the motor's gain, honours a task ceiling,
// keeps squeezing on stale data and opens on command.
#include "controller/constant_grip_controller.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "controller/grasp_controller.h"

namespace graspbed::controller {
namespace {

constexpr double kTickS = 0.001;
/// The loop settles within a few percent of the target (its integral removes the rest).
constexpr double kGripTolN = 0.02;

/// A hand whose digits touch the object once closed far enough, then press with gain x effort: the
/// force loop must find the effort whatever the gain (the object's stiffness, the motor's strength).
class SyntheticHand {
 public:
  explicit SyntheticHand(double newtons_per_effort) : gain_(newtons_per_effort) {}

  /// One tick: moves with the last command, returns the frame the units report.
  sensor::TactileState Step(const hand::HandCommand& command, bool stale = false) {
    closure_ = std::clamp(closure_ + command.grip_effort * kTickS * 10.0, 0.0, 1.0);
    sensor::TactileState state;
    state.sequence = ++sequence_;
    state.time_s = sequence_ * kTickS;
    state.unit_count = 20;
    state.valid_count = 20;
    state.stale = stale;
    state.total_fn_n = closure_ >= 0.5 ? gain_ * std::max(command.grip_effort, 0.0) : 0.0;
    return state;
  }
  double closure() const { return closure_; }

 private:
  double gain_;
  double closure_ = 0.0;
  uint32_t sequence_ = 0;
};

/// Runs `controller` on `hand` for `seconds`, returns the last reported grip.
double Drive(ConstantGripController& controller, SyntheticHand& hand, double seconds, double& time_s,
           hand::HandCommand& command, bool stale = false) {
  sensor::TactileState state;
  for (double end = time_s + seconds; time_s < end; time_s += kTickS) {
    state = hand.Step(command, stale);
    command = controller.Update(state, {}, time_s);
  }
  return state.total_fn_n;
}

TEST(ConstantGripControllerTest, ClosesThenHoldsItsGripWhateverTheMotorsGain) {
  for (const double gain : {10.0, 20.0, 40.0}) {
    SCOPED_TRACE(gain);
    ConstantGripController controller(ConstantGripConfig{.grip_n = 1.5});
    SyntheticHand hand(gain);
    controller.SetIntent(GraspIntent::kClose);
    double time_s = 0.0;
    hand::HandCommand command;
    Drive(controller, hand, 0.01, time_s, command);
    EXPECT_STREQ(controller.telemetry().phase, "closing");
    EXPECT_DOUBLE_EQ(command.grip_effort, ConstantGripConfig{}.close_effort);
    const double grip_n = Drive(controller, hand, 1.5, time_s, command);
    EXPECT_STREQ(controller.telemetry().phase, "holding");
    EXPECT_NEAR(grip_n, 1.5, kGripTolN);
    EXPECT_DOUBLE_EQ(controller.telemetry().grip_target_n, 1.5);
    EXPECT_FALSE(controller.telemetry().slip_detected);  // it knows nothing of slip
  }
}

TEST(ConstantGripControllerTest, ATaskCeilingCapsTheGripAndStaleDataKeepTheSqueeze) {
  ConstantGripController controller(ConstantGripConfig{.grip_n = 4.0});
  controller.SetGripCeiling(2.5);
  SyntheticHand hand(20.0);
  controller.SetIntent(GraspIntent::kClose);
  double time_s = 0.0;
  hand::HandCommand command;
  EXPECT_NEAR(Drive(controller, hand, 1.5, time_s, command), 2.5, kGripTolN);
  const double holding_effort = command.grip_effort;
  Drive(controller, hand, 0.1, time_s, command, /*stale=*/true);
  EXPECT_DOUBLE_EQ(command.grip_effort, holding_effort);  // never opens on stale data
  EXPECT_TRUE(controller.telemetry().safe_hold);
  controller.SetIntent(GraspIntent::kOpen);
  Drive(controller, hand, 0.01, time_s, command);
  EXPECT_LT(command.grip_effort, 0.0);
  EXPECT_STREQ(controller.telemetry().phase, "releasing");
}

}  // namespace
}  // namespace graspbed::controller
