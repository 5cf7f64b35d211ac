// Script actions that wait for an event (after: grasped | stable | slip_flagged | released): the
// schema and its load-time messages, and runs on the real simulation that show the event gates the
// action -- on a slowed motor a lift after `grasped` holds the object where the same lift at a fixed
// time leaves it on the table, each action fires at its event's tick plus its delay, and a missing
// event fails the run naming the action, the event and the timeout. The machinery tests run on the
// jaw fixture (as tests/testbed does), the slowed-motor one on the prosthetic hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "controller/grasp_controller.h"
#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "sim/sim_rig.h"
#include "testbed/scenario_config.h"
#include "testbed/script_events.h"
#include "testbed/script_player.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/cli_runner.h"
#include "tests/support/error_of.h"
#include "tests/support/temp_dir.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed::testbed {
namespace {

using graspbed::test_support::TempDir;
using test_support::RunScenarioText;
using test_support::ScenarioRun;
using test_support::Signals;

constexpr double kControlTickS = 0.001;                        // default controller.rate_hz
const double kPhysicsStepS = sim::PhysicsConfig{}.timestep_s;  // the default physics step [s]
constexpr double kGraspForceN = 0.3;                           // default metrics.grasp_force_n
constexpr double kLiftHeightM = 0.05;

std::string LoadError(const std::string& text) {
  return graspbed::test_support::ErrorOf<common::ConfigError>(
      [&] { LoadScenarioFromString(text, "test.yaml"); });
}

const ExpectationOutcome* FindOutcome(const RunResult& result, const std::string& prefix) {
  for (const ExpectationOutcome& outcome : result.outcomes) {
    if (outcome.name.rfind(prefix, 0) == 0) return &outcome;
  }
  return nullptr;
}

// The grasped condition recomputed from signals.csv: intent close, fresh data, >= 1 contact unit and
// >= grasp_force_n estimated in total, without a break for kEventConfirmS. First row time it holds
// at or after `from_s` (< 0: never).
double FirstGraspedTime(const Signals& s, double from_s) {
  double since = -1.0;
  for (size_t r = 0; r < s.rows(); ++r) {
    const double t = s.At("time_s", r);
    const bool in_grasp = s.At("stale", r) == 0.0 && s.At("contact_units", r) >= 1.0 &&
                          s.At("est_total_fn_n", r) >= kGraspForceN;
    since = in_grasp ? (since < 0.0 ? t : since) : -1.0;
    if (t >= from_s - 1e-9 && s.Text("intent")[r] == "close" && since >= 0.0 &&
        t - since >= kEventConfirmS - 1e-9) {
      return t;
    }
  }
  return -1.0;
}

// ---- schema ------------------------------------------------------------------------------------------

TEST(ScriptEventSchemaTest, EventActionsLoadKeepTheirPlaceAfterTheirPredecessorAndRoundTrip) {
  const ScenarioConfig config = LoadScenarioFromString(R"(duration_s: 3
script:
  - {at_s: 0.5, action: close}
  - {after: grasped, delay_s: 0.1, timeout_s: 2.0, action: lift, height_m: 0.05, duration_s: 0.8}
  - {after: stable, timeout_s: 1, action: add_mass, mass_kg: 0.05}
  - {at_s: 0.2, action: shake, frequency_hz: 2, amplitude_m: 0.001, duration_s: 0.1}
  - {at_s: 2.5, action: open}
  - {after: released, delay_s: 0.2, timeout_s: 0.4, action: idle}
)",
                                                       "t.yaml");
  ASSERT_EQ(config.script.size(), 6u);
  // Fixed-time actions by at_s; each event action right behind the action it follows in the file.
  EXPECT_EQ(config.script[0].kind, ActionKind::kShake);
  EXPECT_EQ(config.script[1].kind, ActionKind::kClose);
  EXPECT_EQ(config.script[2].kind, ActionKind::kLift);
  EXPECT_EQ(config.script[2].after, ScriptEvent::kGrasped);
  EXPECT_DOUBLE_EQ(config.script[2].delay_s, 0.1);
  EXPECT_DOUBLE_EQ(config.script[2].timeout_s, 2.0);
  EXPECT_EQ(config.script[2].line, 4);
  EXPECT_EQ(config.script[3].after, ScriptEvent::kStable);
  EXPECT_DOUBLE_EQ(config.script[3].delay_s, 0.0);
  EXPECT_EQ(config.script[4].kind, ActionKind::kOpen);
  EXPECT_EQ(config.script[5].after, ScriptEvent::kReleased);
  // config.yaml writes after/delay_s/timeout_s instead of at_s and loads again to the same script.
  const std::string emitted = EmitScenarioYaml(config);
  EXPECT_NE(emitted.find("after: grasped"), std::string::npos) << emitted;
  const ScenarioConfig again = LoadScenarioFromString(emitted, "config.yaml");
  EXPECT_EQ(EmitScenarioYaml(again), emitted);
  ASSERT_EQ(again.script.size(), 6u);
  for (size_t i = 0; i < again.script.size(); ++i) {
    EXPECT_EQ(again.script[i].kind, config.script[i].kind) << i;
    EXPECT_EQ(again.script[i].after, config.script[i].after) << i;
  }
  EXPECT_EQ(EventNames(), (std::vector<std::string>{"grasped", "stable", "slip_flagged", "released"}));
}

