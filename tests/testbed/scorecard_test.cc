// Scorecards: pooling of run metrics into a controller's score, the shipped set's expansion (seeded,
// within its ranges), the set file's error messages, and `graspbed score` on a small set with both
// controllers (table, CSV and JSON columns, the PNG, the reference ahead of open_loop on slip detection).
#include "testbed/scorecard.h"
#include "testbed/oracle.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/yaml_map.h"
#include "tests/support/cli_runner.h"
#include "tests/support/error_of.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::testbed {
namespace {

using graspbed::test_support::CliResult;
using graspbed::test_support::ReadText;
using graspbed::test_support::RunCli;
using graspbed::test_support::TempDir;

constexpr double kTol = 1e-9;
constexpr int kExitOk = 0;
constexpr int kExitBadInput = 2;

const std::string kShippedSet = std::string(GRASPBED_SOURCE_DIR) + "/scenarios/scorecard/set.yaml";
/// The shipped set's runs of its boxes, cylinders and disturbances (the bases of version 3), which
/// come first; the everyday objects' bases follow them.
constexpr int kBoxAndDisturbanceRuns = 41;
const std::string kScenarios = std::string(GRASPBED_SOURCE_DIR) + "/scenarios";

RunResult FinishedRun(int events, int missed, std::vector<double> latencies_ms, int false_flags,
                      double held_s) {
  RunResult result;
  result.completed = true;
  result.passed = missed == 0;
  result.metrics.slip_events = events;
  result.metrics.missed_slip_events = missed;
  for (double latency_ms : latencies_ms) {
    SlipEvent event;
    event.detected = true;
    event.latency_s = latency_ms / 1000.0;
    result.metrics.events.push_back(event);
  }
  for (int i = 0; i < missed; ++i) result.metrics.events.push_back(SlipEvent{});
  result.metrics.false_slip_flags = false_flags;
  result.metrics.held_s = held_s;
  return result;
}

TEST(ScorecardTest, PercentileInterpolatesBetweenOrderStatistics) {
  EXPECT_FALSE(Percentile({}, 50.0).has_value());
  EXPECT_NEAR(*Percentile({3.0}, 95.0), 3.0, kTol);
  EXPECT_NEAR(*Percentile({4.0, 1.0, 3.0, 2.0}, 50.0), 2.5, kTol);
  // numpy.percentile([0, 10, ..., 100], 95) = 95.
  EXPECT_NEAR(*Percentile({0, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100}, 95.0), 95.0, kTol);
}

TEST(ScorecardTest, ScoreRunsPoolsEventsFlagsGripAndEstimationOverRuns) {
  RunResult a = FinishedRun(2, 0, {10.0, 20.0}, 1, 30.0);
  a.metrics.grip_efficiency = 1.5;
  a.metrics.peak_grip_ratio = 2.0;
  a.metrics.gross = {1, 1, 10.0};
  a.metrics.micro = {1, 1, 20.0};
  a.metrics.events = {SlipEvent{.detected = true, .gross = true, .latency_s = 0.010},
                      SlipEvent{.detected = true, .gross = false, .latency_s = 0.020}};
  a.metrics.fn_rmse_n = 0.1;
  a.metrics.estimation_samples = 300;
  RunResult b = FinishedRun(2, 1, {30.0}, 2, 30.0);
  b.metrics.dropped = true;
  b.metrics.missed_unsensed_slip_events = 1;
  b.metrics.missed_thumb_only_slip_events = 1;
  a.metrics.false_slip_flags_by_cue = {{"vibration", 1}};
  b.metrics.false_slip_flags_by_cue = {{"vibration", 1}, {"ratio", 1}};
  b.metrics.grip_efficiency = 3.0;
  b.metrics.peak_grip_ratio = 5.0;
  b.metrics.gross = {2, 1, 30.0};
  b.metrics.events = {SlipEvent{.detected = true, .gross = true, .latency_s = 0.030},
                      SlipEvent{.detected = false, .gross = true}};
  b.metrics.fn_rmse_n = 0.2;
  b.metrics.estimation_samples = 100;
  RunResult c = FinishedRun(0, 0, {}, 0, 60.0);
  c.metrics.crushed = true;
  const ControllerScore score = ScoreRuns("x", {&a, &b, &c}, 1);
  EXPECT_EQ(score.runs, 3);
  EXPECT_EQ(score.errors, 1);
  EXPECT_EQ(score.passed, 2);
  EXPECT_EQ(score.slip_events, 4);
  EXPECT_EQ(score.slip_detected, 3);
  EXPECT_EQ(score.missed_unsensed, 1);
  EXPECT_EQ(score.missed_thumb_only, 1);
  const std::map<std::string, int> by_cue = {{"vibration", 2}, {"ratio", 1}};
  EXPECT_EQ(score.false_flags_by_cue, by_cue);
  EXPECT_NEAR(*score.detected_pct, 75.0, kTol);
  EXPECT_NEAR(*score.latency_p50_ms, 20.0, kTol);
  EXPECT_NEAR(*score.latency_p95_ms, 29.0, kTol);
  // 3 false flags over 2 minutes held in all.
  EXPECT_NEAR(score.held_min, 2.0, kTol);
  EXPECT_NEAR(*score.false_per_min, 1.5, kTol);
  EXPECT_EQ(score.drops, 1);
  EXPECT_EQ(score.crushes, 1);
  EXPECT_NEAR(*score.grip_efficiency_median, 2.25, kTol);
  EXPECT_NEAR(*score.grip_efficiency_p95, 1.5 + 0.95 * 1.5, kTol);
  EXPECT_NEAR(*score.peak_grip_ratio_median, 3.5, kTol);
  EXPECT_EQ(score.gross_slip_events, 3);
  EXPECT_EQ(score.gross_slip_detected, 2);
  EXPECT_NEAR(*score.gross_detected_pct, 200.0 / 3.0, kTol);
  EXPECT_NEAR(*score.gross_latency_p50_ms, 20.0, kTol);  // the gross events' 10 and 30 ms
  EXPECT_EQ(score.micro_slip_events, 1);
  EXPECT_EQ(score.micro_slip_detected, 1);
  // RMS weighted by samples: sqrt((0.01 * 300 + 0.04 * 100) / 400).
  EXPECT_NEAR(*score.fn_rmse_n, std::sqrt(7.0 / 400.0), kTol);
}

TEST(ScorecardTest, ScoreOfNoRunHasNoRatesRatherThanZeros) {
  const ControllerScore score = ScoreRuns("x", {}, 0);
  EXPECT_EQ(score.runs, 0);
  EXPECT_FALSE(score.detected_pct.has_value());
  EXPECT_FALSE(score.latency_p95_ms.has_value());
  EXPECT_FALSE(score.false_per_min.has_value());
  EXPECT_FALSE(score.grip_efficiency_median.has_value());
  EXPECT_FALSE(score.gross_detected_pct.has_value());
  EXPECT_FALSE(score.fn_rmse_n.has_value());
  EXPECT_FALSE(score.false_per_lift.has_value());
  // A run that never held its object is no lift: still no rate.
  const RunResult never_held = FinishedRun(0, 0, {}, 0, 0.0);
  const ControllerScore unheld = ScoreRuns("x", {&never_held}, 0);
  EXPECT_EQ(unheld.lifts, 0);
  EXPECT_FALSE(unheld.false_per_lift.has_value());
}

// Three runs: held 30 s with 2 false flags, held 60 s with 3, never held (dropped at the close).
// By hand: 2 lifts (the runs that held), 5 false flags, 1.5 min held: 2.5 per lift, 3.33 per minute.
Scorecard PerLiftScorecard() {
  RunResult short_hold = FinishedRun(0, 0, {}, 2, 30.0);
  RunResult long_hold = FinishedRun(0, 0, {}, 3, 60.0);
  RunResult never_held = FinishedRun(0, 0, {}, 0, 0.0);
  never_held.metrics.dropped = true;
  Scorecard scorecard;
  scorecard.set_name = "lifts";
  scorecard.set_version = 1;
  scorecard.runs_per_controller = 3;
  scorecard.completed = true;
  scorecard.rows = {{"grip_slip", "short.v0", {}, "", short_hold},
                    {"grip_slip", "long.v0", {}, "", long_hold},
                    {"grip_slip", "dropped.v0", {}, "", never_held}};
  scorecard.scores = {ScoreRuns("grip_slip", {&short_hold, &long_hold, &never_held}, 0)};
  return scorecard;
}

TEST(ScorecardTest, FalseFlagsPerLiftCountOneLiftPerRunThatHeldItsObject) {
  constexpr int kLifts = 2;
  constexpr double kFalsePerLift = 5.0 / 2.0;
  constexpr double kFalsePerMin = 5.0 / 1.5;
  const Scorecard scorecard = PerLiftScorecard();
  const ControllerScore& score = scorecard.scores.front();
  EXPECT_EQ(score.runs, 3);
  EXPECT_EQ(score.lifts, kLifts);
  ASSERT_TRUE(score.false_per_lift.has_value());
  EXPECT_NEAR(*score.false_per_lift, kFalsePerLift, kTol);
  EXPECT_NEAR(*score.false_per_min, kFalsePerMin, kTol);

  // The table: per lift beside per minute, with its flags over its lifts.
  const std::string table = ScorecardTable(scorecard);
  EXPECT_NE(table.find("false flags / min held    3.33 (5)"), std::string::npos) << table;
  EXPECT_NE(table.find("false flags / lift        2.50 (5/2)"), std::string::npos) << table;
  // CSV and JSON: the column once, with the same value; the lifts beside it.
  const std::string csv = ScorecardCsv(scorecard);
  std::vector<std::string> header;
  std::vector<std::string> values;
  std::istringstream lines(csv);
  std::string line;
  for (std::vector<std::string>* cells : {&header, &values}) {
    ASSERT_TRUE(std::getline(lines, line)) << csv;
    std::istringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells->push_back(cell);
  }
  ASSERT_EQ(std::count(header.begin(), header.end(), "false_flags_per_lift"), 1) << csv;
  const size_t column = std::find(header.begin(), header.end(), "false_flags_per_lift") - header.begin();
  ASSERT_LT(column, values.size()) << csv;
  EXPECT_NEAR(std::stod(values[column]), kFalsePerLift, kTol) << csv;
  const nlohmann::json json = ScorecardJson(scorecard);
  const nlohmann::json& controller = json.at("controllers").at(0);
  EXPECT_NEAR(controller.at("false_flags_per_lift").get<double>(), kFalsePerLift, kTol);
  EXPECT_EQ(controller.at("lifts").get<int>(), kLifts);
  // Per sensor (all three runs on the default sensor): the same figure, in JSON and in the table.
  ASSERT_EQ(controller.at("by_sensor").size(), 1u) << controller.at("by_sensor").dump();
  const nlohmann::json& sensor = controller.at("by_sensor").begin().value();
  EXPECT_NEAR(sensor.at("false_flags_per_lift").get<double>(), kFalsePerLift, kTol);
  const std::string by_sensor = ScorecardBySensorTable(scorecard);
  EXPECT_NE(by_sensor.find("false flags/lift"), std::string::npos) << by_sensor;
  EXPECT_NE(by_sensor.find("2.50 (2 lifts)"), std::string::npos) << by_sensor;
  // The plot: a panel of its own, a bar of that height.
  const plot::Figure figure = ScorecardFigure(scorecard);
  const auto panel = std::find_if(figure.panels.begin(), figure.panels.end(), [](const plot::Chart& chart) {
    return chart.title == "false flags per lift";
  });
  ASSERT_NE(panel, figure.panels.end());
  ASSERT_EQ(panel->bars.size(), 1u);
  ASSERT_TRUE(panel->bars[0].value.has_value());
  EXPECT_NEAR(*panel->bars[0].value, kFalsePerLift, kTol);
}

ExpectationOutcome Outcome(const std::string& name, bool passed, const std::string& value_text,
                           const std::string& limit, const std::string& note = "") {
  ExpectationOutcome outcome;
  outcome.name = name;
  outcome.passed = passed;
  outcome.value_text = value_text;
  outcome.limit = limit;
  outcome.note = note;
  return outcome;
}

TEST(ScorecardTest, FailedRunsNameTheirFirstFailedExpectationAndNoPassingRun) {
  RunResult passed = FinishedRun(0, 0, {}, 0, 30.0);
  passed.outcomes = {Outcome("not_dropped", true, "held", "true"),
                     Outcome("max_slip_mm", true, "0.1 mm", "<= 2 mm")};
  // Fails two expectations: only the first it recorded is named, with its value and limit.
  RunResult slipped = FinishedRun(0, 0, {}, 0, 30.0);
  slipped.passed = false;
  slipped.outcomes = {Outcome("not_dropped", true, "held", "true"),
                      Outcome("max_slip_mm", false, "3.2 mm", "<= 2 mm"),
                      Outcome("max_grip_n", false, "12.5 N", "<= 10 N")};
  RunResult crushed = FinishedRun(0, 0, {}, 0, 30.0);
  crushed.passed = false;
  crushed.outcomes = {Outcome("not_crushed", false, "crushed (9.1 N)", "true", "limit 8 N")};
  Scorecard scorecard;
  scorecard.rows = {{"grip_slip", "passing.v0", {}, "", passed},
                    {"grip_slip", "slipping.v1", {}, "", slipped},
                    {"open_loop", "passing.v0", {}, "", passed},
                    {"open_loop", "crushing.v0", {}, "", crushed},
                    {"open_loop", "broken.v2", {}, "scenario broken.yaml: no such file", {}},
                    {"open_loop", "late.v3", {}, "interrupted", {}}};
  const std::string listing = ScorecardFailedRuns(scorecard);
  EXPECT_EQ(listing,
            "  failed runs (run@controller: first failed expectation: got, limit):\n"
            "    slipping.v1@grip_slip: max_slip_mm: got 3.2 mm, limit <= 2 mm\n"
            "    crushing.v0@open_loop: not_crushed: got crushed (9.1 N), limit true (limit 8 N)\n"
            "    broken.v2@open_loop: error: scenario broken.yaml: no such file\n"
            "  not finished (interrupted): 1 run\n");
  EXPECT_EQ(listing.find("passing"), std::string::npos) << listing;
  EXPECT_EQ(listing.find("max_grip_n"), std::string::npos) << listing;

  // Every run passed: said so, nothing listed.
  scorecard.rows = {{"grip_slip", "passing.v0", {}, "", passed}};
  EXPECT_EQ(ScorecardFailedRuns(scorecard), "  failed runs: none\n");
}

TEST(ScorecardTest, ShippedSetExpandsReproduciblyWithinItsRanges) {
  const ScorecardSet set = LoadScorecardSet(kShippedSet);
  EXPECT_FALSE(set.name.empty());
  EXPECT_GE(set.version, 1);
  const std::vector<ScorecardRun> runs = ExpandScorecardSet(set);
  // The boxes, cylinders and disturbances first (the ctest below scores them), then the everyday
  // objects' tasks (19 runs), then the default lift of each of the 13 library objects by name (26):
  // 86 runs per controller.
  ASSERT_EQ(runs.size(), 86u);
  EXPECT_EQ(runs[kBoxAndDisturbanceRuns - 1].name, "wrap_cylinder.v3");
  // Both grasps are scored (the wrap base is in the set), and each everyday task of the objects'
  // shipped scenarios.
  for (const char* base : {"wrap_cylinder.v0", "lift_can.v0", "lift_mug.v0", "pick_marker.v0", "pick_card.v0",
                           "carry_egg.v0", "lift_plastic_cup.v0", "hold_foam_brick.v0", "pour_bottle.v0"}) {
    EXPECT_TRUE(std::any_of(runs.begin(), runs.end(), [&](const ScorecardRun& run) { return run.name == base; }))
        << base;
  }
  // Each library object by name in the default lift, v0 with that one override and nothing else.
  for (const char* object : {"can", "bottle", "bottle_half", "mug", "marker", "card", "banana", "tennis_ball",
                             "apple", "egg", "plastic_cup", "foam_brick", "wine_glass"}) {
    const std::string name = std::string("default_") + object + ".v0";
    const auto run = std::find_if(runs.begin(), runs.end(), [&](const ScorecardRun& r) { return r.name == name; });
    ASSERT_NE(run, runs.end()) << name;
    EXPECT_EQ(run->scenario_path, kScenarios + "/default.yaml");
    ASSERT_EQ(run->overrides.size(), 1u) << name;
    EXPECT_EQ(run->overrides[0].key, "object");
    EXPECT_EQ(LoadScenario(run->scenario_path, run->overrides).scene.object.name, object);
  }
  const std::vector<ScorecardRun> again = ExpandScorecardSet(LoadScorecardSet(kShippedSet));
  ASSERT_EQ(again.size(), runs.size());
  std::set<std::string> names;
  for (size_t i = 0; i < runs.size(); ++i) {
    EXPECT_TRUE(names.insert(runs[i].name).second) << runs[i].name;
    ASSERT_EQ(runs[i].overrides.size(), again[i].overrides.size());
    for (size_t k = 0; k < runs[i].overrides.size(); ++k) {
      EXPECT_EQ(runs[i].overrides[k].key, again[i].overrides[k].key);
      EXPECT_EQ(runs[i].overrides[k].value, again[i].overrides[k].value);
    }
    if (runs[i].name.ends_with(".v0") && !runs[i].name.starts_with("default_")) {
      EXPECT_TRUE(runs[i].overrides.empty()) << runs[i].name;
    }
    // The last value of a key is the one that applies; the mass and friction ranges hold.
    double mass = -1.0, friction = -1.0;
    for (const Override& each : runs[i].overrides) {
      if (each.key == "object.mass_kg") mass = std::stod(each.value);
      if (each.key == "object.friction") friction = std::stod(each.value);
    }
    // The objects' bases draw their masses round the object's own (a 3 g cup, a 490 g bottle).
    const bool object_base = static_cast<int>(i) >= kBoxAndDisturbanceRuns;
    if (!runs[i].name.ends_with(".v0")) {
      EXPECT_GE(mass, object_base ? 0.002 : 0.05) << runs[i].name;
      EXPECT_LE(mass, object_base ? 0.5 : 0.4) << runs[i].name;
      EXPECT_GE(friction, 0.3) << runs[i].name;
      EXPECT_LE(friction, 1.0) << runs[i].name;
    }
    // Every run loads: the overrides name keys the scenario schema accepts.
    EXPECT_NO_THROW(LoadScenario(runs[i].scenario_path, runs[i].overrides)) << runs[i].name;
  }
}

TEST(ScorecardTest, SetFileErrorsNameTheFileLineAndKey) {
  TempDir dir;
  const std::string no_version = dir.Write("a.yaml", "name: s\nbases:\n  - {scenario: x.yaml}\n");
  EXPECT_NE(graspbed::test_support::ErrorOf<common::ConfigError>([&] {
              LoadScorecardSet(no_version);
            }).find("version"),
            std::string::npos);
  const std::string missing =
      dir.Write("b.yaml", "name: s\nversion: 1\nbases:\n  - {scenario: nowhere.yaml}\n");
  const std::string message =
      graspbed::test_support::ErrorOf<common::ConfigError>([&] { LoadScorecardSet(missing); });
  EXPECT_NE(message.find("b.yaml:4: bases[0].scenario = nowhere.yaml: no such file"), std::string::npos)
      << message;
  const std::string bad_range = dir.Write(
      "c.yaml", "name: s\nversion: 1\nbases:\n  - scenario: " + kScenarios +
                    "/default.yaml\n    vary:\n      - {key: object.mass_kg, min: 0.4, max: 0.1}\n");
  const std::string range_message =
      graspbed::test_support::ErrorOf<common::ConfigError>([&] { LoadScorecardSet(bad_range); });
  EXPECT_NE(range_message.find("bases[0].vary[0].max = 0.1: must be >= min"), std::string::npos)
      << range_message;
  // One scenario twice needs a name per base, or the runs' names (and their output folders) collide.
  const std::string base = "  - scenario: " + kScenarios + "/default.yaml\n";
  const std::string twice = dir.Write("d.yaml", "name: s\nversion: 1\nbases:\n" + base + base);
  const std::string twice_message =
      graspbed::test_support::ErrorOf<common::ConfigError>([&] { LoadScorecardSet(twice); });
  EXPECT_NE(twice_message.find("d.yaml:5: bases[1].name = default: another base has this name"), std::string::npos)
      << twice_message;
  const std::string bad_set = dir.Write("e.yaml", "name: s\nversion: 1\nbases:\n" + base + "    set: [1, 2]\n");
  const std::string set_message =
      graspbed::test_support::ErrorOf<common::ConfigError>([&] { LoadScorecardSet(bad_set); });
  EXPECT_NE(set_message.find("e.yaml:5: bases[0].set = [1, 2]: expected a map"), std::string::npos) << set_message;
}

TEST(ScorecardTest, EachRunsOracleIsSearchedOnceWhateverTheNumberOfControllers) {
  SetOracleDiskCacheOff();  // searched here, not read from another process's cache
  TempDir dir;
  // Masses no other test uses, so this process has not searched them yet.
  const std::string path = dir.Write(
      "s.yaml", "name: s\nversion: 1\nseed: 5\nbases:\n  - scenario: " + kScenarios +
                    "/default.yaml\n    set: {object.mass_kg: 0.1234, duration_s: 1.6}\n    variations: 1\n"
                    "    vary:\n      - {key: object.mass_kg, min: 0.131, max: 0.139}\n");
  ScorecardOptions options;
  options.controllers = {"grip_slip", "open_loop", "constant_grip"};
  options.jobs = 2;
  const OracleCacheCounters before = OracleCacheCountersNow();
  const Scorecard scorecard = RunScorecard(LoadScorecardSet(path), options);
  const OracleCacheCounters after = OracleCacheCountersNow();
  ASSERT_TRUE(scorecard.completed);
  ASSERT_EQ(scorecard.rows.size(), 6u);
  // Six runs asked, two searches ran (one per run of the set), four were answered by them.
  EXPECT_EQ(after.searches - before.searches, 6u);
  EXPECT_EQ((after.searches - after.cache_hits) - (before.searches - before.cache_hits), 2u);
  for (const ScorecardRow& row : scorecard.rows) {
    ASSERT_TRUE(row.result.metrics.oracle.has_value()) << row.run;
    EXPECT_EQ(row.result.metrics.oracle->grip_n, scorecard.rows[row.run == "default.v0" ? 0 : 1].result.metrics.oracle->grip_n)
        << row.run << "@" << row.controller;
  }
}

TEST(ScorecardTest, ABaseNamedAndSetRunsItsOverridesBeforeEachVariations) {
  TempDir dir;
  const std::string path = dir.Write(
      "s.yaml", "name: s\nversion: 1\nseed: 4\nbases:\n  - scenario: " + kScenarios +
                    "/default.yaml\n    name: lift_egg\n    set: {object: {name: egg}, seed: 7}\n    variations: 1\n"
                    "    vary:\n      - {key: object.mass_kg, min: 0.05, max: 0.06}\n");
  const std::vector<ScorecardRun> runs = ExpandScorecardSet(LoadScorecardSet(path));
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].name, "lift_egg.v0");
  EXPECT_EQ(runs[1].name, "lift_egg.v1");
  ASSERT_EQ(runs[0].overrides.size(), 2u);
  EXPECT_EQ(runs[0].overrides[0].key, "object");
  EXPECT_EQ(runs[0].overrides[0].value, "{name: egg}");
  EXPECT_EQ(runs[0].overrides[1].key, "seed");
  // The variation keeps the base's overrides first, so its drawn mass and seed win.
  const ScenarioConfig varied = LoadScenario(runs[1].scenario_path, runs[1].overrides);
  EXPECT_EQ(varied.scene.object.name, "egg");
  EXPECT_GE(varied.scene.object.mass_kg, 0.05);
  EXPECT_LE(varied.scene.object.mass_kg, 0.06);
  EXPECT_NE(varied.seed, 7u);
  EXPECT_EQ(LoadScenario(runs[0].scenario_path, runs[0].overrides).seed, 7u);
}

