// Metrics and expectations: every expectation kind evaluated passing and failing, the tracker's slip
// events, detection latency, false alarms, drops, stable window and estimation error on synthetic
// ticks, and expectations scored on real runs.
#include "testbed/metrics.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "testbed/runner.h"
#include "tests/support/temp_dir.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed::testbed {
namespace {

using graspbed::test_support::TempDir;
using test_support::HeldBoxScenario;
using test_support::RunScenarioText;
using test_support::ScenarioRun;

constexpr double kTimeTolS = 1e-9;
constexpr double kTickS = 0.001;  // control period of the synthetic ticks

// The outcome named `name` (fails the test when absent).
ExpectationOutcome Find(const std::vector<ExpectationOutcome>& outcomes, const std::string& name) {
  for (const ExpectationOutcome& o : outcomes) {
    if (o.name == name) return o;
  }
  ADD_FAILURE() << "no outcome " << name;
  return {};
}

bool Passes(const Expectations& e, const Metrics& m, const std::string& name) {
  return Find(EvaluateExpectations(e, m, MetricsConfig{}), name).passed;
}

// A held, clean run's metrics.
Metrics HeldMetrics() {
  Metrics m;
  m.grasped = true;
  m.grasp_time_s = 0.2;
  m.max_slip_mm = 1.5;
  m.peak_grip_n = 6.0;
  m.fn_rmse_n = 0.2;
  m.ft_rmse_n = 0.3;
  m.time_to_stable_s = 0.5;
  m.held_s = 60.0;
  m.sensed_grip_share = 0.9;
  m.contact_unit = 9;
  return m;
}

TEST(ExpectationsTest, NotDroppedPassesWhenHeldAndFailsWhenDroppedOrNeverGrasped) {
  Expectations e;
  e.not_dropped = true;
  Metrics m = HeldMetrics();
  EXPECT_TRUE(Passes(e, m, "not_dropped"));
  m.dropped = true;
  m.drop_time_s = 1.25;
  const ExpectationOutcome dropped = Find(EvaluateExpectations(e, m, MetricsConfig{}), "not_dropped");
  EXPECT_FALSE(dropped.passed);
  EXPECT_EQ(dropped.value_text, "dropped at 1.25 s");
  Metrics never;
  never.dropped = true;
  const ExpectationOutcome missed = Find(EvaluateExpectations(e, never, MetricsConfig{}), "not_dropped");
  EXPECT_FALSE(missed.passed);
  EXPECT_EQ(missed.value_text, "never grasped");
  // not_dropped: false asks for a drop.
  e.not_dropped = false;
  EXPECT_TRUE(Passes(e, m, "not_dropped"));
  EXPECT_FALSE(Passes(e, HeldMetrics(), "not_dropped"));
}

TEST(ExpectationsTest, LimitsPassAtAndBelowAndFailAbove) {
  Expectations e;
  e.max_slip_mm = 1.5;
  e.max_peak_grip_n = 6.0;
  e.stable_within_s = 0.5;
  e.max_false_slip_per_min = 1.0;
  Metrics m = HeldMetrics();
  m.false_slip_per_min = 1.0;
  for (const char* name : {"max_slip_mm", "max_peak_grip_n", "stable_within_s", "max_false_slip_per_min"}) {
    EXPECT_TRUE(Passes(e, m, name)) << name << " at its limit";
  }
  m.max_slip_mm = 1.6;
  m.peak_grip_n = 6.1;
  m.time_to_stable_s = 0.6;
  m.false_slip_per_min = 2.0;
  for (const char* name : {"max_slip_mm", "max_peak_grip_n", "stable_within_s", "max_false_slip_per_min"}) {
    EXPECT_FALSE(Passes(e, m, name)) << name << " above its limit";
  }
  const ExpectationOutcome slip = Find(EvaluateExpectations(e, m, MetricsConfig{}), "max_slip_mm");
  EXPECT_EQ(slip.limit, "<= 1.5 mm");
  EXPECT_EQ(slip.value_text, "1.6 mm");
  ASSERT_TRUE(slip.value.has_value());
  EXPECT_DOUBLE_EQ(*slip.value, 1.6);
  // Never stable fails and says so.
  m.time_to_stable_s.reset();
  const ExpectationOutcome never = Find(EvaluateExpectations(e, m, MetricsConfig{}), "stable_within_s");
  EXPECT_FALSE(never.passed);
  EXPECT_EQ(never.value_text, "never");
}

TEST(ExpectationsTest, NotCrushedFollowsTheCrushFlag) {
  Expectations e;
  e.not_crushed = true;
  Metrics m = HeldMetrics();
  EXPECT_TRUE(Passes(e, m, "not_crushed"));
  m.crushed = true;
  EXPECT_FALSE(Passes(e, m, "not_crushed"));
}

TEST(ExpectationsTest, SlipDetectionJudgesGrossSlipsAndTheMicroExpectationTheRest) {
  Expectations e;
  e.slip_detected_within_ms = 30.0;
  Metrics m = HeldMetrics();
  // No slip at all: nothing to detect, passes with a note.
  const ExpectationOutcome none = Find(EvaluateExpectations(e, m, MetricsConfig{}), "slip_detected_within_ms");
  EXPECT_TRUE(none.passed);
  EXPECT_EQ(none.value_text, "no gross slip");
  // Micro-slips missed do not fail it; only micro_slip_detected_within_ms asks for them.
  m.slip_events = 3;
  m.missed_slip_events = 3;
  m.micro = {3, 0, std::nullopt};
  EXPECT_TRUE(Passes(e, m, "slip_detected_within_ms"));
  e.micro_slip_detected_within_ms = 30.0;
  const ExpectationOutcome micro = Find(EvaluateExpectations(e, m, MetricsConfig{}), "micro_slip_detected_within_ms");
  EXPECT_FALSE(micro.passed);
  EXPECT_EQ(micro.value_text, "3 of 3 missed");
  e.micro_slip_detected_within_ms.reset();
  m.gross = {2, 2, 30.0};
  EXPECT_TRUE(Passes(e, m, "slip_detected_within_ms"));
  m.gross.worst_latency_ms = 31.0;
  EXPECT_FALSE(Passes(e, m, "slip_detected_within_ms"));
  m.gross = {2, 1, 5.0};
  const ExpectationOutcome missed = Find(EvaluateExpectations(e, m, MetricsConfig{}), "slip_detected_within_ms");
  EXPECT_FALSE(missed.passed);
  EXPECT_EQ(missed.value_text, "1 of 2 missed");
}

TEST(ExpectationsTest, GripEfficiencyIsJudgedAgainstTheOracleAndFailsWithoutOne) {
  Expectations e;
  e.max_grip_efficiency = 2.0;
  Metrics m = HeldMetrics();
  m.mean_held_grip_n = 3.0;
  const ExpectationOutcome unasked = Find(EvaluateExpectations(e, m, MetricsConfig{}), "max_grip_efficiency");
  EXPECT_FALSE(unasked.passed);
  EXPECT_EQ(unasked.note, "the run computed no oracle grip");
  ApplyOracle(OracleGrip{1.5, ""}, m);
  ASSERT_TRUE(m.grip_efficiency.has_value());
  EXPECT_DOUBLE_EQ(*m.grip_efficiency, 2.0);          // 3 N held on average over the 1.5 N oracle
  EXPECT_DOUBLE_EQ(*m.peak_grip_ratio, 6.0 / 1.5);  // the 6 N peak
  EXPECT_TRUE(Passes(e, m, "max_grip_efficiency"));
  m.mean_held_grip_n = 3.1;
  ApplyOracle(OracleGrip{1.5, ""}, m);
  EXPECT_FALSE(Passes(e, m, "max_grip_efficiency"));
  ApplyOracle(OracleGrip{std::nullopt, "not held at the motor's stall pinch of 20 N: dropped at 1.7 s"}, m);
  EXPECT_FALSE(m.grip_efficiency.has_value());
  EXPECT_FALSE(m.peak_grip_ratio.has_value());
  const ExpectationOutcome unholdable = Find(EvaluateExpectations(e, m, MetricsConfig{}), "max_grip_efficiency");
  EXPECT_FALSE(unholdable.passed);
  EXPECT_NE(unholdable.note.find("stall pinch"), std::string::npos) << unholdable.note;
}

TEST(ExpectationsTest, EstimationErrorTakesTheWorseOfFnAndFtAndFailsWithoutContact) {
  Expectations e;
  e.max_estimation_error_n = 0.3;
  Metrics m = HeldMetrics();  // Fn 0.2, Ft 0.3
  EXPECT_TRUE(Passes(e, m, "max_estimation_error_n"));
  m.ft_rmse_n = 0.31;
  EXPECT_FALSE(Passes(e, m, "max_estimation_error_n"));
  m.ft_rmse_n = 0.1;
  m.fn_rmse_n = 0.4;
  EXPECT_FALSE(Passes(e, m, "max_estimation_error_n"));
  m.fn_rmse_n.reset();
  m.ft_rmse_n.reset();
  const ExpectationOutcome unscored = Find(EvaluateExpectations(e, m, MetricsConfig{}), "max_estimation_error_n");
  EXPECT_FALSE(unscored.passed);
  EXPECT_EQ(unscored.value_text, "no contact");
}

TEST(ExpectationsTest, PhysicsFaultAndGraspedOnSensorAreAlwaysCheckedAndOnlyConfiguredOnesAppear) {
  Metrics m = HeldMetrics();
  std::vector<ExpectationOutcome> outcomes = EvaluateExpectations(Expectations{}, m, MetricsConfig{});
  ASSERT_EQ(outcomes.size(), 2u);
  EXPECT_EQ(outcomes[0].name, "grasped_on_sensor");
  EXPECT_TRUE(outcomes[0].passed);
  EXPECT_EQ(outcomes[1].name, "no_physics_fault");
  EXPECT_TRUE(outcomes[1].passed);
  m.physics_fault = true;
  m.physics_fault_cause = "NaN in qacc";
  m.physics_fault_time_s = 0.75;
  outcomes = EvaluateExpectations(Expectations{}, m, MetricsConfig{});
  EXPECT_FALSE(outcomes[1].passed);
  EXPECT_EQ(outcomes[1].value_text, "NaN in qacc");
  EXPECT_EQ(outcomes[1].note, "at t = 0.75 s");
  // Set false, grasped_on_sensor is not checked (a scene meant to be held off the pad).
  Expectations off_pad;
  off_pad.grasped_on_sensor = false;
  EXPECT_EQ(EvaluateExpectations(off_pad, m, MetricsConfig{}).size(), 1u);
}

// grasped_on_sensor fails a held object the units barely felt, by either of its limits, and says
// which; a run that never held anything passes it (not_dropped speaks for that).
TEST(ExpectationsTest, GraspedOnSensorFailsAnObjectHeldOffThePadByTimeOrByShare) {
  const MetricsConfig config;
  Metrics m = HeldMetrics();
  EXPECT_TRUE(Find(EvaluateExpectations(Expectations{}, m, config), "grasped_on_sensor").passed);
  m.unsensed_held_s = config.max_unsensed_held_s + 0.01;
  const ExpectationOutcome unsensed = Find(EvaluateExpectations(Expectations{}, m, config), "grasped_on_sensor");
  EXPECT_FALSE(unsensed.passed);
  EXPECT_NE(unsensed.note.find("with no unit loaded"), std::string::npos) << unsensed.note;
  m.unsensed_held_s = config.max_unsensed_held_s;  // at the limit: passes
  EXPECT_TRUE(Find(EvaluateExpectations(Expectations{}, m, config), "grasped_on_sensor").passed);
  m.sensed_grip_share = config.min_sensed_grip_share - 0.01;
  const ExpectationOutcome light = Find(EvaluateExpectations(Expectations{}, m, config), "grasped_on_sensor");
  EXPECT_FALSE(light.passed);
  EXPECT_NE(light.note.find("beside the pad"), std::string::npos) << light.note;
  EXPECT_NEAR(*light.value, config.min_sensed_grip_share - 0.01, 1e-12);
  Metrics never;
  EXPECT_TRUE(Find(EvaluateExpectations(Expectations{}, never, config), "grasped_on_sensor").passed);
}

TEST(SummaryTableTest, EstimationErrorKeepsItsSignificantDigits) {
  RunResult result;
  result.completed = true;
  result.metrics = HeldMetrics();
  result.metrics.fn_rmse_n = 9.7e-16;  // an ideal sensor: the inversion is exact up to rounding
  result.metrics.ft_rmse_n = 0.000123;
  const std::string table = SummaryTable(result);
  EXPECT_NE(table.find("Fn RMSE 9.7e-16 N, Ft RMSE 0.000123 N"), std::string::npos) << table;
  result.metrics.fn_rmse_n.reset();
  result.metrics.ft_rmse_n.reset();
  EXPECT_NE(SummaryTable(result).find("Fn RMSE none, Ft RMSE none"), std::string::npos);
}

// ---- MetricsTracker on synthetic ticks -------------------------------------------------------------------

// Drives a tracker with a held object: every tick says both digits touch with 2 N; the test sets the
// slip speed, the object offset and the controller flag per tick.
class TrackerTest : public ::testing::Test {
 protected:
  TrackerTest() : tracker_(MetricsConfig{}, /*crush_limit_n=*/8.0, /*contact_threshold_n=*/0.05) {
    truth_.finger_contacts = 1;
    truth_.thumb_contacts = 1;
    truth_.finger_normal_force_n = 2.0;
    truth_.object_squeeze_n = 2.0;
    // Lifted off the table: the grasp is established at the first touch (no acquisition).
    truth_.object_height_above_table_m = 0.01;
    state_.unit_count = 1;
    loads_[0].fn_n = 1.0;
    state_.fn_n[0] = 1.0;
  }

