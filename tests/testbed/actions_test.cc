// Every script action on the real simulation: a short scenario per action, run in process, and its
// physical or sensor effect checked on the ground truth, the signals and the metrics. The hand runs
// the open-loop controller (blind to the sensor), so a sensor fault leaves the physics alone and a
// faulted run can be compared row by row with a fault-free one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "sensor/tactile_state.h"
#include "testbed/script_player.h"
#include "tests/support/temp_dir.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed::testbed {
namespace {

using graspbed::test_support::TempDir;
using test_support::HeldBoxScenario;
using test_support::kHeldInAirS;
using test_support::RunScenarioText;
using test_support::ScenarioRun;
using test_support::Signals;

constexpr double kPositionTolM = 1.5e-3;  // wrist servo tracking and object settling
constexpr double kForceTolN = 1e-6;       // script force/mass columns are set exactly
constexpr double kMassTolKg = 1e-6;
constexpr double kLiftHeightM = 0.05;  // HeldBoxScenario's lift
constexpr double kGripFloorN = 5.0;    // the open-loop default effort squeezes about 10 N
constexpr double kReleasedN = 0.5;     // squeeze left after opening
constexpr double kR0Ohm = 3400.0;      // paper R0, unloaded reading of an ideal unit
const double kPhysicsStepS = sim::PhysicsConfig{}.timestep_s;  // the default physics step [s]

// Minimum and maximum of `column` over rows with time in [t0, t1].
std::pair<double, double> Range(const Signals& s, const std::string& column, double t0, double t1) {
  double low = INFINITY;
  double high = -INFINITY;
  for (size_t r = s.RowAt(t0); r < s.rows() && s.At("time_s", r) <= t1 + 1e-9; ++r) {
    low = std::min(low, s.At(column, r));
    high = std::max(high, s.At(column, r));
  }
  return {low, high};
}

// Standard deviation of `column` over rows with time in [t0, t1].
double StdDev(const Signals& s, const std::string& column, double t0, double t1) {
  double sum = 0.0;
  double square_sum = 0.0;
  int count = 0;
  for (size_t r = s.RowAt(t0); r < s.rows() && s.At("time_s", r) <= t1 + 1e-9; ++r) {
    sum += s.At(column, r);
    square_sum += s.At(column, r) * s.At(column, r);
    ++count;
  }
  const double mean = sum / count;
  return std::sqrt(std::max(0.0, square_sum / count - mean * mean));
}

// The unit carrying the most true normal force at `time_s`.
int BusiestUnit(const Signals& s, double time_s, int units = 20) {
  int best = 0;
  for (int u = 1; u < units; ++u) {
    if (s.AtTime("fn_true_n_" + std::to_string(u), time_s) >
        s.AtTime("fn_true_n_" + std::to_string(best), time_s)) {
      best = u;
    }
  }
  return best;
}

// A unit that never carries load in the run.
int IdleUnit(const Signals& s, int units = 20) {
  for (int u = 0; u < units; ++u) {
    const std::vector<double>& fn = s.Column("fn_true_n_" + std::to_string(u));
    if (*std::max_element(fn.begin(), fn.end()) == 0.0) return u;
  }
  ADD_FAILURE() << "every unit is loaded at some point";
  return 0;
}

class ActionsTest : public ::testing::Test {
 protected:
  TempDir dir_;
};

TEST_F(ActionsTest, CloseSqueezesTheObjectAndLiftRaisesIt) {
  const ScenarioRun run = RunScenarioText(dir_, "close_lift", HeldBoxScenario(kHeldInAirS));
  const Signals& s = run.signals;
  // Before the close nothing touches the box.
  EXPECT_EQ(s.AtTime("true_squeeze_n", 0.005), 0.0);
  EXPECT_EQ(s.Text("intent")[s.RowAt(0.005)], "idle");
  EXPECT_EQ(s.Text("intent")[s.RowAt(0.05)], "close");
  // After it the fingers have closed on the box, the sensor sees it and the metrics count a grasp.
  EXPECT_GT(s.AtTime("grip_closure_m", 0.14), 0.002);
  EXPECT_GT(s.AtTime("true_squeeze_n", 0.14), kGripFloorN);
  EXPECT_GT(s.AtTime("contact_units", 0.14), 0.0);
  EXPECT_GT(s.AtTime("est_total_fn_n", 0.14), kGripFloorN / 2);
  EXPECT_TRUE(run.result.metrics.grasped);
  EXPECT_LT(run.result.metrics.contact_time_s, 0.15);
  // Established when the lift (from 0.15 s) takes the box off the table, within the acquisition's
  // longest time after the touch.
  EXPECT_GT(run.result.metrics.grasp_time_s, 0.15);
  EXPECT_LE(run.result.metrics.grasp_time_s,
            run.result.metrics.contact_time_s + MetricsConfig{}.acquisition_max_s + 1e-9);
  // The lift carries wrist and box up 50 mm with it.
  EXPECT_NEAR(s.AtTime("object_height_m", 0.14), 0.0, kPositionTolM);
  EXPECT_NEAR(s.AtTime("wrist_target_z_m", kHeldInAirS) - s.AtTime("wrist_target_z_m", 0.14), kLiftHeightM,
              1e-9);
  EXPECT_NEAR(s.AtTime("wrist_z_m", kHeldInAirS) - s.AtTime("wrist_z_m", 0.14), kLiftHeightM, kPositionTolM);
  EXPECT_NEAR(s.AtTime("object_height_m", kHeldInAirS), kLiftHeightM, kPositionTolM);
  // Minimum-jerk profile. A row holds the target the script set for the physics step that ended at
  // its time, i.e. the target at the step's start.
  for (double t : {0.2, 0.25, 0.3}) {
    EXPECT_NEAR(s.AtTime("wrist_target_z_m", t) - s.AtTime("wrist_target_z_m", 0.14),
                kLiftHeightM * ProfileProgress(Profile::kMinimumJerk, (t - kPhysicsStepS - 0.15) / 0.2),
                1e-9);
  }
  EXPECT_FALSE(run.result.metrics.dropped);
}

TEST_F(ActionsTest, LiftWithoutCloseLeavesTheObjectOnTheTable) {
  const std::string yaml = R"(duration_s: 0.4
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.7}
hand: {model: jaw, open_gap_m: 0.055}
controller: {name: open_loop}
script:
  - {at_s: 0.1, action: lift, height_m: 0.05, duration_s: 0.2, profile: linear}
)";
  const ScenarioRun run = RunScenarioText(dir_, "lift_only", yaml);
  const Signals& s = run.signals;
  EXPECT_NEAR(s.AtTime("wrist_z_m", 0.4) - s.AtTime("wrist_z_m", 0.05), kLiftHeightM, kPositionTolM);
  // Linear profile (a row holds the target at the start of the physics step that ended at its time).
  EXPECT_NEAR(s.AtTime("wrist_target_z_m", 0.15) - s.AtTime("wrist_target_z_m", 0.05),
              kLiftHeightM * (0.15 - kPhysicsStepS - 0.1) / 0.2, 1e-9);
  EXPECT_NEAR(s.AtTime("object_height_m", 0.4), 0.0, 1e-4);
  EXPECT_EQ(Range(s, "true_squeeze_n", 0.0, 0.4).second, 0.0);
  EXPECT_FALSE(run.result.metrics.grasped);
}