// A small set through the real CLI: two bases (a pull ramp and an added mass step), one seeded
// variation of each that slips under a 10 N grip (friction 0.28-0.31 against the 4 N pull; 0.85-0.95 kg
// added) on another sensor than the bases' (so the per-sensor figures have two groups), both
// controllers.
TEST(ScorecardCliTest, ScoresBothControllersSideBySideAndTheReferenceDetectsMoreSlip) {
  TempDir dir;
  dir.Write("set/set.yaml",
            "name: small\nversion: 1\nseed: 3\nbases:\n"
            "  - {scenario: " +
                kScenarios +
                "/pull_ramp.yaml, variations: 1,\n"
                "     vary: [{key: object.friction, min: 0.28, max: 0.31},\n"
                "            {choose: [{sensor.profile: ideal}, {sensor.profile: divider_12bit}]}]}\n"
                "  - {scenario: " +
                kScenarios +
                "/added_mass_step.yaml, variations: 1,\n"
                "     vary: [{key: \"script[2].mass_kg\", min: 0.85, max: 0.95},\n"
                "            {choose: [{sensor.profile: ideal}, {sensor.profile: divider_12bit}]}]}\n");
  const std::string out = dir.Path("out");
  const CliResult result = RunCli("score --set-dir " + dir.Path("set") + " -j 2 --out " + out);
  ASSERT_EQ(result.exit_code, kExitOk) << result.out << result.err;
  EXPECT_NE(result.out.find("scorecard small v1"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("4 runs per controller"), std::string::npos) << result.out;
  // One table, one column per controller.
  std::istringstream lines(result.out);
  std::string line;
  bool header = false;
  while (std::getline(lines, line)) {
    if (line.find("grip_slip") != std::string::npos && line.find("open_loop") != std::string::npos)
      header = true;
  }
  EXPECT_TRUE(header) << result.out;
  // Per base scenario: each base's two runs (v0 and one variation) under each controller.
  const std::string by_scenario = result.out.substr(result.out.find("by scenario"));
  for (const char* line :
       {"pull_ramp              grip_slip        2", "pull_ramp              open_loop        2",
        "added_mass_step        grip_slip        2"}) {
    EXPECT_NE(by_scenario.find(line), std::string::npos) << line << "\n" << result.out;
  }
  for (const char* label :
       {"gross slips flagged", "gross latency p50", "gross latency p95", "micro-slips flagged",
        "all slip events flagged", "false flags / min held", "false flags / lift", "drops", "crushes",
        "grip efficiency median", "grip efficiency p95", "peak grip / oracle median", "Fn estimation RMSE",
        "passed"}) {
    EXPECT_NE(result.out.find(label), std::string::npos) << label;
  }

  EXPECT_EQ(ReadText(out + "/scorecard.png").substr(1, 3), "PNG");
  const std::string csv = ReadText(out + "/scorecard.csv");
  const std::string csv_header = csv.substr(0, csv.find('\n'));
  for (const char* column :
       {"controller", "slip_detected_pct", "latency_p50_ms", "latency_p95_ms", "false_flags_per_min",
        "false_flags_per_lift", "lifts", "drops", "crushes", "grip_efficiency_median", "grip_efficiency_p95",
        "peak_grip_ratio_median", "gross_slip_events", "gross_slip_detected", "gross_slip_detected_pct",
        "gross_latency_p50_ms", "gross_latency_p95_ms", "micro_slip_events", "micro_slip_detected",
        "fn_rmse_n", "passed", "runs"}) {
    EXPECT_NE(csv_header.find(column), std::string::npos) << column;
  }
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3) << csv;

  const nlohmann::json json = nlohmann::json::parse(ReadText(out + "/scorecard.json"));
  EXPECT_EQ(json.at("set").at("name"), "small");
  EXPECT_EQ(json.at("set").at("version"), 1);
  ASSERT_EQ(json.at("controllers").size(), 2u);
  const nlohmann::json& reference = json.at("controllers")[0];
  const nlohmann::json& baseline = json.at("controllers")[1];
  EXPECT_EQ(reference.at("controller"), "grip_slip");
  EXPECT_EQ(baseline.at("controller"), "open_loop");
  EXPECT_EQ(json.at("runs").size(), 8u);
  // The outcome: both controllers met slip events, and the reference flagged more of them than the
  // baseline (which has no slip detection at all), half of them within 50 ms. (Its p95 here is the
  // slow onset of a pull ramped over 1.2 s: 131 ms; the shipped set's figures are in
  // docs/controller.md.)
  ASSERT_GT(reference.at("slip_events").get<int>(), 0);
  ASSERT_GT(baseline.at("slip_events").get<int>(), 0);
  ASSERT_FALSE(reference.at("slip_detected_pct").is_null());
  EXPECT_GT(reference.at("slip_detected_pct").get<double>(), baseline.at("slip_detected_pct").get<double>());
  EXPECT_GE(reference.at("slip_detected_pct").get<double>(), 75.0);
  ASSERT_FALSE(reference.at("latency_p50_ms").is_null());
  EXPECT_LE(reference.at("latency_p50_ms").get<double>(), 50.0);
  // Which runs the reference holds, each: the seeded runs' outcomes move only with the code. It holds
  // both bases (oracles 4.7 and 4.6 N) and the pull variation (9.6 N); it drops the added-mass
  // variation, 0.85-0.95 kg landing on a 100 g box whose oracle is 9.2 N, which a grip kept light
  // does not catch (docs/controller.md).
  int grip_slip_runs = 0;
  for (const nlohmann::json& run : json.at("runs")) {
    if (run.at("controller") != "grip_slip") continue;
    ++grip_slip_runs;
    const nlohmann::json& metrics = run.at("summary").at("metrics");
    std::printf("[ measure ] %s: oracle %s N, %s\n", run.at("run").get<std::string>().c_str(),
                metrics.at("oracle_grip_n").dump().c_str(), metrics.at("dropped").get<bool>() ? "dropped" : "held");
    EXPECT_EQ(metrics.at("dropped").get<bool>(), run.at("run") == "added_mass_step.v1") << run.at("run");
  }
  EXPECT_EQ(grip_slip_runs, 4);
  // Under the table, each run that failed with the first expectation its summary records as failed,
  // and no run that passed.
  const size_t failed_at = result.out.find("  failed runs");
  ASSERT_NE(failed_at, std::string::npos) << result.out;
  const std::string failed = result.out.substr(failed_at, result.out.find("by sensor") - failed_at);
  int failures = 0;
  for (const nlohmann::json& run : json.at("runs")) {
    const std::string name = run.at("run").get<std::string>() + "@" + run.at("controller").get<std::string>();
    const nlohmann::json& summary = run.at("summary");
    if (summary.at("passed").get<bool>()) {
      EXPECT_EQ(failed.find("    " + name + ":"), std::string::npos) << name << " passed\n" << failed;
      continue;
    }
    ++failures;
    for (const nlohmann::json& outcome : summary.at("expectations")) {
      if (outcome.at("passed").get<bool>()) continue;
      const std::string line = "    " + name + ": " + outcome.at("name").get<std::string>() + ": got " +
                               outcome.at("value_text").get<std::string>() + ", limit " +
                               outcome.at("limit").get<std::string>();
      EXPECT_NE(failed.find(line), std::string::npos) << line << "\n" << failed;
      break;
    }
  }
  EXPECT_GE(failures, 1) << "the premise: the reference drops added_mass_step.v1";
  // The false flags by cue add up to the false flags, and the table names them when there are any;
  // the misses with no unit loaded, and those where only the thumb slid, are some of the misses.
  int by_cue = 0;
  for (const auto& [cues, count] : reference.at("false_flags_by_cue").items()) by_cue += count.get<int>();
  EXPECT_EQ(by_cue, reference.at("false_flags").get<int>());
  EXPECT_EQ(result.out.find("false flags by cue, grip_slip:") != std::string::npos, by_cue > 0) << result.out;
  const int missed = reference.at("slip_events").get<int>() - reference.at("slip_detected").get<int>();
  EXPECT_LE(reference.at("missed_unsensed").get<int>(), missed);
  EXPECT_LE(reference.at("missed_thumb_only").get<int>(), missed);
  // Per sensor (profile/sensitivities of each run): one group per sensor the runs used (the bases'
  // inamp_16bit, their variations' draw), each counting exactly the runs on that sensor, so the
  // groups partition the runs and their counts add up to the controller's.
  std::map<std::string, int> runs_by_sensor;
  for (const nlohmann::json& run : json.at("runs")) {
    if (run.at("controller") != "grip_slip") continue;
    const nlohmann::json& overrides = run.at("overrides");
    const std::string profile =
        overrides.contains("sensor.profile") ? overrides.at("sensor.profile").get<std::string>() : "inamp_16bit";
    ++runs_by_sensor[profile + "/paper"];
  }
  ASSERT_GE(runs_by_sensor.size(), 2u) << "the premise: the variations use another sensor than the bases";
  std::map<std::string, int> grouped;
  for (const auto& [sensor, figures] : reference.at("by_sensor").items()) grouped[sensor] = figures.at("runs");
  EXPECT_EQ(grouped, runs_by_sensor);
  for (const nlohmann::json* controller : {&reference, &baseline}) {
    const nlohmann::json& by_sensor = controller->at("by_sensor");
    ASSERT_FALSE(by_sensor.empty());
    for (const char* count :
         {"runs", "slip_events", "slip_detected", "missed_thumb_only", "false_flags", "drops", "passed"}) {
      int sum = 0;
      for (const auto& [sensor, figures] : by_sensor.items()) sum += figures.at(count).get<int>();
      EXPECT_EQ(sum, controller->at(count).get<int>()) << controller->at("controller") << " " << count;
    }
  }
  for (const auto& [sensor, figures] : reference.at("by_sensor").items()) {
    EXPECT_NE(sensor.find('/'), std::string::npos) << sensor << ": profile/sensitivities";
    EXPECT_LE(figures.at("slip_detected").get<int>(), figures.at("slip_events").get<int>()) << sensor;
  }
}