  // Ticks from the current time up to `until_s` (exclusive) with the given sliding speed (at the
  // friction limit; the fastest contact moves at least as fast) and flag.
  void Run(double until_s, double sliding_speed_m_s, bool flag = false,
           controller::GraspIntent intent = controller::GraspIntent::kClose) {
    RunContacts(until_s, sliding_speed_m_s, sliding_speed_m_s, flag, intent);
  }

  // The same with the fastest contact's speed given apart: motion inside the friction cone.
  void RunContacts(double until_s, double contact_speed_m_s, double sliding_speed_m_s, bool flag = false,
                   controller::GraspIntent intent = controller::GraspIntent::kClose) {
    while (time_s_ < until_s - kTimeTolS) {
      truth_.time_s = time_s_;
      truth_.slip_speed_m_s = contact_speed_m_s;
      truth_.sliding_speed_m_s = sliding_speed_m_s;
      truth_.sliding_load_share = sliding_speed_m_s > 0.0 ? sliding_share_ : 0.0;
      TickSample sample;
      sample.time_s = time_s_;
      sample.intent = intent;
      sample.truth = &truth_;
      sample.state = &state_;
      sample.true_loads = loads_;
      sample.controller_slip = flag;
      sample.controller_cues = cues_;
      tracker_.Update(sample);
      time_s_ += kTickS;
    }
  }