TEST_F(ActionsTest, OpenReleasesTheObjectWhichFallsBackToTheTable) {
  const ScenarioRun run =
      RunScenarioText(dir_, "open", HeldBoxScenario(0.8, "  - {at_s: 0.45, action: open}\n"));
  const Signals& s = run.signals;
  EXPECT_GT(s.AtTime("true_squeeze_n", 0.44), kGripFloorN);
  EXPECT_EQ(s.Text("intent")[s.RowAt(0.46)], "open");
  EXPECT_LT(s.AtTime("true_squeeze_n", 0.8), kReleasedN);
  EXPECT_LT(s.AtTime("grip_closure_m", 0.8), s.AtTime("grip_closure_m", 0.44) - 0.002);
  EXPECT_NEAR(s.AtTime("object_height_m", 0.8), 0.0, kPositionTolM);
  // Letting go on purpose is no drop: the grasp is over once the intent is open.
  EXPECT_FALSE(run.result.metrics.dropped);
  EXPECT_EQ(s.AtTime("holding", 0.8), 0.0);
}

TEST_F(ActionsTest, MoveTakesTheWristToAnOffsetAndToAnAbsolutePosition) {
  // The pre-grasp wrist pose is computed from the scene; read it from a very short run first.
  const std::string scene = R"(object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.7}
hand: {model: jaw, open_gap_m: 0.055}
controller: {name: open_loop}
)";
  const ScenarioRun probe = RunScenarioText(dir_, "probe", "duration_s: 0.01\n" + scene);
  const double x0 = probe.signals.At("wrist_x_m", 0);
  const double y0 = probe.signals.At("wrist_y_m", 0);
  const double z0 = probe.signals.At("wrist_z_m", 0);
  char script[512];
  std::snprintf(
      script, sizeof(script),
      "script:\n"
      "  - {at_s: 0.05, action: move, offset_m: [0.01, 0, 0.02], duration_s: 0.15}\n"
      "  - {at_s: 0.35, action: move, position_m: [%.9g, %.9g, %.9g], duration_s: 0.15, profile: linear}\n",
      x0 - 0.01, y0 + 0.005, z0 + 0.04);
  const ScenarioRun run = RunScenarioText(dir_, "move", "duration_s: 0.65\n" + scene + script);
  const Signals& s = run.signals;
  EXPECT_NEAR(s.AtTime("wrist_x_m", 0.34), x0 + 0.01, kPositionTolM);
  EXPECT_NEAR(s.AtTime("wrist_y_m", 0.34), y0, kPositionTolM);
  EXPECT_NEAR(s.AtTime("wrist_z_m", 0.34), z0 + 0.02, kPositionTolM);
  EXPECT_NEAR(s.AtTime("wrist_target_z_m", 0.34), z0 + 0.02, 1e-9);
  // Linear from +20 mm to +40 mm (a row holds the target at the start of its physics step).
  EXPECT_NEAR(s.AtTime("wrist_target_z_m", 0.40), z0 + 0.02 + 0.02 * (0.40 - kPhysicsStepS - 0.35) / 0.15,
              1e-7);
  EXPECT_NEAR(s.AtTime("wrist_x_m", 0.65), x0 - 0.01, kPositionTolM);
  EXPECT_NEAR(s.AtTime("wrist_y_m", 0.65), y0 + 0.005, kPositionTolM);
  EXPECT_NEAR(s.AtTime("wrist_z_m", 0.65), z0 + 0.04, kPositionTolM);
}