TEST(ScriptEventSchemaTest, BadEventActionsAreRefusedAtLoadWithFileLineAndKey) {
  const struct {
    const char* action;
    const char* message;
  } cases[] = {
      {"{after: grabbed, timeout_s: 1, action: open}",
       "test.yaml:3: script[0].after = grabbed: unknown name; valid names: grasped, stable, slip_flagged, "
       "released"},
      {"{after: grasped, delay_s: -0.1, timeout_s: 1, action: open}",
       "test.yaml:3: script[0].delay_s = -0.1: must be >= 0"},
      {"{after: grasped, action: open}",
       "test.yaml:3: script[0].timeout_s = null: missing required key: an action after an event needs "
       "timeout_s > 0"},
      {"{after: grasped, timeout_s: 0, action: open}", "test.yaml:3: script[0].timeout_s = 0: must be > 0"},
      {"{after: grasped, timeout_s: -2, action: open}", "test.yaml:3: script[0].timeout_s = -2: must be > 0"},
      {"{at_s: 0.5, after: grasped, timeout_s: 1, action: open}",
       "test.yaml:3: script[0].after = grasped: give either at_s (a fixed time) or after (an event), not "
       "both"},
      {"{at_s: 0.5, delay_s: 0.1, action: open}",
       "test.yaml:3: script[0].delay_s = 0.1: only with after: <event>; a fixed-time action fires at at_s"},
      {"{at_s: 0.5, timeout_s: 1, action: open}",
       "test.yaml:3: script[0].timeout_s = 1: only with after: <event>"},
      {"{action: open}",
       "test.yaml:3: script[0].at_s = null: missing required key: give at_s [s] or after: <event>"},
      {"{after: grasped, delay_s: 5, timeout_s: 1, action: open}",
       "test.yaml:3: script[0].delay_s = 5: must be <= 2"},
  };
  for (const auto& c : cases) {
    const std::string error = LoadError(std::string("duration_s: 2\nscript:\n  - ") + c.action + "\n");
    EXPECT_NE(error.find(c.message), std::string::npos) << c.action << "\n  got: " << error;
  }
}

// ---- runs --------------------------------------------------------------------------------------------

// The prosthetic hand opened to a 90 mm pre-shape around a 100 g box 50 mm wide, its digit motors at
// `speed_rad_s` (default 1.6 rad/s), the open-loop controller; `lift` is the lift's script entry.
std::string WidePreShapeScenario(double speed_rad_s, const std::string& lift) {
  return R"(duration_s: 1.6
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.7}
hand: {open_gap_m: 0.09, digit_motor: {no_load_speed_rad_s: )" +
         std::to_string(speed_rad_s) + R"(}}
controller: {name: open_loop}
script:
  - {at_s: 0.04, action: close}
)" + lift;
}