  MetricsTracker tracker_;
  sim::GroundTruth truth_;
  sensor::TactileState state_;
  std::array<sensor::UnitLoad, 1> loads_{};
  double time_s_ = 0.0;
  double sliding_share_ = 1.0;  ///< share of the digit's force on the sliding contacts, while sliding
  const char* cues_ = "";       ///< the controller's slip_cues label on the next ticks
};

TEST_F(TrackerTest, SlipEventDetectedLateGivesItsLatencyAndDistance) {
  Run(0.5, 0.0);
  Run(0.52, 0.01);       // slipping at 10 mm/s, not flagged for 20 ms
  Run(0.6, 0.01, true);  // flagged from 0.52 s
  Run(1.0, 0.0);
  const Metrics m = tracker_.Finish(1.0, 0.1, 0.0);
  EXPECT_EQ(m.slip_events, 1);
  EXPECT_EQ(m.missed_slip_events, 0);
  ASSERT_TRUE(m.slip_detect_latency_ms.has_value());
  EXPECT_NEAR(*m.slip_detect_latency_ms, 20.0, 1e-6);
  EXPECT_NEAR(m.max_slip_mm, 0.01 * 0.1 * 1e3, 0.02);  // 10 mm/s for 0.1 s
  EXPECT_EQ(m.false_slip_flags, 0);
  EXPECT_FALSE(m.dropped);
  ASSERT_EQ(m.events.size(), 1u);
  EXPECT_NEAR(m.events[0].onset_s, 0.5, kTimeTolS);
}

TEST_F(TrackerTest, EarlyFlagCountsAsZeroLatencyAndUnmatchedFlagsAreFalseAlarms) {
  Run(0.3, 0.0);
  Run(0.31, 0.0, true);  // a false alarm, long before any slip
  Run(0.5, 0.0);
  Run(0.51, 0.0, true);  // flagged 10 ms before the slip starts (incipient slip)
  Run(0.6, 0.01, true);
  Run(1.0, 0.0);
  const Metrics m = tracker_.Finish(1.0, 0.1, 0.0);
  EXPECT_EQ(m.slip_events, 1);
  ASSERT_TRUE(m.slip_detect_latency_ms.has_value());
  EXPECT_EQ(*m.slip_detect_latency_ms, 0.0);
  EXPECT_EQ(m.controller_slip_flags, 2);
  EXPECT_EQ(m.false_slip_flags, 1);
  EXPECT_NEAR(m.false_slip_per_min, 1.0 / (m.held_s / 60.0), 1e-9);
}

// A slip while no unit carries load (the object sliding on an unsensed part of the finger) is
// missed like any other, and counted apart as one the sensor could not report; a slip during which
// a unit reaches the contact threshold, even for one tick, was sensed.
TEST_F(TrackerTest, AMissedSlipWithNoUnitLoadedIsCountedApart) {
  Run(0.5, 0.0);
  loads_[0].fn_n = 0.049;  // just under the 0.05 N contact threshold
  Run(0.55, 0.01);         // unflagged slip, nothing on the sensor
  Run(0.7, 0.0);
  Run(0.75, 0.01);  // a second unflagged slip, which reaches the threshold on its last tick
  loads_[0].fn_n = 0.05;
  Run(0.751, 0.01);
  loads_[0].fn_n = 0.0;
  Run(1.0, 0.0);
  const Metrics m = tracker_.Finish(1.0, 0.1, 0.0);
  ASSERT_EQ(m.slip_events, 2);
  EXPECT_EQ(m.missed_slip_events, 2);
  EXPECT_EQ(m.missed_unsensed_slip_events, 1);
  ASSERT_EQ(m.events.size(), 2u);
  EXPECT_FALSE(m.events[0].sensed);
  EXPECT_TRUE(m.events[1].sensed);
  // Flagged, an unsensed slip is a detection and not counted apart.
  MetricsTracker flagged(MetricsConfig{}, 8.0, 0.05);
  TickSample sample;
  truth_.sliding_load_share = 1.0;
  for (int tick = 0; tick < 300; ++tick) {
    const double t = 0.5 + tick * kTickS;
    truth_.time_s = t;
    truth_.slip_speed_m_s = truth_.sliding_speed_m_s = tick < 50 ? 0.0 : 0.01;
    sample.time_s = t;
    sample.intent = controller::GraspIntent::kClose;
    sample.truth = &truth_;
    sample.state = &state_;
    sample.true_loads = loads_;
    sample.controller_slip = tick >= 60;
    flagged.Update(sample);
  }
  const Metrics f = flagged.Finish(0.8, 0.1, 0.0);
  EXPECT_EQ(f.slip_events, 1);
  EXPECT_EQ(f.missed_slip_events, 0);
  EXPECT_EQ(f.missed_unsensed_slip_events, 0);
}

// A missed slip where only the thumb slid (the sensed finger's contact stuck) is counted apart; one
// where the finger slid, alone or with the thumb, is not. A digit counts when it slid faster than the
// event's speed at one of its ticks.
TEST_F(TrackerTest, AMissedSlipOfTheThumbAloneIsCountedApart) {
  Run(0.3, 0.0);
  truth_.thumb_sliding_speed_m_s = 0.01;
  Run(0.35, 0.01);  // the thumb alone
  truth_.thumb_sliding_speed_m_s = 0.0;
  Run(0.5, 0.0);
  truth_.finger_sliding_speed_m_s = 0.01;
  Run(0.55, 0.01);  // the finger alone
  truth_.finger_sliding_speed_m_s = 0.0;
  Run(0.7, 0.0);
  truth_.thumb_sliding_speed_m_s = 0.01;
  Run(0.74, 0.01);
  truth_.finger_sliding_speed_m_s = 0.0021;  // both, the finger just over the 2 mm/s event speed
  Run(0.75, 0.01);
  truth_.finger_sliding_speed_m_s = truth_.thumb_sliding_speed_m_s = 0.0;
  Run(1.0, 0.0);
  const Metrics m = tracker_.Finish(1.0, 0.1, 0.0);
  ASSERT_EQ(m.events.size(), 3u);
  EXPECT_EQ(m.missed_slip_events, 3);
  EXPECT_EQ(m.missed_thumb_only_slip_events, 1);
  EXPECT_TRUE(m.events[0].thumb_slid && !m.events[0].finger_slid);
  EXPECT_TRUE(m.events[1].finger_slid && !m.events[1].thumb_slid);
  EXPECT_TRUE(m.events[2].finger_slid && m.events[2].thumb_slid);
}

// False flags are counted by the controller's cue label at their rise; a flag after sliding
// (incipient) and a flag that detects an event are not false and not counted.
TEST_F(TrackerTest, FalseFlagsAreCountedByTheControllersCueLabel) {
  const auto flag = [&](double from_s, const char* cues) {
    Run(from_s, 0.0);
    cues_ = cues;
    Run(from_s + 0.01, 0.0, true);
    cues_ = "";
  };
  Run(0.3, 0.0);
  flag(0.3, "vibration");
  flag(0.5, "centroid");
  flag(0.7, "vibration");
  flag(0.9, "");
  Run(1.1, 0.001);  // sliding at 1 mm/s: above creep speed, below an event
  cues_ = "ratio";
  Run(1.11, 0.0, true);  // incipient, not false
  cues_ = "vibration";
  Run(1.3, 0.0);
  Run(1.4, 0.01, true);  // detects the slip: not false
  Run(1.6, 0.0);
  const Metrics m = tracker_.Finish(1.6, 0.1, 0.0);
  EXPECT_EQ(m.false_slip_flags, 4);
  EXPECT_EQ(m.incipient_slip_flags, 1);
  EXPECT_EQ(m.slip_events, 1);
  EXPECT_EQ(m.missed_slip_events, 0);
  const std::map<std::string, int> expected = {{"vibration", 2}, {"centroid", 1}, {"(none)", 1}};
  EXPECT_EQ(m.false_slip_flags_by_cue, expected);
}

TEST_F(TrackerTest, UnflaggedSlipIsMissedAndCreepIsNoSlip) {
  Run(0.5, 0.0003);  // below the creep speed: no slip distance
  Run(0.6, 0.01);    // never flagged
  Run(1.0, 0.0);
  const Metrics m = tracker_.Finish(1.0, 0.1, 0.0);
  EXPECT_EQ(m.slip_events, 1);
  EXPECT_EQ(m.missed_slip_events, 1);
  EXPECT_FALSE(m.slip_detect_latency_ms.has_value());
  EXPECT_NEAR(m.max_slip_mm, 1.0, 0.02);
  Expectations e;
  e.slip_detected_within_ms = 1000.0;
  EXPECT_FALSE(Passes(e, m, "slip_detected_within_ms"));
}

TEST_F(TrackerTest, ContactsMovingInsideTheFrictionConeAreNoSlip) {
  // A shake rocks the object against the pads at 20 mm/s with the friction inside its cone (the
  // soft contact's give): no event, no slip distance. The same speed at the cone's edge is slip.
  Run(0.5, 0.0);
  RunContacts(0.8, 0.02, 0.0);
  Metrics m = tracker_.Finish(0.8, 0.1, 0.0);
  EXPECT_EQ(m.slip_events, 0);
  EXPECT_EQ(m.max_slip_mm, 0.0);
  RunContacts(0.9, 0.02, 0.02);
  m = tracker_.Finish(0.9, 0.1, 0.0);
  EXPECT_EQ(m.slip_events, 1);
  EXPECT_NEAR(m.max_slip_mm, 2.0, 0.05);  // 20 mm/s for 0.1 s
}

TEST_F(TrackerTest, AFlagAfterSlidingTooSlowForAnEventIsIncipientNotFalse) {
  // A contact slides at the friction limit at 1 mm/s for 10 ms (above creep, below the 2 mm/s of an
  // event: a load landing); a flag 20 ms later is an incipient-slip flag. A flag with no sliding
  // before it is false, and so is one whose only sliding comes after it (the response's own).
  Run(0.5, 0.0);
  Run(0.51, 0.001);
  Run(0.53, 0.0);
  Run(0.54, 0.0, true);
  Run(0.8, 0.0);
  Run(0.81, 0.0, true);
  Run(1.2, 0.0);
  Run(1.21, 0.0, true);
  Run(1.22, 0.001);
  Run(1.5, 0.0);
  const Metrics m = tracker_.Finish(1.5, 0.1, 0.0);
  EXPECT_EQ(m.slip_events, 0);
  EXPECT_EQ(m.incipient_slip_flags, 1);
  EXPECT_EQ(m.false_slip_flags, 2);
}

TEST_F(TrackerTest, PartialSlipAtALightlyLoadedContactIsNoEventButMakesAFlagIncipient) {
  // One contact carrying 5 % of the digit's force slides at 5 mm/s for 50 ms while the rest stick
  // (the default slip_min_load_share is 0.2): no event, no slip distance, 0.25 mm of partial slip,
  // and a flag 10 ms later is incipient. The same sliding with 30 % of the force is a slip event.
  sliding_share_ = 0.05;
  Run(0.5, 0.0);
  Run(0.55, 0.005);
  Run(0.56, 0.0);
  Run(0.57, 0.0, true);
  Run(0.8, 0.0);
  Metrics m = tracker_.Finish(0.8, 0.1, 0.0);
  EXPECT_EQ(m.slip_events, 0);
  EXPECT_EQ(m.max_slip_mm, 0.0);
  EXPECT_NEAR(m.partial_slip_mm, 0.25, 0.01);
  EXPECT_EQ(m.incipient_slip_flags, 1);
  EXPECT_EQ(m.false_slip_flags, 0);
  sliding_share_ = 0.3;
  Run(0.85, 0.005);
  Run(1.0, 0.0);
  m = tracker_.Finish(1.0, 0.1, 0.0);
  EXPECT_EQ(m.slip_events, 1);
  EXPECT_NEAR(m.max_slip_mm, 0.25, 0.01);
  EXPECT_NEAR(m.partial_slip_mm, 0.25, 0.01);
}

/// Runs a tracker with `config` over held ticks 0 .. end_s at 1 kHz, the object sliding at the
/// friction limit at `speed_m_s(t)` and the controller flagging where `flag(t)`; returns its metrics.
template <typename Speed, typename Flag>
Metrics RunHeld(const MetricsConfig& config, double end_s, Speed speed_m_s, Flag flag) {
  MetricsTracker tracker(config, /*crush_limit_n=*/8.0, /*contact_threshold_n=*/0.05);
  sim::GroundTruth truth;
  truth.finger_contacts = truth.thumb_contacts = 1;
  truth.finger_normal_force_n = truth.object_squeeze_n = 2.0;
  sensor::TactileState state;
  for (int tick = 0; tick * kTickS <= end_s + kTimeTolS; ++tick) {
    const double t = tick * kTickS;
    truth.slip_speed_m_s = truth.sliding_speed_m_s = speed_m_s(t);
    truth.sliding_load_share = 1.0;
    TickSample sample;
    sample.time_s = t;
    sample.intent = controller::GraspIntent::kClose;
    sample.truth = &truth;
    sample.state = &state;
    sample.controller_slip = flag(t);
    tracker.Update(sample);
  }
  return tracker.Finish(end_s, 0.1, 0.0);
}

/// True for t in [from_s, to_s) at tick resolution.
bool Within(double t, double from_s, double to_s) { return t >= from_s - kTimeTolS && t < to_s - kTimeTolS; }

TEST(TrackerCreepTest, ASlowSlideIsAnEventOnceItHasCreptFarEnoughWithItsOnsetAtItsStart) {
  // 1 mm/s at the friction limit for 0.3 s (0.3 mm; under the 2 mm/s of a slip event), flagged
  // 40 ms after it began.
  const auto run = [](double creep_event_m) {
    MetricsConfig config;
    config.creep_event_m = creep_event_m;
    return RunHeld(
        config, 1.0, [](double t) { return Within(t, 0.5, 0.8) ? 0.001 : 0.0; },
        [](double t) { return Within(t, 0.54, 0.6); });
  };
  const Metrics counted = run(0.2e-3);
  ASSERT_EQ(counted.slip_events, 1);
  EXPECT_EQ(counted.missed_slip_events, 0);
  ASSERT_EQ(counted.events.size(), 1u);
  EXPECT_NEAR(counted.events[0].onset_s, 0.5, 1e-9);
  EXPECT_NEAR(*counted.slip_detect_latency_ms, 40.0, 1e-6);
  EXPECT_EQ(counted.false_slip_flags + counted.incipient_slip_flags, 0);
  // The creep's distance counts from its onset.
  EXPECT_NEAR(counted.events[0].distance_m, 0.3e-3, 0.01e-3);
  // Off (the default): no event; the flag followed sliding, so it is an incipient-slip flag.
  const Metrics off = run(0.0);
  EXPECT_EQ(off.slip_events, 0);
  EXPECT_EQ(off.incipient_slip_flags, 1);
  EXPECT_NEAR(off.max_slip_mm, 0.3, 0.01);
}

TEST(TrackerCreepTest, SlidingOnAfterAFastSlipIsANewCreepNotAnEarlierOne) {
  // Creep at 1 mm/s from 0.5 s, a burst at 10 mm/s at 0.55 - 0.56 s, creep again until 1.0 s. The
  // burst's event closes 50 ms after it with 0.2 mm slid, under the 0.3 mm of a creep event; the
  // creep that goes on is a second event, with its onset after the first ended (not at 0.5 s).
  MetricsConfig config;
  config.creep_event_m = 0.3e-3;
  const Metrics m = RunHeld(
      config, 1.5,
      [](double t) { return Within(t, 0.55, 0.56) ? 0.01 : (Within(t, 0.5, 1.0) ? 0.001 : 0.0); },
      [](double) { return false; });
  ASSERT_EQ(m.slip_events, 2);
  EXPECT_NEAR(m.events[0].onset_s, 0.55, 1e-9);
  EXPECT_GT(m.events[1].onset_s, m.events[0].end_s);
}

TEST_F(TrackerTest, ObjectLeavingTheHandIsADropAndOpeningIsNot) {
  Run(0.2, 0.0);
  truth_.object_position_m = {0.0, 0.0, -0.025};  // 25 mm below where it was grasped
  Run(0.3, 0.0);
  const Metrics dropped = tracker_.Finish(0.3, 0.1, 0.0);
  EXPECT_TRUE(dropped.dropped);
  EXPECT_NEAR(dropped.drop_time_s, 0.2, kTimeTolS);

  MetricsTracker released(MetricsConfig{}, 0.0, 0.05);
  TickSample sample;
  sample.truth = &truth_;
  sample.state = &state_;
  sample.true_loads = loads_;
  truth_.object_position_m = {0.0, 0.0, 0.0};
  for (int i = 0; i < 300; ++i) {
    sample.time_s = i * kTickS;
    sample.intent = i < 200 ? controller::GraspIntent::kClose : controller::GraspIntent::kOpen;
    if (i >= 200) truth_.object_position_m = {0.0, 0.0, -0.05};
    released.Update(sample);
  }
  EXPECT_FALSE(released.Finish(0.3, 0.1, 0.0).dropped);
}

TEST_F(TrackerTest, MeanGripIsOverTheHeldTimeAndTheLoadBoundItsPeak) {
  // Not held yet (intent idle): a 9 N squeeze then counts in the peak, not in the mean held.
  truth_.object_squeeze_n = 9.0;
  Run(0.1, 0.0, false, controller::GraspIntent::kIdle);
  truth_.object_squeeze_n = 2.0;
  truth_.load_bound_grip_n = 0.3;
  Run(0.6, 0.0);
  truth_.object_squeeze_n = 4.0;
  truth_.load_bound_grip_n = 0.9;
  Run(1.1, 0.0);
  const Metrics m = tracker_.Finish(1.1, 0.1, 0.1);
  EXPECT_DOUBLE_EQ(m.peak_grip_n, 9.0);
  EXPECT_NEAR(m.held_s, 1.0, 2 * kTickS);
  EXPECT_NEAR(m.mean_held_grip_n, 3.0, 0.01);  // half the held time at 2 N, half at 4 N
  EXPECT_DOUBLE_EQ(m.peak_load_bound_grip_n, 0.9);
}

TEST_F(TrackerTest, SlipsAreGrossFromTheirSizeOrADropAndCountedByClass) {
  Run(0.3, 0.0);
  Run(0.33, 0.01, true);  // 0.3 mm, flagged: a micro-slip
  Run(0.5, 0.0);
  Run(0.56, 0.01);  // 0.6 mm, missed: a gross slip
  Run(0.8, 0.0);
  Run(0.82, 0.01);  // 0.2 mm, missed: micro
  Run(1.0, 0.0);
  const Metrics m = tracker_.Finish(1.0, 0.1, 0.0);
  ASSERT_EQ(m.events.size(), 3u);
  EXPECT_FALSE(m.events[0].gross);
  EXPECT_TRUE(m.events[1].gross);
  EXPECT_FALSE(m.events[2].gross);
  EXPECT_EQ(m.micro.events, 2);
  EXPECT_EQ(m.micro.detected, 1);
  EXPECT_EQ(m.gross.events, 1);
  EXPECT_EQ(m.gross.detected, 0);
  EXPECT_FALSE(m.gross.worst_latency_ms.has_value());
  // A drop makes the slip it ends in gross, however short; a drop without an open slip is an event.
  MetricsTracker dropping(MetricsConfig{}, 8.0, 0.05);
  TickSample sample;
  sample.truth = &truth_;
  sample.state = &state_;
  sample.true_loads = loads_;
  sample.intent = controller::GraspIntent::kClose;
  truth_.slip_speed_m_s = truth_.sliding_speed_m_s = 0.0;
  for (int tick = 0; tick < 400; ++tick) {
    sample.time_s = tick * kTickS;
    if (tick == 300) truth_.object_position_m = {0.0, 0.0, -0.03};  // gone at once
    dropping.Update(sample);
    if (tick == 301) {
      EXPECT_FALSE(dropping.in_slip_event()) << "the drop's event closes with the hold";
    }
  }
  const Metrics d = dropping.Finish(0.4, 0.1, 0.0);
  EXPECT_TRUE(d.dropped);
  ASSERT_EQ(d.events.size(), 1u);
  EXPECT_TRUE(d.events[0].ends_in_drop);
  EXPECT_TRUE(d.events[0].gross);
  EXPECT_EQ(d.gross.events, 1);
}

TEST_F(TrackerTest, ACloseThatNeverGraspsIsCounted) {
  Run(0.3, 0.0);  // grasped at once (both digits touch)
  Run(0.4, 0.0, false, controller::GraspIntent::kOpen);
  truth_.finger_contacts = 0;  // the second close misses the object
  Run(0.8, 0.0);
  Run(0.9, 0.0, false, controller::GraspIntent::kOpen);
  Run(1.0, 0.0);  // and so does the third, until the run ends
  const Metrics m = tracker_.Finish(1.0, 0.1, 0.0);
  EXPECT_TRUE(m.grasped);
  EXPECT_FALSE(m.dropped);
  EXPECT_EQ(m.ungrasped_closes, 2);
}

TEST_F(TrackerTest, StableWindowAndCrushAndEstimationError) {
  // Squeeze wobbling by 50 % for 0.3 s, then steady: stable from the steady part on.
  for (int i = 0; i < 300; ++i) {
    truth_.object_squeeze_n = (i % 2 == 0) ? 2.0 : 3.0;
    Run(time_s_ + kTickS, 0.0);
  }
  truth_.object_squeeze_n = 9.0;  // above the 8 N crush limit
  state_.fn_n[0] = 1.5;           // the estimate reads 0.5 N high
  state_.ft_n[0] = -0.2;
  Run(0.8, 0.0);
  const Metrics m = tracker_.Finish(0.8, 0.1, /*first_close_time_s=*/0.1);
  ASSERT_TRUE(m.time_to_stable_s.has_value());
  EXPECT_NEAR(*m.time_to_stable_s, 0.3 - 0.1, 2 * kTickS);
  EXPECT_TRUE(m.crushed);
  EXPECT_DOUBLE_EQ(m.peak_grip_n, 9.0);
  ASSERT_TRUE(m.fn_rmse_n.has_value());
  // RMSE over 300 exact ticks and 500 ticks 0.5 N off.
  EXPECT_NEAR(*m.fn_rmse_n, std::sqrt(500 * 0.25 / 800), 1e-9);
  EXPECT_NEAR(*m.ft_rmse_n, std::sqrt(500 * 0.04 / 800), 1e-9);
  EXPECT_EQ(m.estimation_samples, 800);
}

// ---- expectations on real runs
// -----------------------------------------------------------------------------

TEST(ExpectationsOnRunsTest, FragileObjectCrushedByAHardGripAndSparedByASoftOne) {
  TempDir dir;
  const std::string fragile = R"(duration_s: 0.3
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.7, crush_limit_n: 6}
hand: {model: jaw, open_gap_m: 0.055}
script:
  - {at_s: 0.04, action: close}
expectations: {not_crushed: true, max_peak_grip_n: 6}
controller:
  name: open_loop
  params:
)";
  const ScenarioRun hard = RunScenarioText(dir, "hard", fragile + "    close_effort: 0.5\n");
  EXPECT_TRUE(hard.result.metrics.crushed);
  EXPECT_GT(hard.result.metrics.peak_grip_n, 6.0);
  EXPECT_FALSE(Find(hard.result.outcomes, "not_crushed").passed);
  EXPECT_FALSE(Find(hard.result.outcomes, "max_peak_grip_n").passed);
  EXPECT_FALSE(hard.result.passed);
  const ScenarioRun soft = RunScenarioText(dir, "soft", fragile + "    close_effort: 0.15\n");
  EXPECT_FALSE(soft.result.metrics.crushed);
  EXPECT_TRUE(Find(soft.result.outcomes, "not_crushed").passed);
  EXPECT_TRUE(soft.result.passed);
}