TEST_F(ActionsTest, ShakeOscillatesTheWristAtItsFrequencyAndAmplitudeAndStops) {
  constexpr double kAmplitudeM = 0.005;
  constexpr double kFrequencyHz = 5.0;
  const ScenarioRun run = RunScenarioText(
      dir_, "shake",
      HeldBoxScenario(0.95,
                      "  - {at_s: 0.45, action: shake, frequency_hz: 5, amplitude_m: 0.005, duration_s: 0.4, "
                      "axis: [0, 0, 2], ramp_s: 0.1}\n"));
  const Signals& s = run.signals;
  const double base = s.AtTime("wrist_target_z_m", 0.44);
  // Faded in and out over ramp_s: 5 ms into the shake and 5 ms before its end the target is within
  // 0.01 mm of rest (a sine switched on at full speed would be 0.78 mm away after 5 ms), and it
  // reaches the full amplitude in between (the peaks at 0.6 and 0.7 s).
  EXPECT_NEAR(s.AtTime("wrist_target_z_m", 0.455), base, 1e-5);
  EXPECT_NEAR(s.AtTime("wrist_target_z_m", 0.845), base, 1e-5);
  const auto [low, high] = Range(s, "wrist_target_z_m", 0.45, 0.85);
  EXPECT_NEAR(high - base, kAmplitudeM, 1e-4);
  EXPECT_NEAR(base - low, kAmplitudeM, 1e-4);
  // Sign changes of the offset: two per period.
  int crossings = 0;
  double previous = 0.0;
  for (size_t r = s.RowAt(0.451); r < s.RowAt(0.849); ++r) {
    const double offset = s.At("wrist_target_z_m", r) - base;
    if (std::abs(offset) < 1e-7) continue;
    if (previous != 0.0 && (offset > 0) != (previous > 0)) ++crossings;
    previous = offset;
  }
  EXPECT_NEAR(crossings, 2.0 * kFrequencyHz * 0.4, 1.0);
  // The wrist and the box really move; after the shake the target is back at rest.
  const auto [wrist_low, wrist_high] = Range(s, "wrist_z_m", 0.45, 0.9);
  EXPECT_GT(wrist_high - wrist_low, kAmplitudeM);
  const auto [box_low, box_high] = Range(s, "object_z_m", 0.45, 0.9);
  EXPECT_GT(box_high - box_low, kAmplitudeM);
  EXPECT_NEAR(s.AtTime("wrist_target_z_m", 0.9), base, 1e-9);
  // The shake moves only along its axis.
  EXPECT_NEAR(Range(s, "wrist_x_m", 0.45, 0.9).second - Range(s, "wrist_x_m", 0.45, 0.9).first, 0.0, 5e-4);
  // It rocked the box against the fingertips (a contact moved faster than the 2 mm/s that opens a
  // slip event) without sliding it: the friction held inside its cone, so no slip distance accrued.
  EXPECT_GT(Range(s, "slip_speed_mm_s", 0.45, 0.85).second, MetricsConfig{}.slip_speed_m_s * 1e3);
  EXPECT_LT(s.AtTime("slip_distance_mm", 0.95) - s.AtTime("slip_distance_mm", 0.44), 0.01);
  EXPECT_FALSE(run.result.metrics.dropped);
}

