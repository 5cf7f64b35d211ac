// The oracle grip (the lightest constant grip that holds a scenario) on the real simulation: where it
// lies against the load and against open loop, that grip efficiency measures what it claims (1 at
// the oracle, 2 at twice it, far more for a squeeze), that it grows with the mass, that it is cached,
// the unholdable case, and `graspbed oracle` through the CLI.
#include "testbed/oracle.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "testbed/runner.h"
#include "tests/support/cli_runner.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::testbed {
namespace {

using graspbed::test_support::CliResult;
using graspbed::test_support::RunCli;
using graspbed::test_support::RunCliUnder;
using graspbed::test_support::TempDir;

const std::string kDefault = std::string(GRASPBED_SOURCE_DIR) + "/scenarios/default.yaml";

/// The bisection stops at 2 % of its bracket: the oracle is that close to the true threshold.
constexpr double kResolution = 0.02;
/// The default box: 100 g at mu 0.8, g = 9.81: its load bound m g / (2 mu) [N].
constexpr double kDefaultLoadBoundN = 0.1 * 9.81 / (2.0 * 0.8);
/// Open loop at effort 0.08 holds the default box (`graspbed run scenarios/default.yaml --set
/// controller.name=open_loop --set controller.params.close_effort=0.08`: held, slip 0.00 mm); the
/// oracle is below it.
constexpr double kOpenLoopHoldingEffort = 0.08;

/// The default scenario with `overrides`, scored against its oracle.
RunResult RunWith(const std::vector<Override>& overrides) {
  const ScenarioConfig config = LoadScenario(kDefault, overrides);
  RunOptions options;
  options.oracle = OracleMode::kAlways;
  return RunScenario(config, options);
}

TEST(OracleTest, TheDefaultBoxsOracleLiesAboveItsLoadBoundAndBelowWhatOpenLoopHeldItWith) {
  const ScenarioConfig config = LoadScenario(kDefault);
  const OracleSearch search = FindOracleGrip(config);
  ASSERT_TRUE(search.grip.grip_n.has_value()) << search.grip.reason;
  std::printf("[ measure ] default: oracle grip %.3f N (setpoint %.3f N) in %zu runs\n", *search.grip.grip_n,
              *search.setpoint_n, search.steps.size());
  EXPECT_GT(*search.grip.grip_n, kDefaultLoadBoundN);
  // The bisection's last held and last failed setpoints bracket it within the resolution.
  double below_n = 0.0;
  for (const OracleStep& step : search.steps) {
    if (!step.held && step.setpoint_n < *search.setpoint_n) below_n = std::max(below_n, step.setpoint_n);
  }
  EXPECT_LE(*search.setpoint_n - below_n, std::max(0.02, kResolution * 2.0 * *search.setpoint_n));
  // Open loop at 0.08 holds the box (no drop, no gross slip) with more grip than the oracle.
  const RunResult open_loop =
      RunWith({{"controller.name", "open_loop"},
                       {"controller.params.close_effort", std::to_string(kOpenLoopHoldingEffort)}});
  ASSERT_FALSE(open_loop.metrics.dropped);
  ASSERT_EQ(open_loop.metrics.gross.events, 0);
  EXPECT_LT(*search.grip.grip_n, open_loop.metrics.mean_held_grip_n);
  EXPECT_LT(*search.grip.grip_n, open_loop.metrics.peak_grip_n);
}

TEST(OracleTest, GripEfficiencyIsNearOneAtTheOracleOnAnotherSensorTwoAtTwiceItAndFourForAFirmSqueeze) {
  const ScenarioConfig config = LoadScenario(kDefault);
  const OracleSearch search = FindOracleGrip(config);
  ASSERT_TRUE(search.setpoint_n.has_value() && search.grip.grip_n.has_value());
  const auto constant = [&](double setpoint_n, const std::string& sensor_profile) {
    return RunWith({{"controller.name", "constant_grip"},
                            {"controller.params.grip_n", std::to_string(setpoint_n)},
                            {"sensor.profile", sensor_profile}});
  };
  // The oracle's own run (its setpoint on the ideal sensor) would score 1 by construction: its grip is
  // that run's mean grip. The same setpoint read through the 16-bit chain's noise and offsets is
  // another run; the grip it holds is the oracle's within the chain's error (a few percent).
  const RunResult at_oracle = constant(*search.setpoint_n, "inamp_16bit");
  ASSERT_TRUE(at_oracle.metrics.grip_efficiency.has_value());
  EXPECT_DOUBLE_EQ(*at_oracle.metrics.grip_efficiency, at_oracle.metrics.mean_held_grip_n / *search.grip.grip_n);
  EXPECT_NEAR(*at_oracle.metrics.grip_efficiency, 1.0, 0.05);
  EXPECT_FALSE(at_oracle.metrics.dropped);
  const RunResult at_twice = constant(2.0 * *search.setpoint_n, "ideal");
  ASSERT_TRUE(at_twice.metrics.grip_efficiency.has_value());
  EXPECT_NEAR(*at_twice.metrics.grip_efficiency, 2.0, 0.1);
  // Open loop at effort 0.5 squeezes about 13 N: the efficiency says how far beyond need that is.
  const RunResult squeeze = RunWith({{"controller.name", "open_loop"}, {"controller.params.close_effort", "0.5"}});
  ASSERT_TRUE(squeeze.metrics.grip_efficiency.has_value());
  std::printf("[ measure ] default: efficiency %.3f at the oracle (16-bit chain), %.2f at twice it, %.2f open loop at 0.5\n",
              *at_oracle.metrics.grip_efficiency, *at_twice.metrics.grip_efficiency,
              *squeeze.metrics.grip_efficiency);
  EXPECT_GE(*squeeze.metrics.grip_efficiency, 4.0);
  EXPECT_GE(*squeeze.metrics.peak_grip_ratio, *squeeze.metrics.grip_efficiency);
}

/// A run that finished with an object grasped and held to its end, as the oracle's rule sees it.
RunResult HeldRun() {
  RunResult result;
  result.completed = true;
  result.metrics.grasped = true;
  result.metrics.mean_held_grip_n = 2.5;
  return result;
}

TEST(OracleTest, TheHoldRuleRefusesAGrossSlipWithoutADropAndEachOtherFailureInItsOrder) {
  EXPECT_TRUE(JudgeOracleStep(2.0, HeldRun()).held);
  EXPECT_EQ(JudgeOracleStep(2.0, HeldRun()).outcome, "held");
  EXPECT_DOUBLE_EQ(JudgeOracleStep(2.0, HeldRun()).mean_grip_n, 2.5);
  // A gross slip of 0.6 mm, the object never dropped: not held.
  RunResult gross = HeldRun();
  SlipEvent slide;
  slide.gross = true;
  slide.distance_m = 0.0006;
  slide.onset_s = 0.9;
  gross.metrics.events.push_back(slide);
  gross.metrics.gross.events = 1;
  gross.metrics.max_slip_mm = 0.6;
  const OracleStep slid = JudgeOracleStep(2.0, gross);
  EXPECT_FALSE(slid.held);
  EXPECT_EQ(slid.outcome, "gross slip of 0.6 mm at 0.9 s");
  // Micro-slips alone (below the gross threshold) are held.
  RunResult micro = HeldRun();
  micro.metrics.micro.events = 3;
  micro.metrics.max_slip_mm = 0.3;
  EXPECT_TRUE(JudgeOracleStep(2.0, micro).held);
  // Each other failure, and the first one wins when several hold.
  RunResult dropped = gross;
  dropped.metrics.dropped = true;
  dropped.metrics.drop_time_s = 1.62;
  EXPECT_EQ(JudgeOracleStep(2.0, dropped).outcome, "dropped at 1.62 s");
  RunResult regrasp = dropped;
  regrasp.metrics.ungrasped_closes = 1;
  EXPECT_EQ(JudgeOracleStep(2.0, regrasp).outcome, "not grasped after 1 close command(s)");
  RunResult never = HeldRun();
  never.metrics.grasped = false;
  EXPECT_EQ(JudgeOracleStep(2.0, never).outcome, "never grasped");
  RunResult fault = dropped;
  fault.metrics.physics_fault = true;
  fault.metrics.physics_fault_cause = "NaN in qacc";
  EXPECT_EQ(JudgeOracleStep(2.0, fault).outcome, "physics fault: NaN in qacc");
  RunResult stopped = HeldRun();
  stopped.completed = false;
  EXPECT_EQ(JudgeOracleStep(2.0, stopped).outcome, "stopped");
  // Held with the mesas carrying less of the finger's squeeze than grasped_on_sensor's floor: no
  // controller of this sensor could feel that grip. Unless the scenario does not check it.
  RunResult beside = stopped;
  beside.metrics.sensed_grip_share = 0.02;
  EXPECT_EQ(JudgeOracleStep(2.0, beside).outcome,
            "held beside the units: they carried 0.02 of the finger's squeeze (floor 0.25)");
  beside.config.expectations.grasped_on_sensor = false;
  EXPECT_EQ(JudgeOracleStep(2.0, beside).outcome, "stopped");
  beside.config.expectations.grasped_on_sensor = true;
  beside.metrics.sensed_grip_share = 0.25;
  EXPECT_EQ(JudgeOracleStep(2.0, beside).outcome, "stopped");
  for (const RunResult* failed : {&gross, &dropped, &regrasp, &never, &fault, &stopped}) {
    EXPECT_FALSE(JudgeOracleStep(2.0, *failed).held);
  }
}

TEST(OracleTest, TheOracleGrowsWithTheMassAndIsCachedPerConfiguration) {
  const ScenarioConfig light = LoadScenario(kDefault);
  const ScenarioConfig heavy = LoadScenario(kDefault, {{"object.mass_kg", "0.3"}});
  const OracleCacheCounters before = OracleCacheCountersNow();
  const OracleSearch light_search = FindOracleGrip(light);
  const OracleSearch heavy_search = FindOracleGrip(heavy);
  ASSERT_TRUE(light_search.grip.grip_n && heavy_search.grip.grip_n);
  EXPECT_GT(*heavy_search.grip.grip_n, 1.5 * *light_search.grip.grip_n);
  EXPECT_NE(light_search.config_hash, heavy_search.config_hash);
  // The same scenario under another controller or sensor is the same oracle: answered from the cache.
  const OracleCacheCounters middle = OracleCacheCountersNow();
  const ScenarioConfig other_controller =
      LoadScenario(kDefault, {{"controller.name", "open_loop"}, {"sensor.profile", "divider_12bit"}});
  const OracleSearch again = FindOracleGrip(other_controller);
  const OracleCacheCounters after = OracleCacheCountersNow();
  EXPECT_EQ(after.searches - middle.searches, 1u);
  EXPECT_EQ(after.cache_hits - middle.cache_hits, 1u);
  EXPECT_EQ(again.config_hash, light_search.config_hash);
  EXPECT_EQ(*again.grip.grip_n, *light_search.grip.grip_n);
  EXPECT_GE(middle.searches - before.searches, 2u);
}

TEST(OracleTest, AnObjectTheStallPinchCannotHoldHasNoOracleAndSaysWhy) {
  // 2 kg at mu 0.2: its weight alone needs 49 N per digit, beyond the 20 N stall pinch.
  const ScenarioConfig config = LoadScenario(kDefault, {{"object.mass_kg", "2.0"}, {"object.friction", "0.2"}});
  const OracleSearch search = FindOracleGrip(config);
  EXPECT_FALSE(search.grip.grip_n.has_value());
  EXPECT_FALSE(search.setpoint_n.has_value());
  EXPECT_NE(search.grip.reason.find("not held at the motor's stall pinch of 20 N"), std::string::npos)
      << search.grip.reason;
  EXPECT_NE(search.grip.reason.find("nor at any grip halved down to 0.1 N"), std::string::npos) << search.grip.reason;
  // Doubled from the first guess to the stall pinch, then halved from it down to the lowest setpoint:
  // 2, 4, 8, 16, 20, then 1, 0.5, 0.25, 0.125 N, none held.
  std::vector<double> setpoints;
  for (const OracleStep& step : search.steps) {
    EXPECT_FALSE(step.held) << step.setpoint_n << " N";
    setpoints.push_back(step.setpoint_n);
  }
  EXPECT_EQ(setpoints, (std::vector<double>{2.0, 4.0, 8.0, 16.0, 20.0, 1.0, 0.5, 0.25, 0.125}));
}

TEST(OracleTest, AnObjectAFirmSqueezePushesOutHasTheLightestGripThatHoldsItAsItsOracle) {
  // The 28 g foam brick (500 N/m, mu 1) under friction 1000 times harder than its contacts, with
  // rolling friction (its physics until 2026-11-28): from 2 N up the pads sink so deep that it slides
  // and is squeezed out; a fraction of a newton holds it. Its weight needs m g / (2 mu) = 0.14 N.
  const ScenarioConfig config = LoadScenario(std::string(GRASPBED_SOURCE_DIR) + "/scenarios/hold_foam_brick.yaml",
                                             {{"physics.impratio", "1000"}, {"object.condim", "6"}});
  const OracleSearch search = FindOracleGrip(config);
  ASSERT_TRUE(search.grip.grip_n.has_value()) << search.grip.reason;
  std::printf("[ measure ] hold_foam_brick: oracle grip %.3f N (setpoint %.3f N) in %zu runs\n", *search.grip.grip_n,
              *search.setpoint_n, search.steps.size());
  const double load_bound_n = 0.028 * 9.81 / 2.0;
  EXPECT_GT(*search.grip.grip_n, load_bound_n);
  EXPECT_LT(*search.grip.grip_n, 1.0);
  bool first_guess_failed = false;
  double failed_below_n = 0.0;
  for (const OracleStep& step : search.steps) {
    if (step.setpoint_n == 2.0) first_guess_failed = !step.held;
    if (!step.held && step.setpoint_n < *search.setpoint_n) failed_below_n = std::max(failed_below_n, step.setpoint_n);
  }
  EXPECT_TRUE(first_guess_failed);
  // Bracketed from below within the resolution, as a search upwards would be.
  EXPECT_GT(failed_below_n, 0.0);
  EXPECT_LE(*search.setpoint_n - failed_below_n, std::max(0.02, kResolution * 2.0 * *search.setpoint_n));
}

TEST(OracleTest, UntilTheFirstDisturbanceCutsTheScriptAndTheDuration) {
  const ScenarioConfig config =
      LoadScenario(std::string(GRASPBED_SOURCE_DIR) + "/scenarios/added_mass_step.yaml");
  const std::optional<ScenarioConfig> until = UntilFirstDisturbance(config);
  ASSERT_TRUE(until.has_value());
  ASSERT_EQ(until->script.size(), 2u);  // close and lift; the add_mass is gone
  EXPECT_EQ(until->script.back().kind, ActionKind::kLift);
  EXPECT_DOUBLE_EQ(until->duration_s, config.script[2].at_s);
  EXPECT_FALSE(UntilFirstDisturbance(LoadScenario(kDefault)).has_value());
  // The oracle's runs: constant_grip on the ideal sensor at the default control rate (nothing of the
  // controller under test), sensor faults left out.
  const ScenarioConfig step =
      OracleStepConfig(LoadScenario(std::string(GRASPBED_SOURCE_DIR) + "/scenarios/sensor_dropout.yaml",
                                    {{"controller.rate_hz", "500"}, {"controller.grip_ceiling_n", "3"}}),
                       1.5);
  EXPECT_EQ(step.controller.name, "constant_grip");
  EXPECT_EQ(step.controller.rate_hz, ControllerOptions{}.rate_hz);
  EXPECT_EQ(step.controller.grip_ceiling_n, 0.0);
  EXPECT_DOUBLE_EQ(step.controller.params.at("grip_n"), 1.5);
  EXPECT_EQ(step.sensor.profile, "ideal");
  for (const Action& action : step.script) EXPECT_FALSE(IsSensorAction(action.kind)) << ActionName(action.kind);
}

TEST(OracleTest, AnInterruptedSearchSaysSoAndIsNotAppliedToTheRun) {
  const ScenarioConfig config = LoadScenario(kDefault, {{"object.mass_kg", "0.11"}});
  std::atomic<bool> stop{true};
  OracleOptions options;
  options.stop = &stop;
  const OracleSearch search = FindOracleGrip(config, options);
  EXPECT_FALSE(search.completed);
  EXPECT_FALSE(search.grip.grip_n.has_value());
  EXPECT_EQ(search.grip.reason, "interrupted");
  // Not cached: asked again without the stop, it searches and finds the grip.
  EXPECT_TRUE(FindOracleGrip(config).grip.grip_n.has_value());
}

TEST(OracleCliTest, PrintsBothOraclesAsJsonWithTheStepsAndRefusesBadInput) {
  const CliResult result =
      RunCli("oracle " + std::string(GRASPBED_SOURCE_DIR) + "/scenarios/added_mass_step.yaml --json");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json json = nlohmann::json::parse(result.out);
  ASSERT_TRUE(json.at("oracle_grip_n").is_number());
  ASSERT_TRUE(json.at("oracle_grip_until_disturbance_n").is_number());
  EXPECT_GE(json.at("oracle_grip_n").get<double>(), 1.5 * json.at("oracle_grip_until_disturbance_n").get<double>());
  EXPECT_EQ(json.at("first_disturbance").at("action"), "add_mass");
  EXPECT_GE(json.at("full").at("steps").size(), 5u);
  EXPECT_EQ(json.at("full").at("steps").back().at("setpoint_n").get<double>() > 0.0, true);
  const CliResult table = RunCli("oracle " + kDefault);
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_NE(table.out.find("oracle grip:"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("no disturbance action"), std::string::npos) << table.out;
  const CliResult bad = RunCli("oracle " + kDefault + " --set object.mass_kg=-1");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("object.mass_kg = -1"), std::string::npos) << bad.err;
}

TEST(OracleCliTest, TheDiskCacheAnswersAnotherProcessAndAnUnreadableEntryIsSearchedAgain) {
  TempDir dir;
  const std::string env = "env GRASPBED_ORACLE_CACHE_DIR=" + dir.Path("cache") + " ";
  const std::string arguments = "oracle " + kDefault + " --set object.mass_kg=0.12 --json";
  const CliResult first = RunCliUnder(env, arguments);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const nlohmann::json searched = nlohmann::json::parse(first.out);
  const std::string entry = dir.Path("cache") + "/" + searched.at("full").at("config_hash").get<std::string>() + ".json";
  ASSERT_TRUE(std::filesystem::exists(entry));
  // Another process reads it back: the same figures and steps. A stored search with a doctored
  // figure proves the answer came from the file, not from a new search.
  nlohmann::json stored = nlohmann::json::parse(graspbed::test_support::ReadText(entry));
  stored["grip_n"] = 0.123;
  std::ofstream(entry) << stored.dump();
  const nlohmann::json cached = nlohmann::json::parse(RunCliUnder(env, arguments).out);
  EXPECT_EQ(cached.at("oracle_grip_n").get<double>(), 0.123);
  EXPECT_EQ(cached.at("full").at("steps"), searched.at("full").at("steps"));
  // A file that does not parse is searched again and rewritten.
  std::ofstream(entry) << "{ not json";
  const nlohmann::json again = nlohmann::json::parse(RunCliUnder(env, arguments).out);
  EXPECT_EQ(again.at("oracle_grip_n"), searched.at("oracle_grip_n"));
  EXPECT_EQ(nlohmann::json::parse(graspbed::test_support::ReadText(entry)).at("grip_n"), searched.at("oracle_grip_n"));
}

TEST(OracleCliTest, TheDiskCacheIsOnByDefaultUnderTheUsersCacheDirectoryAndOffOnRequest) {
  TempDir dir;
  // As a user's shell has it: no GRASPBED_ORACLE_CACHE_DIR (the tests' environment sets it off).
  const std::string user = "env -u GRASPBED_ORACLE_CACHE_DIR XDG_CACHE_HOME=" + dir.Path("xdg") + " ";
  const std::string arguments = "oracle " + kDefault + " --set object.mass_kg=0.125 --json";
  const CliResult first = RunCliUnder(user, arguments);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const std::string hash = nlohmann::json::parse(first.out).at("full").at("config_hash").get<std::string>();
  EXPECT_TRUE(std::filesystem::exists(dir.Path("xdg") + "/graspbed/oracle/" + hash + ".json"));
  // Without XDG_CACHE_HOME: under HOME/.cache.
  const CliResult home = RunCliUnder("env -u GRASPBED_ORACLE_CACHE_DIR -u XDG_CACHE_HOME HOME=" + dir.Path("home") + " ",
                                     arguments);
  ASSERT_EQ(home.exit_code, 0) << home.err;
  EXPECT_TRUE(std::filesystem::exists(dir.Path("home") + "/.cache/graspbed/oracle/" + hash + ".json"));
  // --no-oracle-cache, before or after the command: nothing read (a doctored entry is not used) and
  // nothing written.
  std::ofstream(dir.Path("xdg") + "/graspbed/oracle/" + hash + ".json") << "{ not json";
  for (const std::string& command : {"--no-oracle-cache " + arguments, arguments + " --no-oracle-cache"}) {
    const CliResult off = RunCliUnder("env -u GRASPBED_ORACLE_CACHE_DIR XDG_CACHE_HOME=" + dir.Path("xdg") + " ", command);
    ASSERT_EQ(off.exit_code, 0) << command << ": " << off.err;
    EXPECT_EQ(graspbed::test_support::ReadText(dir.Path("xdg") + "/graspbed/oracle/" + hash + ".json"), "{ not json");
  }
  // The key leaves out the run's name: the same scenario renamed (as a scorecard names each
  // controller's run) is the same search.
  const CliResult renamed = RunCliUnder(user, arguments + " --set name=another");
  ASSERT_EQ(renamed.exit_code, 0) << renamed.err;
  EXPECT_EQ(nlohmann::json::parse(renamed.out).at("full").at("config_hash").get<std::string>(), hash);
}

}  // namespace
}  // namespace graspbed::testbed