// The reference controller over the shipped set's boxes, cylinders and disturbances, against what it
// meets today: nothing dropped or crushed, every run finished without a physics fault, every run
// scored against an oracle grip. Its grip efficiency and gross-slip figures are printed; their
// targets are the reference controller's issue (docs/controller.md, "Scorecard"). The everyday
// objects' bases are left to `graspbed score` (8.6 min with their oracle searches on 2 cores): the
// reference drops the foam brick and crushes the plastic cup and one egg variation there, each a
// failure tests/controller/reference_suite_test.cc lists for the object's shipped scenario.
TEST(ScorecardTest, ReferenceOnTheBoxesAndDisturbancesDropsAndCrushesNothingAndHoldsNearTheOracleGrip) {
  ScorecardOptions options;
  options.controllers = {"grip_slip"};
  options.jobs = 2;
  options.limit = kBoxAndDisturbanceRuns;
  const Scorecard scorecard = RunScorecard(LoadScorecardSet(kShippedSet), options);
  ASSERT_TRUE(scorecard.completed);
  ASSERT_EQ(scorecard.rows.size(), static_cast<size_t>(kBoxAndDisturbanceRuns));
  EXPECT_EQ(scorecard.rows.back().run, "wrap_cylinder.v3") << "the limit ends with the last box base";
  ASSERT_EQ(scorecard.scores.size(), 1u);
  const ControllerScore& score = scorecard.scores[0];
  std::printf(
      "[ measure ] shipped set, boxes and disturbances, grip_slip: %d runs, %d passed, %d/%d slip events flagged, p95 %.1f ms, "
      "%.2f false flags/min held, gross %d/%d flagged, grip efficiency median %.2f p95 %.2f\n",
      score.runs, score.passed, score.slip_detected, score.slip_events, score.latency_p95_ms.value_or(-1.0),
      score.false_per_min.value_or(-1.0), score.gross_slip_detected, score.gross_slip_events,
      score.grip_efficiency_median.value_or(-1.0), score.grip_efficiency_p95.value_or(-1.0));
  EXPECT_EQ(score.errors, 0);
  EXPECT_EQ(score.runs, scorecard.runs_per_controller);
  EXPECT_EQ(score.physics_faults, 0);
  EXPECT_EQ(score.drops, 0);
  EXPECT_EQ(score.crushes, 0);
  // Every run was scored against an oracle grip, or says why it has none (a variation no constant
  // grip holds within the stall pinch: the narrow box of default.v2 slides 0.55 mm at the lift
  // whatever the grip, its finger pressed on the table).
  for (const ScorecardRow& row : scorecard.rows) {
    ASSERT_TRUE(row.result.metrics.oracle.has_value()) << row.run;
    if (!row.result.metrics.oracle->grip_n) {
      std::printf("[ measure ] %s: no oracle grip: %s\n", row.run.c_str(), row.result.metrics.oracle->reason.c_str());
      EXPECT_FALSE(row.result.metrics.oracle->reason.empty()) << row.run;
    }
  }
  // The grip it holds against each run's oracle. Printed 2026-11-28 (the line above): 34 passed,
  // efficiency median 1.51, p95 3.22; the runs are seeded, so these move only when the code does.
  // With the grip target tripled (grip_slip_controller.cc, target_n_) the reference still drops and
  // crushes nothing but passes 30, median 1.77, p95 6.46: the bounds sit between the two, so a
  // reference that squeezes more than it needs fails here.
  ASSERT_TRUE(score.grip_efficiency_median.has_value());
  ASSERT_TRUE(score.grip_efficiency_p95.has_value());
  EXPECT_LE(*score.grip_efficiency_median, 1.65);
  EXPECT_LE(*score.grip_efficiency_p95, 4.5);
  EXPECT_GE(score.passed, 32);
  // The set does exercise slip: the figures above are over real events.
  EXPECT_GT(score.slip_events, 10);
}