TEST(ExpectationsOnRunsTest, EstimationErrorGrowsWithSensorNoiseAsTheModelPredicts) {
  TempDir dir;
  // Ideal sensor: the inversion is exact, the RMSE is rounding.
  const ScenarioRun ideal = RunScenarioText(
      dir, "ideal", HeldBoxScenario(0.3, "", "expectations: {max_estimation_error_n: 0.01}\n"));
  ASSERT_TRUE(ideal.result.metrics.fn_rmse_n.has_value());
  EXPECT_LT(*ideal.result.metrics.fn_rmse_n, 1e-9);
  EXPECT_GT(ideal.result.metrics.estimation_samples, 100);
  EXPECT_TRUE(ideal.result.passed);
  // 3 Ohm of white noise per channel: Fn noise = sqrt(2) * 3 / R0 / (2 G kn) = 11 mN, Ft = 15 mN
  // (plus a little from the tare's own noise).
  const ScenarioRun noisy = RunScenarioText(
      dir, "noisy",
      HeldBoxScenario(
          0.3, "", "sensor: {strain_model: {noise_ohm: 3}}\nexpectations: {max_estimation_error_n: 0.01}\n"));
  EXPECT_NEAR(*noisy.result.metrics.fn_rmse_n, 0.0113, 0.003);
  EXPECT_NEAR(*noisy.result.metrics.ft_rmse_n, 0.0152, 0.004);
  EXPECT_FALSE(Find(noisy.result.outcomes, "max_estimation_error_n").passed);
  EXPECT_FALSE(noisy.result.passed);
}

