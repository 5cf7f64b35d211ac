// The shipped disturbance scenarios disturb, and their verdicts tell controllers apart: each raises
// the lightest grip that holds it by at least 1.5x over the same scenario before its disturbance,
// stays holdable within the reference's grip ceiling, and fails both strawmen: a blind light grip
// (constant_grip at 1.3x the undisturbed oracle, a person's margin for the task before the
// disturbance) by slip or drop, and a blind firm grip (constant_grip at the ceiling) by grip
// efficiency wherever the ceiling is above twice the oracle. The scenarios that slip by their nature
// state the same expectations and fail the firm strawman.
#include <gtest/gtest.h>

#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "testbed/oracle.h"
#include "testbed/runner.h"

namespace graspbed::testbed {
namespace {

const std::string kScenarios = std::string(GRASPBED_SOURCE_DIR) + "/scenarios/";

/// The shipped scenarios with a disturbance action (docs/scenarios.md, "Disturbance scenarios").
const std::vector<std::string> kDisturbed = {"added_mass_step", "friction_drop", "pull_ramp",
                                             "shake_transport", "tilt_in_grasp", "pouring_cup"};
/// The shipped scenarios that slip by their nature.
const std::vector<std::string> kSlippery = {"low_friction", "ball_rolls", "narrow_box"};

/// A disturbance must raise the oracle grip at least this much (DESIGN.md, "Verdicts").
constexpr double kMinDisturbanceRatio = 1.5;
/// The blind light grip: this times the undisturbed oracle's setpoint.
constexpr double kLightMargin = 1.3;
/// The reference controller's grip ceiling (grip_slip's max_grip_n) [N]: the firm strawman's grip.
constexpr double kCeilingN = 10.0;
/// The grip efficiency the scenarios allow.
constexpr double kMaxEfficiency = 2.0;

std::set<std::string> Failed(const RunResult& result) {
  std::set<std::string> failed;
  for (const ExpectationOutcome& o : result.outcomes) {
    if (!o.passed) failed.insert(o.name);
  }
  return failed;
}

RunResult RunConstantGrip(const std::string& name, double grip_n) {
  const ScenarioConfig config = LoadScenario(kScenarios + name + ".yaml", {{"controller.name", "constant_grip"},
                                                                          {"controller.params.grip_n", std::to_string(grip_n)}});
  return RunScenario(config);  // the scenarios state max_grip_efficiency: the run finds its oracle
}

void ExpectTheFourExpectations(const ScenarioConfig& config) {
  EXPECT_TRUE(config.expectations.not_dropped.value_or(false));
  EXPECT_TRUE(config.expectations.max_slip_mm.has_value());
  EXPECT_TRUE(config.expectations.slip_detected_within_ms.has_value());
  EXPECT_EQ(config.expectations.max_grip_efficiency.value_or(0.0), kMaxEfficiency);
}

TEST(DisturbanceTest, EachDisturbanceRaisesTheOracleAndFailsTheBlindLightAndFirmGrips) {
  for (const std::string& name : kDisturbed) {
    SCOPED_TRACE(name);
    const ScenarioConfig config = LoadScenario(kScenarios + name + ".yaml");
    ExpectTheFourExpectations(config);
    const OracleReport report = RunOracleReport(config);
    ASSERT_TRUE(report.full.grip.grip_n.has_value()) << report.full.grip.reason;
    ASSERT_TRUE(report.until_disturbance.has_value()) << "no disturbance action";
    ASSERT_TRUE(report.until_disturbance->setpoint_n.has_value()) << report.until_disturbance->grip.reason;
    const double oracle_n = *report.full.grip.grip_n;
    const double ratio = oracle_n / *report.until_disturbance->grip.grip_n;
    const double light_n = kLightMargin * *report.until_disturbance->setpoint_n;
    const RunResult light = RunConstantGrip(name, light_n);
    const RunResult firm = RunConstantGrip(name, kCeilingN);
    std::printf("[ measure ] %-16s oracle %.2f N, undisturbed %.2f N (x%.2f); light grip %.2f N: slip %.2f mm%s; "
                "firm: efficiency %.2f\n",
                name.c_str(), oracle_n, *report.until_disturbance->grip.grip_n, ratio, light_n,
                light.metrics.max_slip_mm, light.metrics.dropped ? ", dropped" : "",
                firm.metrics.grip_efficiency.value_or(-1.0));
    EXPECT_GE(ratio, kMinDisturbanceRatio);
    EXPECT_LE(oracle_n, kCeilingN) << "holdable within the reference's grip ceiling";
    const std::set<std::string> light_failed = Failed(light);
    EXPECT_TRUE(light_failed.count("not_dropped") || light_failed.count("max_slip_mm"))
        << "the blind light grip must lose it by slip or drop";
    if (kCeilingN > kMaxEfficiency * oracle_n) {
      EXPECT_TRUE(Failed(firm).count("max_grip_efficiency")) << "the blind firm grip must fail by efficiency";
    }
  }
}

TEST(DisturbanceTest, TheScenariosThatSlipByNatureStateTheSameAndFailTheBlindFirmGrip) {
  for (const std::string& name : kSlippery) {
    SCOPED_TRACE(name);
    const ScenarioConfig config = LoadScenario(kScenarios + name + ".yaml");
    ExpectTheFourExpectations(config);
    const OracleSearch search = FindOracleGrip(config);
    ASSERT_TRUE(search.grip.grip_n.has_value()) << search.grip.reason;
    EXPECT_LE(*search.grip.grip_n, kCeilingN);
    const RunResult firm = RunConstantGrip(name, kCeilingN);
    std::printf("[ measure ] %-16s oracle %.2f N; firm: efficiency %.2f\n", name.c_str(), *search.grip.grip_n,
                firm.metrics.grip_efficiency.value_or(-1.0));
    if (kCeilingN > kMaxEfficiency * *search.grip.grip_n) {
      EXPECT_TRUE(Failed(firm).count("max_grip_efficiency"));
    }
  }
}

}  // namespace
}  // namespace graspbed::testbed
