// backend replay and `graspbed compare` through the real CLI: a simulated run replayed with the
// controller that recorded it writes the same commands bit for bit; with another controller the
// output shows both; a frame log replays frame by frame under the scenario's intent script; bad
// recordings are refused by name; a run compared with itself has zero residuals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/support/cli_runner.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed::testbed {
namespace {

using graspbed::test_support::CliBinary;
using graspbed::test_support::CliResult;
using graspbed::test_support::ReadText;
using graspbed::test_support::RunCli;
using graspbed::test_support::TempDir;
using test_support::Signals;

// A shipped scenario with slip: the grip-slip controller's commands depend on every frame.
constexpr char kScenario[] = "scenarios/pull_ramp.yaml";
constexpr int kUnits = 20;
constexpr double kR0Ohm = 3400.0;
// Fn = 5 N alone on a paper unit: R = R0 (1 + G kn Fn) = 3400 x 1.275.
constexpr double kLoadedOhm = 4335.0;
constexpr double kLoadedFnN = 5.0;
// The ideal sensor inverts the paper's numbers exactly up to rounding of the doubles.
constexpr double kInversionTolN = 1e-9;

/// The raw text of column `name` of a CSV, row by row (for bit-exact comparisons).
std::vector<std::string> ColumnText(const std::string& path, const std::string& name) {
  std::ifstream csv(path);
  std::string line;
  std::getline(csv, line);
  std::vector<std::string> header;
  std::stringstream split(line);
  for (std::string cell; std::getline(split, cell, ',');) header.push_back(cell);
  size_t column = header.size();
  for (size_t c = 0; c < header.size(); ++c) {
    if (header[c] == name) column = c;
  }
  std::vector<std::string> values;
  if (column == header.size()) {
    ADD_FAILURE() << path << " has no column " << name;
    return values;
  }
  while (std::getline(csv, line)) {
    std::stringstream cells(line);
    std::string cell;
    for (size_t c = 0; c <= column && std::getline(cells, cell, ','); ++c) {
    }
    values.push_back(cell);
  }
  return values;
}

class ReplayCompareTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY must point at the CLI";
  }
  std::string Path(const std::string& name) const { return dir_.Path(name); }
  nlohmann::json Summary(const std::string& run) const {
    return nlohmann::json::parse(ReadText(Path(run) + "/summary.json"));
  }
  /// The simulated reference run, once per test.
  void RunSimulation() {
    const CliResult sim = RunCli(std::string("run ") + kScenario + " --no-plots --out " + Path("sim"));
    ASSERT_EQ(sim.exit_code, 0) << sim.out << sim.err;
  }

  const TempDir dir_{"replay"};
};

TEST_F(ReplayCompareTest, ReplayWithTheRecordedControllerReproducesEveryCommandBitForBit) {
  RunSimulation();
  const CliResult replay = RunCli("run " + Path("sim") + "/config.yaml --backend replay --log " +
                                  Path("sim") + "/signals.csv --no-plots --out " + Path("replay"));
  ASSERT_EQ(replay.exit_code, 0) << replay.out << replay.err;
  const nlohmann::json bench = Summary("replay").at("bench");
  const size_t rows = ColumnText(Path("sim") + "/signals.csv", "time_s").size();
  ASSERT_GT(rows, 1000u);
  EXPECT_EQ(bench.at("recorded_ticks").get<size_t>(), rows);
  EXPECT_EQ(bench.at("commands_compared").get<size_t>(), rows);
  EXPECT_EQ(bench.at("commands_differing").get<size_t>(), 0u) << bench.dump(2);
  EXPECT_EQ(bench.at("max_effort_difference").get<double>(), 0.0);
  EXPECT_EQ(bench.at("intent_from").get<std::string>(), "recording");
  // The same text, cell by cell: the commands, the controller's target, the estimate and the
  // controller's own diagnostics.
  for (const char* column : {"grip_effort", "grip_target_n", "est_total_fn_n", "phase", "intent", "slip_flag",
                             "ctl_vibration_rms_n", "ctl_load_ratio", "ctl_centroid_drift_pitch"}) {
    EXPECT_TRUE(ColumnText(Path("sim") + "/signals.csv", column) ==
                ColumnText(Path("replay") + "/signals.csv", column))
        << column << " differs between the run and its replay";
  }
  // The recorded commands are written beside the new ones.
  EXPECT_TRUE(ColumnText(Path("sim") + "/signals.csv", "grip_effort") ==
              ColumnText(Path("replay") + "/signals.csv", "recorded_grip_effort"));
  // The slip the run saw is in the replay too (the scenario's pull makes the controller react).
  const Signals signals(Path("replay") + "/signals.csv");
  double flags = 0.0;
  for (double flag : signals.Column("slip_flag")) flags += flag;
  EXPECT_GT(flags, 0.0) << "the recording has no slip: the test would not exercise the controller";
}