TEST_F(ActionsTest, AddMassStepBeyondTheGripDropsTheObjectAndASmallOneDoesNot) {
  const ScenarioRun heavy = RunScenarioText(
      dir_, "heavy", HeldBoxScenario(0.7, "  - {at_s: 0.45, action: add_mass, mass_kg: 2.0}\n"));
  EXPECT_NEAR(heavy.signals.AtTime("object_mass_kg", 0.44), 0.1, kMassTolKg);
  EXPECT_NEAR(heavy.signals.AtTime("object_mass_kg", 0.451), 2.1, kMassTolKg);
  EXPECT_TRUE(heavy.result.metrics.dropped);
  EXPECT_GT(heavy.result.metrics.drop_time_s, 0.45);
  EXPECT_LT(heavy.result.metrics.drop_time_s, 0.6);

  const ScenarioRun light = RunScenarioText(
      dir_, "light", HeldBoxScenario(0.7, "  - {at_s: 0.45, action: add_mass, mass_kg: 0.3}\n"));
  EXPECT_NEAR(light.signals.AtTime("object_mass_kg", 0.7), 0.4, kMassTolKg);
  EXPECT_FALSE(light.result.metrics.dropped);
  // The extra weight hangs on the fingertips: more shear on the sensor.
  const double shear_before = std::abs(light.signals.AtTime("est_shear_axial_n", 0.44)) +
                              std::abs(light.signals.AtTime("est_shear_circumferential_n", 0.44));
  const double shear_after = std::abs(light.signals.AtTime("est_shear_axial_n", 0.7)) +
                             std::abs(light.signals.AtTime("est_shear_circumferential_n", 0.7));
  EXPECT_GT(shear_after, shear_before + 1.0);
}