TEST(ScriptEventRunTest, LiftAfterGraspedHoldsOnASlowedMotorWhereTheSameLiftAtAFixedTimeDoesNot) {
  const TempDir dir("script_events_test");
  constexpr double kNormalSpeedRadS = 1.6;  // hand.digit_motor default
  constexpr double kSlowedSpeedRadS = 0.6;
  constexpr double kFixedLiftS = 0.45;
  const std::string lift = "action: lift, height_m: 0.05, duration_s: 0.3}\n";
  const std::string fixed_lift = "  - {at_s: 0.45, " + lift;
  const std::string gated_lift = "  - {after: grasped, delay_s: 0.1, timeout_s: 1.0, " + lift;
  const ScenarioRun normal_fixed =
      RunScenarioText(dir, "normal_fixed", WidePreShapeScenario(kNormalSpeedRadS, fixed_lift));
  const ScenarioRun slowed_fixed =
      RunScenarioText(dir, "slowed_fixed", WidePreShapeScenario(kSlowedSpeedRadS, fixed_lift));
  const ScenarioRun slowed_gated =
      RunScenarioText(dir, "slowed_gated", WidePreShapeScenario(kSlowedSpeedRadS, gated_lift));

  // The fixed time suits the hand's own motor: grasped before it, the box goes up.
  const double normal_grasp_s = FirstGraspedTime(normal_fixed.signals, 0.0);
  ASSERT_GT(normal_grasp_s, 0.0);
  EXPECT_LT(normal_grasp_s, kFixedLiftS);
  EXPECT_NEAR(normal_fixed.signals.AtTime("object_height_m", 1.6), kLiftHeightM, 0.2 * kLiftHeightM);

  // On the slowed motor the wrist goes up before the digits reach the box, which stays on the table.
  const double slowed_grasp_s = FirstGraspedTime(slowed_fixed.signals, 0.0);
  EXPECT_TRUE(slowed_grasp_s < 0.0 || slowed_grasp_s > kFixedLiftS) << slowed_grasp_s;
  EXPECT_LT(slowed_fixed.signals.AtTime("object_height_m", 1.6), 0.2 * kLiftHeightM);

  // After `grasped` the same lift waits for the slowed grasp and takes the box up.
  const std::vector<ActionTiming>& timings = slowed_gated.result.script_timings;
  ASSERT_EQ(timings.size(), 2u);
  const double grasp_s = FirstGraspedTime(slowed_gated.signals, 0.04);
  ASSERT_GT(grasp_s, kFixedLiftS) << "the slowed hand must grasp after the fixed lift time";
  EXPECT_NEAR(timings[1].event_s, grasp_s, 1e-9);
  EXPECT_NEAR(slowed_gated.signals.AtTime("object_height_m", 1.6), kLiftHeightM, 0.2 * kLiftHeightM);
  EXPECT_FALSE(slowed_gated.result.metrics.dropped);
  const ExpectationOutcome* outcome = FindOutcome(slowed_gated.result, "script: lift after grasped");
  ASSERT_NE(outcome, nullptr);
  EXPECT_TRUE(outcome->passed) << outcome->note;
  EXPECT_TRUE(slowed_gated.result.passed) << SummaryTable(slowed_gated.result);
}

TEST(ScriptEventRunTest, EventActionsFireAtTheirEventTickPlusTheirDelayAndChainInFileOrder) {
  const TempDir dir("script_events_test");
  // Held box: grasped, then (chained) stable, then a fixed open, then released.
  const ScenarioRun run = RunScenarioText(dir, "chain", R"(duration_s: 1.2
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.7}
hand: {model: jaw, open_gap_m: 0.055}
controller: {name: open_loop}
script:
  - {at_s: 0.04, action: close}
  - {after: grasped, delay_s: 0.0523, timeout_s: 1, action: lift, height_m: 0.02, duration_s: 0.2}
  - {after: stable, delay_s: 0.1, timeout_s: 1, action: add_mass, mass_kg: 0.01}
  - {at_s: 0.8, action: open}
  - {after: released, delay_s: 0.05, timeout_s: 0.3, action: idle}
)");
  const Signals& s = run.signals;
  const std::vector<ActionTiming>& t = run.result.script_timings;
  const std::vector<Action>& script = run.result.config.script;
  ASSERT_EQ(t.size(), 5u);
  ASSERT_TRUE(run.result.passed) << SummaryTable(run.result);

  // grasped: armed when close fired; the event is the first tick the estimate shows the grasp.
  EXPECT_DOUBLE_EQ(t[1].armed_s, t[0].fired_s);
  EXPECT_NEAR(t[1].event_s, FirstGraspedTime(s, t[1].armed_s), 1e-9);
  // stable: armed when the lift fired, seen at or after that, after the stable window of the grasp.
  EXPECT_DOUBLE_EQ(t[2].armed_s, t[1].fired_s);
  EXPECT_GE(t[2].event_s, t[2].armed_s - 1e-9);
  EXPECT_GE(t[2].event_s, t[1].event_s + run.result.config.metrics.stable_window_s - kEventConfirmS - 1e-9);
  // released: after the open, with no contact left on the estimate.
  EXPECT_DOUBLE_EQ(t[4].armed_s, t[3].fired_s);
  EXPECT_GT(t[4].event_s, 0.8);
  EXPECT_EQ(s.AtTime("contact_units", t[4].event_s), 0.0);
  EXPECT_LT(s.AtTime("est_total_fn_n", t[4].event_s), kGraspForceN);

  // Each fires delay_s after its event, within one physics step (actions fire before a step).
  for (size_t i : {1u, 2u, 4u}) {
    EXPECT_GE(t[i].fired_s, t[i].event_s + script[i].delay_s - 1e-9) << i;
    EXPECT_LT(t[i].fired_s, t[i].event_s + script[i].delay_s + kPhysicsStepS + 1e-9) << i;
    EXPECT_LE(t[i].fired_s - (t[i].event_s + script[i].delay_s), kControlTickS) << i;
  }
  // The action did what it does, when it fired: the wrist target starts to rise then, not before.
  EXPECT_DOUBLE_EQ(s.AtTime("wrist_target_z_m", t[1].fired_s - kControlTickS),
                   s.AtTime("wrist_target_z_m", 0.0));
  EXPECT_GT(s.AtTime("wrist_target_z_m", t[1].fired_s + 0.05), s.AtTime("wrist_target_z_m", 0.0) + 1e-4);
  EXPECT_EQ(s.Text("intent")[s.RowAt(t[4].fired_s + kControlTickS)], "idle");
}