TEST_F(ReplayCompareTest, AnotherControllerShowsItsCommandsBesideTheRecordedOnes) {
  RunSimulation();
  const CliResult replay =
      RunCli("run " + Path("sim") + "/config.yaml --backend replay --log " + Path("sim") +
             "/signals.csv --controller open_loop --out " + Path("open_loop"));
  ASSERT_EQ(replay.exit_code, 0) << replay.out << replay.err;
  const nlohmann::json bench = Summary("open_loop").at("bench");
  EXPECT_GT(bench.at("commands_differing").get<size_t>(), 0u);
  EXPECT_GT(bench.at("max_effort_difference").get<double>(), 0.0);
  EXPECT_NE(replay.out.find("commands differing from the recording"), std::string::npos) << replay.out;
  const Signals signals(Path("open_loop") + "/signals.csv");
  for (const char* column : {"grip_effort", "recorded_grip_effort", "command_differs", "est_total_fn_n"}) {
    EXPECT_TRUE(signals.Has(column)) << column;
  }
  EXPECT_FALSE(signals.Has("true_squeeze_n")) << "a replay has no ground truth: its columns are absent";
  EXPECT_TRUE(graspbed::test_support::ReadText(Path("open_loop") + "/grip.png").rfind("\x89PNG", 0) == 0);
}

TEST_F(ReplayCompareTest, AFrameLogReplaysFrameByFrameUnderTheScenariosIntentScript) {
  // A frame log as `hw --log` writes it: 150 unloaded frames (the tare takes 100), then 5 N on every unit.
  std::ofstream log(Path("frames.csv"));
  log << "seq,device_time_s";
  for (int k = 0; k < kUnits; ++k)
    log << ",r1_" << k << ",r2_" << k << ",fn_" << k << ",ft_" << k << ",valid_" << k;
  log << '\n';
  constexpr int kFrames = 300;
  for (int i = 0; i < kFrames; ++i) {
    const double r = i < 150 ? kR0Ohm : kLoadedOhm;
    log << i << ',' << 10.0 + 0.001 * i;  // the device's clock does not start at 0
    for (int k = 0; k < kUnits; ++k) log << ',' << r << ',' << r << ",0,0,1";
    log << '\n';
  }
  log.close();
  std::ofstream scenario(Path("bench.yaml"));
  scenario << "name: bench\nduration_s: 1.0\ncontroller: {name: grip_slip}\n"
              "script:\n  - {at_s: 0.12, action: close}\n";
  scenario.close();
  const CliResult replay = RunCli("run " + Path("bench.yaml") + " --backend replay --log " +
                                  Path("frames.csv") + " --json --no-plots --out " + Path("frame_replay"));
  ASSERT_EQ(replay.exit_code, 0) << replay.out << replay.err;
  const nlohmann::json summary = nlohmann::json::parse(replay.out);
  const nlohmann::json& bench = summary.at("bench");
  EXPECT_EQ(bench.at("recording_kind").get<std::string>(), "frame log");
  EXPECT_EQ(bench.at("recorded_ticks").get<int>(), kFrames);
  EXPECT_EQ(bench.at("loop_frames").get<int>(), kFrames);
  EXPECT_EQ(bench.at("intent_from").get<std::string>(), "script");
  EXPECT_FALSE(bench.at("commands_recorded").get<bool>());
  EXPECT_NEAR(bench.at("final_est_total_fn_n").get<double>(), kUnits * kLoadedFnN, kInversionTolN * kUnits);
  ASSERT_EQ(bench.at("intent_events").size(), 1u);
  EXPECT_EQ(bench.at("intent_events")[0].at("intent").get<std::string>(), "close");
  // Ticks at the frames' times from the first frame: the close fires at the first frame at or after
  // 0.12 s (10.12 - 10.0 may round below 0.12: then one frame later).
  const double applied_s = bench.at("intent_events")[0].at("applied_s").get<double>();
  EXPECT_GE(applied_s, 0.12);
  EXPECT_LE(applied_s, 0.12 + 0.001 + 1e-9);
}