TEST_F(ActionsTest, AddMassRampFillsGraduallyAndDropsLaterThanAStep) {
  const ScenarioRun run = RunScenarioText(
      dir_, "pour",
      HeldBoxScenario(0.95,
                      "  - {at_s: 0.45, action: add_mass, mass_kg: 2.0, ramp_s: 0.4, profile: linear}\n"));
  const Signals& s = run.signals;
  EXPECT_NEAR(s.AtTime("object_mass_kg", 0.45), 0.1, 0.01);
  EXPECT_NEAR(s.AtTime("object_mass_kg", 0.55), 0.6, 0.01);
  EXPECT_NEAR(s.AtTime("object_mass_kg", 0.65), 1.1, 0.01);
  EXPECT_NEAR(s.AtTime("object_mass_kg", 0.9), 2.1, kMassTolKg);
  // About 1.4 kg is what a 10 N pinch at friction 0.7 carries: the box goes part-way into the ramp.
  EXPECT_TRUE(run.result.metrics.dropped);
  EXPECT_GT(run.result.metrics.drop_time_s, 0.6);
  EXPECT_LT(run.result.metrics.drop_time_s, 0.9);
}

TEST_F(ActionsTest, PullStepAndRampAndTimedPull) {
  const ScenarioRun step = RunScenarioText(
      dir_, "pull_step", HeldBoxScenario(0.6, "  - {at_s: 0.45, action: pull, force_n: [0, 0, -20]}\n"));
  EXPECT_NEAR(step.signals.AtTime("external_force_z_n", 0.44), 0.0, kForceTolN);
  EXPECT_NEAR(step.signals.AtTime("external_force_z_n", 0.451), -20.0, kForceTolN);
  EXPECT_TRUE(step.result.metrics.dropped);
  EXPECT_LT(step.result.metrics.drop_time_s, 0.55);

  const ScenarioRun ramp = RunScenarioText(
      dir_, "pull_ramp",
      HeldBoxScenario(
          0.9, "  - {at_s: 0.45, action: pull, force_n: [0, 0, -20], ramp_s: 0.4, profile: linear}\n"));
  EXPECT_NEAR(ramp.signals.AtTime("external_force_z_n", 0.55), -5.0, 0.1);
  EXPECT_NEAR(ramp.signals.AtTime("external_force_z_n", 0.65), -10.0, 0.1);
  EXPECT_TRUE(ramp.result.metrics.dropped);
  EXPECT_GT(ramp.result.metrics.drop_time_s, 0.6);  // about 13 N of pull before the pinch gives way
  EXPECT_LT(ramp.result.metrics.drop_time_s, 0.9);

  // A 3 N sideways tug for 0.1 s: the box yields a little on the compliant contacts and is kept.
  const ScenarioRun tug = RunScenarioText(
      dir_, "tug",
      HeldBoxScenario(0.65, "  - {at_s: 0.45, action: pull, force_n: [0, 0, -3], duration_s: 0.1}\n"));
  EXPECT_NEAR(tug.signals.AtTime("external_force_z_n", 0.5), -3.0, kForceTolN);
  EXPECT_NEAR(tug.signals.AtTime("external_force_z_n", 0.56), 0.0, kForceTolN);
  EXPECT_FALSE(tug.result.metrics.dropped);
  const double sag_before = tug.signals.AtTime("object_z_m", 0.44) - tug.signals.AtTime("wrist_z_m", 0.44);
  const double sag_during = tug.signals.AtTime("object_z_m", 0.54) - tug.signals.AtTime("wrist_z_m", 0.54);
  EXPECT_LT(sag_during, sag_before);
}

TEST_F(ActionsTest, SetFrictionStepDropsTheObjectAndARampDropsItLater) {
  const ScenarioRun step = RunScenarioText(
      dir_, "slippery", HeldBoxScenario(0.7, "  - {at_s: 0.45, action: set_friction, friction: 0.02}\n"));
  EXPECT_LT(step.signals.AtTime("slip_distance_mm", 0.449), 1.0);
  EXPECT_TRUE(step.result.metrics.dropped);
  EXPECT_GT(step.result.metrics.drop_time_s, 0.45);
  EXPECT_LT(step.result.metrics.drop_time_s, 0.6);

  const ScenarioRun ramp = RunScenarioText(
      dir_, "slippery_ramp",
      HeldBoxScenario(
          0.95, "  - {at_s: 0.45, action: set_friction, friction: 0.02, ramp_s: 0.4, profile: linear}\n"));
  EXPECT_TRUE(ramp.result.metrics.dropped);
  // Friction 0.7 -> 0.02 linearly: the 10 N pinch holds 1 N of weight until mu falls near 0.05.
  EXPECT_GT(ramp.result.metrics.drop_time_s, step.result.metrics.drop_time_s + 0.2);
}