TEST(ScriptEventRunTest, SlipFlaggedIsTheControllersFirstSlipFlagAfterArming) {
  const TempDir dir("script_events_test");
  // The reference controller flags the slip an 8 N pull causes; the action after it removes the pull.
  const ScenarioRun run = RunScenarioText(dir, "slip", R"(duration_s: 1.1
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.7}
hand: {model: jaw, open_gap_m: 0.055}
controller: {name: grip_slip}
script:
  - {at_s: 0.04, action: close}
  - {at_s: 0.3, action: lift, height_m: 0.03, duration_s: 0.5}
  - {at_s: 0.85, action: pull, force_n: [0, 0, -8]}
  - {after: slip_flagged, delay_s: 0.01, timeout_s: 0.2, action: pull, force_n: [0, 0, 0]}
)");
  const std::vector<ActionTiming>& t = run.result.script_timings;
  ASSERT_EQ(t.size(), 4u);
  ASSERT_GE(t[3].fired_s, 0.0) << SummaryTable(run.result);
  double first_flag_s = -1.0;
  const Signals& s = run.signals;
  for (size_t r = s.RowAt(t[3].armed_s); r < s.rows(); ++r) {
    if (s.At("slip_flag", r) != 0.0) {
      first_flag_s = s.At("time_s", r);
      break;
    }
  }
  EXPECT_NEAR(t[3].event_s, first_flag_s, 1e-9);
  EXPECT_NEAR(t[3].fired_s, t[3].event_s + 0.01, kPhysicsStepS + 1e-9);
  EXPECT_EQ(s.AtTime("external_force_z_n", t[3].fired_s + kControlTickS), 0.0);
}