TEST(ExpectationsOnRunsTest, SlipUnderASuddenPullIsCaughtByGripSlipAndMissedByAWeakOpenLoopGrip) {
  TempDir dir;
  // Grasped, lifted slowly (no slip), then an 8 N downward pull at once.
  const std::string scenario = R"(duration_s: 1.0
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.7}
hand: {model: jaw, open_gap_m: 0.055}
script:
  - {at_s: 0.04, action: close}
  - {at_s: 0.3, action: lift, height_m: 0.03, duration_s: 0.5}
  - {at_s: 0.85, action: pull, force_n: [0, 0, -8]}
expectations: {slip_detected_within_ms: 50, not_dropped: true}
)";
  const ScenarioRun seeing = RunScenarioText(dir, "seeing", scenario + "controller: {name: grip_slip}\n");
  EXPECT_GE(seeing.result.metrics.slip_events, 1);
  EXPECT_GE(seeing.result.metrics.controller_slip_flags, 1);
  EXPECT_TRUE(Find(seeing.result.outcomes, "slip_detected_within_ms").passed)
      << Find(seeing.result.outcomes, "slip_detected_within_ms").value_text;
  EXPECT_TRUE(Find(seeing.result.outcomes, "not_dropped").passed);
  EXPECT_TRUE(seeing.result.passed);
  // A blind 6 N pinch (capacity about 8.4 N) loses the box and never flags the slip.
  const ScenarioRun blind = RunScenarioText(
      dir, "blind", scenario + "controller: {name: open_loop, params: {close_effort: 0.3}}\n");
  EXPECT_GE(blind.result.metrics.slip_events, 1);
  EXPECT_EQ(blind.result.metrics.missed_slip_events, blind.result.metrics.slip_events);
  EXPECT_EQ(blind.result.metrics.controller_slip_flags, 0);
  EXPECT_FALSE(Find(blind.result.outcomes, "slip_detected_within_ms").passed);
  EXPECT_FALSE(Find(blind.result.outcomes, "not_dropped").passed);
  EXPECT_GT(blind.result.metrics.drop_time_s, 0.85);
}