// ---- sensor faults -------------------------------------------------------------------------------------

class SensorFaultTest : public ActionsTest {
 protected:
  static constexpr double kFaultS = 0.5;
  static constexpr double kDurationS = 0.65;
  // Held, still, in the air by kFaultS; the same run with a fault from kFaultS on.
  ScenarioRun Run(const std::string& name, const std::string& fault_script, const std::string& extra = "") {
    return RunScenarioText(dir_, name, HeldBoxScenario(kDurationS, fault_script, extra));
  }
  static std::string U(const char* column, int unit) {
    return std::string(column) + "_" + std::to_string(unit);
  }
};

TEST_F(SensorFaultTest, DeadUnitReadsOpenCircuitIsInvalidAndLeavesTheEstimate) {
  const ScenarioRun clean = Run("clean", "");
  const int unit = BusiestUnit(clean.signals, kFaultS);
  ASSERT_GT(clean.signals.AtTime(U("fn_true_n", unit), kFaultS), 0.5);
  const ScenarioRun dead =
      Run("dead", "  - {at_s: 0.5, action: dead_unit, unit: " + std::to_string(unit) + "}\n");
  const Signals& s = dead.signals;
  EXPECT_EQ(s.AtTime(U("validity", unit), 0.49), static_cast<double>(sensor::UnitValidity::kValid));
  EXPECT_EQ(s.AtTime(U("validity", unit), 0.6), static_cast<double>(sensor::UnitValidity::kOpen));
  EXPECT_GE(s.AtTime(U("r1_ohm", unit), 0.6), 1e6);
  EXPECT_GE(s.AtTime(U("r2_ohm", unit), 0.6), 1e6);
  // The truth is untouched (the hand is blind to the sensor), the estimate loses that unit's share.
  EXPECT_DOUBLE_EQ(s.AtTime(U("fn_true_n", unit), 0.6), clean.signals.AtTime(U("fn_true_n", unit), 0.6));
  EXPECT_EQ(s.AtTime("valid_units", 0.6), clean.signals.AtTime("valid_units", 0.6) - 1);
  EXPECT_NEAR(s.AtTime("est_total_fn_n", 0.6),
              clean.signals.AtTime("est_total_fn_n", 0.6) - clean.signals.AtTime(U("fn_est_n", unit), 0.6),
              1e-6);
}

TEST_F(SensorFaultTest, ShortedUnitReadsShortCircuitUntilRestored) {
  const ScenarioRun clean = Run("clean", "");
  const int unit = BusiestUnit(clean.signals, kFaultS);  // loaded: its reading is not just R0
  ASSERT_GT(clean.signals.AtTime(U("fn_true_n", unit), kFaultS), 0.5);
  const std::string u = std::to_string(unit);
  const ScenarioRun run = Run("short", "  - {at_s: 0.5, action: short_unit, unit: " + u +
                                           "}\n"
                                           "  - {at_s: 0.58, action: restore_unit, unit: " +
                                           u + "}\n");
  const Signals& s = run.signals;
  // Before the fault the unit reads what it reads without one: the same seeded run up to 0.5 s, so
  // the same resistance to the last digit of signals.csv.
  EXPECT_EQ(s.AtTime(U("r1_ohm", unit), 0.49), clean.signals.AtTime(U("r1_ohm", unit), 0.49));
  EXPECT_GT(s.AtTime(U("r1_ohm", unit), 0.49), kR0Ohm);  // loaded (paper eq. 3: R1 > R0 under Fn)
  EXPECT_EQ(s.AtTime(U("validity", unit), 0.49), static_cast<double>(sensor::UnitValidity::kValid));
  EXPECT_LE(s.AtTime(U("r1_ohm", unit), 0.55), 1.0);
  EXPECT_LE(s.AtTime(U("r2_ohm", unit), 0.55), 1.0);
  EXPECT_EQ(s.AtTime(U("validity", unit), 0.55), static_cast<double>(sensor::UnitValidity::kShort));
  EXPECT_EQ(s.AtTime(U("validity", unit), 0.62), static_cast<double>(sensor::UnitValidity::kValid));
  // Restored, it reads what it would have read without the fault (the hand is blind to the sensor).
  EXPECT_EQ(s.AtTime(U("r1_ohm", unit), 0.62), clean.signals.AtTime(U("r1_ohm", unit), 0.62));
}