TEST(ScorecardCliTest, LimitTakesTheFirstRunsOfTheShippedSetForOneController) {
  TempDir dir;
  const CliResult result = RunCli("score --set-dir " + std::string(GRASPBED_SOURCE_DIR) +
                                  "/scenarios/scorecard --limit 2 "
                                  "--controller open_loop --out " +
                                  dir.Path("out") + " --runs-out " + dir.Path("runs"));
  ASSERT_EQ(result.exit_code, kExitOk) << result.out << result.err;
  EXPECT_NE(result.out.find("2 runs per controller"), std::string::npos) << result.out;
  const nlohmann::json json = nlohmann::json::parse(ReadText(dir.Path("out") + "/scorecard.json"));
  ASSERT_EQ(json.at("controllers").size(), 1u);
  ASSERT_EQ(json.at("runs").size(), 2u);
  // --runs-out keeps each run's outputs under <run>@<controller>, the same summary as the scorecard's.
  for (const nlohmann::json& run : json.at("runs")) {
    const std::string run_dir = dir.Path("runs") + "/" + run.at("run").get<std::string>() + "@open_loop";
    EXPECT_TRUE(std::filesystem::exists(run_dir + "/signals.csv")) << run_dir;
    EXPECT_TRUE(std::filesystem::exists(run_dir + "/config.yaml")) << run_dir;
    const nlohmann::json summary = nlohmann::json::parse(ReadText(run_dir + "/summary.json"));
    EXPECT_EQ(summary.at("metrics").at("held_s"), run.at("summary").at("metrics").at("held_s")) << run_dir;
  }
}