// Acquisition: an object on the table that the closing digits push 1 mm and that then stays put is
// established once still for acquisition_settle_s; the push is acquisition_shift_mm, not slip, and
// the held time starts there.
TEST_F(TrackerTest, AnObjectPushedWhileTheDigitsCloseIsAcquisitionNotSlip) {
  const MetricsConfig config;
  truth_.object_height_above_table_m = 0.0;  // on the table: only settling establishes the grasp
  Run(0.1, 0.0, false, controller::GraspIntent::kIdle);
  // 0.1 .. 0.2 s: closing, touching, the object pushed 1 mm along x at 10 mm/s, sliding on the pad.
  while (time_s_ < 0.2 - kTimeTolS) {
    truth_.object_position_m[0] = 0.01 * (time_s_ - 0.1);
    Run(time_s_ + kTickS, 0.01);
  }
  // Still means within acquisition_settle_m of one place: the stretch began when the push last
  // crossed that band, at most settle_m / speed before it stopped.
  const double band_s = config.acquisition_settle_m / 0.01;
  Run(0.2 + config.acquisition_settle_s - band_s - 2 * kTickS, 0.0);
  EXPECT_FALSE(tracker_.holding());
  Run(0.2 + config.acquisition_settle_s + 2 * kTickS, 0.0);
  EXPECT_TRUE(tracker_.holding());
  Run(1.0, 0.0);
  const Metrics m = tracker_.Finish(1.0, 0.1, 0.1);
  EXPECT_TRUE(m.grasped);
  EXPECT_FALSE(m.dropped);
  EXPECT_NEAR(m.contact_time_s, 0.1, 1e-9);
  EXPECT_GE(m.grasp_time_s, 0.2 + config.acquisition_settle_s - band_s - kTickS);
  EXPECT_LE(m.grasp_time_s, 0.2 + config.acquisition_settle_s + kTickS);
  EXPECT_NEAR(m.acquisition_shift_mm, 1.0, 0.02);
  EXPECT_EQ(m.max_slip_mm, 0.0);
  EXPECT_EQ(m.slip_events, 0);
  EXPECT_NEAR(m.held_s, 1.0 - m.grasp_time_s, 2 * kTickS);
}