TEST_F(SensorFaultTest, BiasShiftsTheResistancesAndTheEstimateByTheModelsAmount) {
  constexpr double kR1BiasOhm = 20.0;
  constexpr double kR2BiasOhm = -10.0;
  // dR/R = bias / R0 on each channel; eq. 4 with G = 100, kn = 5.5e-4 /N, kt = 4.1e-4 /N.
  constexpr double kFnShiftN = (kR1BiasOhm + kR2BiasOhm) / kR0Ohm / (2 * 100 * 5.5e-4);
  constexpr double kFtShiftN = (kR1BiasOhm - kR2BiasOhm) / kR0Ohm / (2 * 100 * 4.1e-4);
  const ScenarioRun clean = Run("clean", "");
  const int unit = BusiestUnit(clean.signals, kFaultS);
  const ScenarioRun biased = Run(
      "bias", "  - {at_s: 0.5, action: bias, unit: " + std::to_string(unit) + ", r1_ohm: 20, r2_ohm: -10}\n");
  for (double t : {0.49, 0.6}) {
    SCOPED_TRACE(t);
    const bool on = t > kFaultS;
    EXPECT_NEAR(biased.signals.AtTime(U("r1_ohm", unit), t) - clean.signals.AtTime(U("r1_ohm", unit), t),
                on ? kR1BiasOhm : 0.0, 1e-6);
    EXPECT_NEAR(biased.signals.AtTime(U("r2_ohm", unit), t) - clean.signals.AtTime(U("r2_ohm", unit), t),
                on ? kR2BiasOhm : 0.0, 1e-6);
  }
  // The inverted load carries the bias (within a percent: R1, R2 are loaded, not R0).
  EXPECT_NEAR(
      biased.signals.AtTime(U("fn_est_n", unit), 0.6) - clean.signals.AtTime(U("fn_est_n", unit), 0.6),
      kFnShiftN, 0.02 * kFnShiftN);
  EXPECT_NEAR(
      biased.signals.AtTime(U("ft_est_n", unit), 0.6) - clean.signals.AtTime(U("ft_est_n", unit), 0.6),
      kFtShiftN, 0.02 * kFtShiftN);
  // And so the estimation error metric sees it.
  EXPECT_GT(*biased.result.metrics.fn_rmse_n, *clean.result.metrics.fn_rmse_n + 0.005);
}