TEST(ScorecardCliTest, SeedAndVariationsScaleDrawAHeldOutSetFromTheSameRanges) {
  TempDir dir;
  const std::string common = "score --set-dir " + std::string(GRASPBED_SOURCE_DIR) +
                             "/scenarios/scorecard --limit 5 --controller open_loop ";
  const std::string version = " v" + std::to_string(LoadScorecardSet(kShippedSet).version);
  CliResult result = RunCli(common + "--out " + dir.Path("shipped"));
  ASSERT_EQ(result.exit_code, kExitOk) << result.out << result.err;
  EXPECT_NE(result.out.find(version + " seed 2026 ("), std::string::npos) << result.out;
  result = RunCli(common + "--seed 11 --variations-scale 2 --out " + dir.Path("held_out"));
  ASSERT_EQ(result.exit_code, kExitOk) << result.out << result.err;
  EXPECT_NE(result.out.find(version + " seed 11 ("), std::string::npos) << result.out;
  const nlohmann::json shipped = nlohmann::json::parse(ReadText(dir.Path("shipped") + "/scorecard.json"));
  const nlohmann::json held_out = nlohmann::json::parse(ReadText(dir.Path("held_out") + "/scorecard.json"));
  EXPECT_EQ(held_out.at("set").at("seed"), 11);
  // The shipped set gives the default base 3 variations, so its 5th run is the next base; scaled by
  // 2 the default base still fills the first 5 runs.
  const nlohmann::json& shipped_runs = shipped.at("runs");
  const nlohmann::json& held_out_runs = held_out.at("runs");
  ASSERT_EQ(shipped_runs.size(), 5u);
  ASSERT_EQ(held_out_runs.size(), 5u);
  EXPECT_EQ(shipped_runs[4].at("run"), "lift_unknown_mass.v0");
  EXPECT_EQ(held_out_runs[4].at("run"), "default.v4");
  // v0 is the base as shipped in both; the variations are other draws from the same ranges.
  EXPECT_EQ(shipped_runs[0].at("overrides"), held_out_runs[0].at("overrides"));
  EXPECT_NE(shipped_runs[1].at("overrides"), held_out_runs[1].at("overrides"));
  const double mass = std::stod(held_out_runs[1].at("overrides").at("object.mass_kg").get<std::string>());
  EXPECT_GE(mass, 0.05);
  EXPECT_LE(mass, 0.4);
}