TEST(ScriptEventRunTest, AMissingEventTimesOutFailsTheRunAndLaterFixedActionsStillFire) {
  const TempDir dir("script_events_test");
  // The open-loop controller never flags slip: the lift waits 0.3 s and is given up, the action
  // chained behind it never runs, the fixed open later in the file still fires.
  const ScenarioRun run =
      RunScenarioText(dir, "timeout",
                      test_support::HeldBoxScenario(
                          0.8, R"(  - {after: slip_flagged, timeout_s: 0.3, action: lift, height_m: 0.02}
  - {after: grasped, timeout_s: 0.3, action: add_mass, mass_kg: 0.05}
  - {at_s: 0.6, action: open}
)"));
  EXPECT_FALSE(run.result.passed);
  EXPECT_TRUE(run.result.completed);
  const ExpectationOutcome* lift = FindOutcome(run.result, "script: lift after slip_flagged (line 8)");
  ASSERT_NE(lift, nullptr) << SummaryTable(run.result);
  EXPECT_FALSE(lift->passed);
  EXPECT_EQ(lift->limit, "slip_flagged within 0.300 s");
  EXPECT_NE(lift->note.find(
                "timed out: no slip_flagged within 0.300 s of arming at 0.150 s; the action did not run"),
            std::string::npos)
      << lift->note;
  const ExpectationOutcome* chained = FindOutcome(run.result, "script: add_mass after grasped");
  ASSERT_NE(chained, nullptr);
  EXPECT_FALSE(chained->passed);
  EXPECT_EQ(chained->value_text, "not armed");
  // Nothing of the lift or the mass happened; the open did.
  const Signals& s = run.signals;
  EXPECT_NEAR(s.AtTime("wrist_target_z_m", 0.8), s.AtTime("wrist_target_z_m", 0.36), 1e-12);
  EXPECT_NEAR(s.AtTime("object_mass_kg", 0.8), 0.1, 1e-9);
  EXPECT_EQ(s.Text("intent")[s.RowAt(0.61)], "open");
  // The summary names it like an expectation.
  EXPECT_NE(SummaryTable(run.result).find("[FAIL] script: lift after slip_flagged (line 8)"),
            std::string::npos)
      << SummaryTable(run.result);
}

TEST(ScriptEventRunTest, PlayerUpdateAndObserveAllocateNothing) {
  // The runner's loop without its logging: a script with fixed and event actions of every kind of
  // wait, on a rig built as RunScenario builds it.
  const ScenarioConfig config = LoadScenarioFromString(
      test_support::HeldBoxScenario(
          0.8, R"(  - {after: grasped, timeout_s: 0.5, action: add_mass, mass_kg: 0.01, ramp_s: 0.1}
  - {after: stable, delay_s: 0.05, timeout_s: 0.5, action: shake, frequency_hz: 5, amplitude_m: 0.001, duration_s: 0.1}
  - {after: slip_flagged, timeout_s: 0.1, action: pull, force_n: [0, 0, -1]}
  - {at_s: 0.6, action: open}
  - {after: released, timeout_s: 0.15, action: idle}
  - {at_s: 0.5, action: drop_frames, duration_s: 0.05, probability: 0.5}
)"),
      "alloc.yaml");
  const sensor::Layout layout = sensor::LoadLayout(ResolveLayoutPath(config));
  sim::SimRigConfig rig_config;
  rig_config.scene = config.scene;
  rig_config.control_rate_hz = config.controller.rate_hz;
  sim::SimRig rig(layout, sensor::NominalCalibration(config.sensor.strain_model.nominal, layout.unit_count()),
                  rig_config, controller::MakeController(config.controller.name, config.controller.params));
  ScriptPlayer player(config);
  player.Start(rig);
  const long before = graspbed::test_support::AllocationCount();
  while (rig.time_s() < config.duration_s - 1e-9) {
    player.Update(rig.time_s(), rig);
    if (rig.Step())
      player.Observe(rig.time_s(), rig.loop().state(), rig.controller().telemetry().slip_detected);
  }
  EXPECT_EQ(graspbed::test_support::AllocationCount() - before, 0);
  // The waits were exercised: grasped, stable and released fired, slip_flagged timed out.
  const std::vector<ActionTiming>& t = player.timings();
  ASSERT_EQ(t.size(), 8u);
  EXPECT_GE(t[2].fired_s, 0.0);
  EXPECT_GE(t[3].fired_s, 0.0);
  EXPECT_GE(t[4].timed_out_s, 0.0);
  EXPECT_GE(t[7].fired_s, 0.0);
}

TEST(ScriptEventRunTest, TheCliExitsOneWhenAnEventTimesOutAndNamesActionEventAndTimeout) {
  if (graspbed::test_support::CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY must point at the CLI";
  const TempDir dir("script_events_test");
  const std::string file =
      dir.Write("wait.yaml",
                test_support::HeldBoxScenario(0.5, "  - {after: released, timeout_s: 0.2, action: open}\n"));
  const graspbed::test_support::CliResult result =
      graspbed::test_support::RunCli("run " + file + " --no-plots --out " + dir.Path("out"));
  EXPECT_EQ(result.exit_code, 1) << result.out << result.err;
  EXPECT_NE(result.out.find("[FAIL] script: open after released (line 8)"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("released within 0.200 s"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("timed out: no released within 0.200 s of arming at 0.150 s"), std::string::npos)
      << result.out;
}

}  // namespace
}  // namespace graspbed::testbed