TEST_F(ReplayCompareTest, BadRecordingsAreRefusedByName) {
  RunSimulation();
  CliResult missing =
      RunCli("run " + Path("sim") + "/config.yaml --backend replay --log " + Path("nothing.csv"));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find(Path("nothing.csv") + ": cannot read the recording"), std::string::npos)
      << missing.err;

  CliResult no_log = RunCli("run " + Path("sim") + "/config.yaml --backend replay");
  EXPECT_EQ(no_log.exit_code, 2);
  EXPECT_NE(no_log.err.find("replay needs the recording to replay"), std::string::npos) << no_log.err;

  // The 9-unit layout cannot replay a 20-unit recording.
  CliResult units =
      RunCli("run " + Path("sim") + "/config.yaml --set sensor.layout=paper_3x3 --backend replay --log " +
             Path("sim") + "/signals.csv");
  EXPECT_EQ(units.exit_code, 2);
  EXPECT_NE(units.err.find("the recording has 20 units (columns r1_ohm_K) but the scenario's layout has 9"),
            std::string::npos)
      << units.err;

  std::ofstream bad(Path("bad.csv"));
  bad << ReadText(Path("sim") + "/signals.csv").substr(0, 20000);
  bad << "\n0.5,close,holding,oops\n";
  bad.close();
  CliResult malformed =
      RunCli("run " + Path("sim") + "/config.yaml --backend replay --log " + Path("bad.csv"));
  EXPECT_EQ(malformed.exit_code, 2);
  EXPECT_NE(malformed.err.find(Path("bad.csv") + ":"), std::string::npos) << malformed.err;
  EXPECT_NE(malformed.err.find("cells, the header has"), std::string::npos) << malformed.err;
}