// An object that keeps creeping on the table is established acquisition_max_s after the touch, and
// from then its motion is slip.
TEST_F(TrackerTest, AGraspStillMovingWhenTheAcquisitionTimeIsUpIsEstablishedAndSlipsFromThere) {
  const MetricsConfig config;
  truth_.object_height_above_table_m = 0.0;
  while (time_s_ < 1.0 - kTimeTolS) {
    truth_.object_position_m[2] = -0.005 * time_s_;  // 5 mm/s downwards, relative to the still wrist
    Run(time_s_ + kTickS, 0.005);
  }
  const Metrics m = tracker_.Finish(1.0, 0.1, 0.0);
  EXPECT_NEAR(m.grasp_time_s, config.acquisition_max_s, 2 * kTickS);
  EXPECT_NEAR(m.acquisition_shift_mm, 5.0 * config.acquisition_max_s, 0.05);
  EXPECT_NEAR(m.max_slip_mm, 5.0 * (1.0 - config.acquisition_max_s), 0.05);
  EXPECT_EQ(m.slip_events, 1);
}

// Pushed out: more than drop_distance_m from where it was at the close, before the grasp is
// established, is a failed grasp and a drop; the wrist lifting away from an object the digits never
// reached counts the same.
TEST_F(TrackerTest, AnObjectPushedOutOrLeftBehindBeforeTheGraspIsEstablishedIsDropped) {
  const MetricsConfig config;
  truth_.object_height_above_table_m = 0.0;
  while (time_s_ < 0.1 - kTimeTolS) {
    truth_.object_position_m[1] = 0.25 * time_s_;  // 25 mm in 0.1 s, sideways out of the pinch
    Run(time_s_ + kTickS, 0.25);
  }
  const Metrics m = tracker_.Finish(0.1, 0.1, 0.0);
  EXPECT_TRUE(m.pushed_out);
  EXPECT_TRUE(m.dropped);
  EXPECT_FALSE(m.grasped);
  EXPECT_NEAR(m.drop_time_s, config.drop_distance_m / 0.25, 2 * kTickS);
  Expectations held;
  held.not_dropped = true;
  const ExpectationOutcome dropped = Find(EvaluateExpectations(held, m, config), "not_dropped");
  EXPECT_FALSE(dropped.passed);
  EXPECT_EQ(dropped.value_text.rfind("pushed out at", 0), 0u) << dropped.value_text;

  MetricsTracker late(config, 8.0, 0.05);
  sim::GroundTruth truth = truth_;
  truth.object_position_m = {0.0, 0.0, 0.0};
  TickSample sample;
  sample.intent = controller::GraspIntent::kClose;
  sample.truth = &truth;
  sample.state = &state_;
  sample.true_loads = loads_;
  for (int tick = 0; tick < 1000; ++tick) {
    sample.time_s = truth.time_s = tick * kTickS;
    // The wrist rises 50 mm in the first 0.5 s with nothing in the hand; the digits touch after.
    truth.wrist_position_m[2] = 0.05 * std::min(1.0, sample.time_s / 0.5);
    truth.finger_contacts = truth.thumb_contacts = sample.time_s >= 0.6 ? 1 : 0;
    late.Update(sample);
  }
  const Metrics left_behind = late.Finish(1.0, 0.1, 0.0);
  EXPECT_TRUE(left_behind.pushed_out);
  EXPECT_TRUE(left_behind.dropped);
}