TEST_F(SensorFaultTest, NoiseBurstMultipliesTheNoiseForItsDuration) {
  constexpr double kScale = 10.0;
  constexpr double kNoiseOhm = 0.5;
  const std::string noisy = "sensor: {strain_model: {noise_ohm: 0.5}}\n";
  const ScenarioRun steady = Run("steady", "", noisy);
  const ScenarioRun run =
      Run("burst", "  - {at_s: 0.5, action: noise_burst, scale: 10, duration_s: 0.08}\n", noisy);
  const int unit = IdleUnit(run.signals);
  // The noise is N(0, noise_ohm) drawn from the seeded stream, the same draws with or without the
  // burst; the burst multiplies them. So an idle unit's deviation from R0 is exactly kScale times the
  // steady run's during the burst and the same outside it, to the rounding of signals.csv (%.9g of
  // about 3400 Ohm: 5e-6 Ohm, times kScale + 1 for the difference).
  constexpr double kCsvRoundingOhm = 5e-6 * (kScale + 1.0);
  const std::string column = U("r1_ohm", unit);
  int compared = 0;
  for (size_t r = 0; r < run.signals.rows(); ++r) {
    const double t = run.signals.At("time_s", r);
    const bool edge = std::abs(t - 0.5) < 0.005 || std::abs(t - 0.58) < 0.005;  // frame vs tick at the edges
    if (t < 0.40 || edge) continue;
    const bool during = t > 0.5 && t < 0.58;
    ASSERT_EQ(steady.signals.At("time_s", r), t);
    EXPECT_NEAR(run.signals.At(column, r) - kR0Ohm,
                (during ? kScale : 1.0) * (steady.signals.At(column, r) - kR0Ohm), kCsvRoundingOhm)
        << "t = " << t;
    ++compared;
  }
  EXPECT_GT(compared, 200);
  // And the steady noise has the configured spread: the sample deviation of n draws has a relative
  // standard error of 1 / sqrt(2 (n - 1)); 4 of those for the 90 rows in [0.40, 0.49] s.
  const double before = StdDev(run.signals, column, 0.40, 0.49);
  EXPECT_NEAR(before, kNoiseOhm, 4.0 / std::sqrt(2.0 * 89.0) * kNoiseOhm);
}

TEST_F(SensorFaultTest, DropFramesLosesFramesAndTheStateGoesStale) {
  const ScenarioRun clean = Run("clean", "");
  EXPECT_EQ(clean.result.dropped_frames, 0u);
  EXPECT_EQ(clean.result.stale_ticks, 0u);
  // Every frame for 50 ms: 50 lost at 1 kHz, stale after the 20 ms timeout for the rest of the gap.
  const ScenarioRun gap = Run("gap", "  - {at_s: 0.5, action: drop_frames, duration_s: 0.05}\n");
  EXPECT_NEAR(static_cast<double>(gap.result.dropped_frames), 50.0, 1.0);
  EXPECT_NEAR(static_cast<double>(gap.result.frames), static_cast<double>(clean.result.frames) - 50.0, 1.0);
  EXPECT_NEAR(static_cast<double>(gap.result.stale_ticks), 30.0, 2.0);
  EXPECT_EQ(gap.signals.AtTime("stale", 0.49), 0.0);
  EXPECT_EQ(gap.signals.AtTime("stale", 0.54), 1.0);
  EXPECT_EQ(gap.signals.AtTime("stale", 0.56), 0.0);
  // Half of the frames for 100 ms: about 50 lost, seeded.
  const ScenarioRun lossy =
      Run("lossy", "  - {at_s: 0.5, action: drop_frames, duration_s: 0.1, probability: 0.5}\n");
  EXPECT_NEAR(static_cast<double>(lossy.result.dropped_frames), 50.0, 20.0);
}

TEST_F(SensorFaultTest, AddedLatencyDelaysTheEstimateByExactlyThatMuch) {
  // Latency added before the grasp: the whole squeeze transient then arrives 10 ms late.
  const ScenarioRun clean = Run("clean", "");
  const ScenarioRun late = Run("late", "  - {at_s: 0.02, action: add_latency, latency_s: 0.01}\n");
  const Signals& a = clean.signals;
  const Signals& b = late.signals;
  double worst_shifted = 0.0;
  double worst_unshifted = 0.0;
  for (size_t r = b.RowAt(0.05); r < b.RowAt(0.45); ++r) {
    const double t = b.At("time_s", r);
    worst_shifted =
        std::max(worst_shifted, std::abs(b.At("est_total_fn_n", r) - a.AtTime("est_total_fn_n", t - 0.01)));
    worst_unshifted =
        std::max(worst_unshifted, std::abs(b.At("est_total_fn_n", r) - a.AtTime("est_total_fn_n", t)));
  }
  EXPECT_LT(worst_shifted, 1e-6);
  EXPECT_GT(worst_unshifted, 0.1);
  // The estimation error is scored against the truth at each frame's sample time, so a late frame
  // is not an estimation error.
  EXPECT_LT(*late.result.metrics.fn_rmse_n, 1e-6);
}

}  // namespace
}  // namespace graspbed::testbed