TEST(ScorecardCliTest, BadInputExitsTwoWithOneLineAndWritesNothing) {
  TempDir dir;
  CliResult result = RunCli("score --set-dir " + dir.Path("nowhere") + " --out " + dir.Path("out"));
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_NE(result.err.find("set.yaml: cannot read the scorecard set"), std::string::npos) << result.err;
  result = RunCli("score --set-dir " + std::string(GRASPBED_SOURCE_DIR) +
                  "/scenarios/scorecard --controller no_such_controller --out " + dir.Path("out"));
  EXPECT_EQ(result.exit_code, kExitBadInput) << result.err;
  EXPECT_NE(result.err.find("no_such_controller"), std::string::npos) << result.err;
  EXPECT_FALSE(std::filesystem::exists(dir.Path("out")));
  result = RunCli("score --seed -1 --out " + dir.Path("out"));
  EXPECT_EQ(result.exit_code, kExitBadInput) << result.err;
  EXPECT_NE(result.err.find("--seed"), std::string::npos) << result.err;
  result = RunCli("score --variations-scale 0 --out " + dir.Path("out"));
  EXPECT_EQ(result.exit_code, kExitBadInput) << result.err;
  EXPECT_NE(result.err.find("--variations-scale"), std::string::npos) << result.err;
  EXPECT_FALSE(std::filesystem::exists(dir.Path("out")));
}

}  // namespace
}  // namespace graspbed::testbed