// Where the held object sits on the sensor: the mesas' share of the finger's normal force over the
// held time, the time with no unit loaded, and the unit that carried most.
TEST_F(TrackerTest, TheSensedShareAndTheUnsensedTimeAreOverTheHeldTime) {
  truth_.finger_object_normal_force_n = 4.0;
  truth_.sensed_object_normal_force_n = 3.0;
  truth_.finger_normal_force_n = 9.0;  // the fingertip also on the table: not the object's share
  Run(0.5, 0.0);
  truth_.sensed_object_normal_force_n = 1.0;  // the rest of the run less on the mesas
  loads_[0].fn_n = 0.01;               // and no unit above the 0.05 N contact threshold
  Run(1.0, 0.0);
  const Metrics m = tracker_.Finish(1.0, 0.1, 0.0);
  ASSERT_TRUE(m.sensed_grip_share.has_value());
  EXPECT_NEAR(*m.sensed_grip_share, 0.5, 0.01);  // (3 x 0.5 + 1 x 0.5) / (4 x 1), the table's 5 N apart
  EXPECT_NEAR(m.unsensed_held_s, 0.5, 2 * kTickS);
  EXPECT_EQ(m.contact_unit, 0);
  EXPECT_FALSE(Find(EvaluateExpectations(Expectations{}, m, MetricsConfig{}), "grasped_on_sensor").passed);
}

// An object sliding out of the hand leaves the pad on its way: time with no unit loaded during a
// slip event does not count as held off the sensor (the slip and the drop speak for it).
TEST_F(TrackerTest, UnloadedUnitsDuringASlipEventAreNotTimeOffTheSensor) {
  truth_.finger_object_normal_force_n = 2.0;
  truth_.sensed_object_normal_force_n = 2.0;
  Run(0.5, 0.0);
  loads_[0].fn_n = 0.0;
  Run(0.8, 0.01);  // sliding at 10 mm/s with nothing on the units: a slip event
  const Metrics sliding = tracker_.Finish(0.8, 0.1, 0.0);
  EXPECT_EQ(sliding.slip_events, 1);
  EXPECT_NEAR(sliding.unsensed_held_s, 0.0, 2 * kTickS);
  Run(1.2, 0.0);  // then still, and still nothing on the units: off the sensor
  const Metrics still = tracker_.Finish(1.2, 0.1, 0.0);
  EXPECT_NEAR(still.unsensed_held_s, 0.4 - MetricsConfig{}.slip_event_gap_s, 3 * kTickS);
}

}  // namespace
}  // namespace graspbed::testbed