TEST_F(ReplayCompareTest, ARunComparedWithItselfHasZeroResidualsAndTheSameTimes) {
  RunSimulation();
  const CliResult compare =
      RunCli("compare " + Path("sim") + " " + Path("sim") + " --json --out " + Path("compare"));
  ASSERT_EQ(compare.exit_code, 0) << compare.out << compare.err;
  const nlohmann::json c = nlohmann::json::parse(compare.out);
  EXPECT_EQ(c.at("aligned_on").get<std::string>(), "close");
  EXPECT_EQ(c.at("shift_s").get<double>(), 0.0);
  EXPECT_EQ(c.at("fn_rms_n").get<double>(), 0.0);
  EXPECT_EQ(c.at("grip_rms_n").get<double>(), 0.0);
  EXPECT_EQ(c.at("effort_rms").get<double>(), 0.0);
  EXPECT_EQ(c.at("units").size(), static_cast<size_t>(kUnits));
  EXPECT_EQ(c.at("unmatched_events").get<int>(), 0);
  ASSERT_GE(c.at("events").size(), 3u) << "close and the controller's phases";
  for (const auto& event : c.at("events"))
    EXPECT_EQ(event.at("difference_s").get<double>(), 0.0) << event.dump();
  EXPECT_TRUE(ReadText(Path("compare") + "/compare.png").rfind("\x89PNG", 0) == 0);
  EXPECT_EQ(nlohmann::json::parse(ReadText(Path("compare") + "/compare.json")), c);

  // Against a replay with another controller: the same sensor data, so the same estimates; other
  // commands.
  ASSERT_EQ(RunCli("run " + Path("sim") + "/config.yaml --backend replay --log " + Path("sim") +
                   "/signals.csv --controller open_loop --no-plots --out " + Path("open_loop"))
                .exit_code,
            0);
  const nlohmann::json other =
      nlohmann::json::parse(RunCli("compare " + Path("sim") + " " + Path("open_loop") + " --json").out);
  EXPECT_EQ(other.at("fn_rms_n").get<double>(), 0.0);
  EXPECT_GT(other.at("effort_rms").get<double>(), 0.0);

  const CliResult bad = RunCli("compare " + Path("sim") + " " + Path("."));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("signals.csv: cannot read"), std::string::npos) << bad.err;
}

// Two runs that differ (the same scenario on two seeds of a noisy readout: other noise, so other
// estimates, commands and physics) on the same tick grid: compare's residuals are the ones computed
// here from the two signals.csv, row against row (an invalid unit's estimate counts as 0 N).
TEST_F(ReplayCompareTest, TheResidualsOfTwoDifferentRunsAreTheirSignalsDifferences) {
  for (const char* seed : {"1", "2"}) {
    const CliResult run = RunCli(std::string("run ") + kScenario + " --seed " + seed +
                                 " --set sensor.profile=divider_12bit --no-plots --out " + Path(std::string("seed") + seed));
    ASSERT_NE(run.exit_code, 2) << run.err;
  }
  const CliResult compare = RunCli("compare " + Path("seed1") + " " + Path("seed2") + " --json");
  ASSERT_EQ(compare.exit_code, 0) << compare.out << compare.err;
  const nlohmann::json c = nlohmann::json::parse(compare.out);
  ASSERT_EQ(c.at("shift_s").get<double>(), 0.0) << "the premise: both close at the same tick";

  const Signals a(Path("seed1") + "/signals.csv");
  const Signals b(Path("seed2") + "/signals.csv");
  ASSERT_EQ(a.rows(), b.rows());
  double grip_sq = 0.0, effort_sq = 0.0, fn_sq = 0.0, grip_max = 0.0;
  std::vector<double> unit_fn_sq(kUnits, 0.0), unit_ft_sq(kUnits, 0.0);
  for (size_t i = 0; i < a.rows(); ++i) {
    ASSERT_EQ(a.At("time_s", i), b.At("time_s", i));
    const double grip = b.At("est_total_fn_n", i) - a.At("est_total_fn_n", i);
    grip_sq += grip * grip;
    grip_max = std::max(grip_max, std::abs(grip));
    const double effort = b.At("grip_effort", i) - a.At("grip_effort", i);
    effort_sq += effort * effort;
    for (int u = 0; u < kUnits; ++u) {
      const std::string k = std::to_string(u);
      const auto reading = [&](const Signals& run, const std::string& column) {
        return run.At("validity_" + k, i) == 0.0 ? run.At(column + k, i) : 0.0;
      };
      const double fn = reading(b, "fn_est_n_") - reading(a, "fn_est_n_");
      const double ft = reading(b, "ft_est_n_") - reading(a, "ft_est_n_");
      unit_fn_sq[u] += fn * fn;
      unit_ft_sq[u] += ft * ft;
      fn_sq += fn * fn;
    }
  }
  const double n = static_cast<double>(a.rows());
  // Both sides read the same text of the two files: the sums differ only in their rounding.
  constexpr double kRelTol = 1e-9;
  const auto near = [&](double expected, const nlohmann::json& got, const char* what) {
    EXPECT_NEAR(got.get<double>(), expected, kRelTol * std::max(1.0, std::abs(expected))) << what;
  };
  EXPECT_EQ(c.at("samples").get<size_t>(), a.rows());
  near(std::sqrt(grip_sq / n), c.at("grip_rms_n"), "grip_rms_n");
  near(grip_max, c.at("grip_max_abs_n"), "grip_max_abs_n");
  near(std::sqrt(effort_sq / n), c.at("effort_rms"), "effort_rms");
  near(std::sqrt(fn_sq / (n * kUnits)), c.at("fn_rms_n"), "fn_rms_n");
  for (int u = 0; u < kUnits; ++u) {
    near(std::sqrt(unit_fn_sq[u] / n), c.at("units")[u].at("fn_rms_n"), "unit fn_rms_n");
    near(std::sqrt(unit_ft_sq[u] / n), c.at("units")[u].at("ft_rms_n"), "unit ft_rms_n");
  }
  // They do differ: the noise alone moves the sensed grip by more than an ADC step.
  EXPECT_GT(c.at("grip_rms_n").get<double>(), 0.01);
  EXPECT_GT(c.at("fn_rms_n").get<double>(), 0.0);
}

// A session where the person closes 0.2 s and opens 0.5 s later than the script did: aligned
// piecewise on each intent change, the release lines up again (the controller enters releasing and
// open at the same delay after the open in both), where one shift taken at close would leave it
// 0.3 s apart. The hold itself differs a little: the box has settled 0.2 s longer when the digits
// reach it, and the closing impact is sensitive to that (loading and holding within 30 ms).
TEST_F(ReplayCompareTest, EachIntentChangeRealignsTheRunsSoALateOpenIsNoResidual) {
  const auto scenario = [&](const std::string& name, double close_s, double open_s) {
    const std::string file = dir_.Write(
        name + ".yaml", "name: " + name +
                            "\nduration_s: 2.2\nsensor: {profile: ideal}\n"
                            "controller: {name: grip_slip}\n"
                            "script:\n  - {at_s: " +
                            std::to_string(close_s) +
                            ", action: close}\n  - {at_s: " + std::to_string(open_s) + ", action: open}\n");
    const CliResult run = RunCli("run " + file + " --no-plots --out " + Path(name));
    ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  };
  scenario("script", 0.15, 1.0);
  scenario("person", 0.35, 1.5);
  const CliResult compare = RunCli("compare " + Path("script") + " " + Path("person") + " --json");
  ASSERT_EQ(compare.exit_code, 0) << compare.out << compare.err;
  const nlohmann::json c = nlohmann::json::parse(compare.out);
  const nlohmann::json& anchors = c.at("anchors");
  ASSERT_EQ(anchors.size(), 2u) << c.dump();
  EXPECT_EQ(anchors[0].at("intent"), "close");
  EXPECT_NEAR(anchors[0].at("shift_s").get<double>(), 0.2, 1e-3);
  EXPECT_EQ(anchors[1].at("intent"), "open");
  EXPECT_NEAR(anchors[1].at("shift_s").get<double>(), 0.5, 1e-3);
  bool released = false;
  for (const auto& event : c.at("events")) {
    if (event.at("a_s").get<double>() < anchors[0].at("a_s").get<double>()) continue;  // before close
    const bool after_open = event.at("a_s").get<double>() >= anchors[1].at("a_s").get<double>();
    EXPECT_LE(std::abs(event.at("difference_s").get<double>()), after_open ? 0.002 : 0.03) << event.dump();
    released = released || event.at("name") == "releasing";
  }
  EXPECT_TRUE(released) << c.dump();
  const nlohmann::json script = Summary("script");
  EXPECT_LT(c.at("grip_rms_n").get<double>(), 0.1 * script.at("metrics").at("peak_grip_n").get<double>())
      << c.dump();
}

}  // namespace
}  // namespace graspbed::testbed
