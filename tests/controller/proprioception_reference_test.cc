// The reference controller's proprioceptive parts, each where it decides the outcome of a real
// simulated run (through the `graspbed run` command): the motor's squeeze estimate keeps a 3 g cup
// uncrushed that the units alone crush, and a closing that meets nothing stops at the closed stop
// instead of stalling the motor there. Each is run with the part switched off (the strawman).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/signal_log.h"
#include "tests/support/cli_runner.h"
#include "tests/support/temp_dir.h"

namespace graspbed::controller {
namespace {

using graspbed::test_support::CliResult;
using graspbed::test_support::RunCli;
using graspbed::test_support::TempDir;

/// `graspbed run` of `scenario` with `sets` (each "key=value"), its summary JSON.
nlohmann::json RunScenario(const std::string& scenario, const std::vector<std::string>& sets,
                           const std::string& out_dir) {
  std::string arguments = "run " + std::string(GRASPBED_SOURCE_DIR) + "/scenarios/" + scenario +
                          ".yaml --no-plots --json --out " + out_dir;
  for (const std::string& set : sets) arguments += " --set " + set;
  const CliResult cli = RunCli(arguments);
  EXPECT_TRUE(cli.exit_code == 0 || cli.exit_code == 1) << arguments << "\n" << cli.err;
  return nlohmann::json::parse(cli.out, nullptr, /*allow_exceptions=*/false);
}

/// Whether expectation `name` of a run's summary passed.
bool Passed(const nlohmann::json& run, const std::string& name) {
  for (const nlohmann::json& expectation : run["expectations"]) {
    if (expectation["name"] == name) return expectation["passed"].get<bool>();
  }
  ADD_FAILURE() << "no expectation " << name;
  return false;
}

/// The last row's cell in column `name` of signals.csv in `dir`.
std::string LastCell(const common::CsvTable& signals, const std::string& name) {
  return signals.rows.back()[signals.Column(name)];
}

TEST(ProprioceptionReferenceTest, TheMotorsSqueezeKeepsTheCupUncrushedWhereTheUnitsAloneCrushIt) {
  TempDir dir;
  // Half the cup's squeeze lands on the holder between the mesas: a grip on the units alone is a
  // squeeze twice as large, past the cup's 3 N.
  const nlohmann::json blind = RunScenario("lift_plastic_cup", {"controller.params.proprioception=0"},
                                           (dir.path() / "blind").string());
  EXPECT_FALSE(Passed(blind, "not_crushed"));
  // The hand that reports no proprioception leaves the reference as blind.
  const nlohmann::json numb =
      RunScenario("lift_plastic_cup", {"proprioception.enabled=false"}, (dir.path() / "numb").string());
  EXPECT_FALSE(Passed(numb, "not_crushed"));
  const nlohmann::json feeling = RunScenario("lift_plastic_cup", {}, (dir.path() / "feeling").string());
  EXPECT_TRUE(Passed(feeling, "not_crushed"));
  EXPECT_TRUE(Passed(feeling, "not_dropped"));
  EXPECT_TRUE(Passed(feeling, "max_slip_mm"));
}

TEST(ProprioceptionReferenceTest, AClosingThatFindsNothingStopsAtTheClosedStop) {
  TempDir dir;
  // The hand 15 cm beside the box and 20 cm up: the digits close on air.
  const std::string away = "hand.initial_wrist_position_m=[0.15,0,0.2]";
  const std::string feeling_dir = (dir.path() / "feeling").string();
  RunScenario("default", {away, "duration_s=2.6"}, feeling_dir);
  const common::CsvTable feeling = common::ReadCsvTable(feeling_dir + "/signals.csv");
  EXPECT_EQ(LastCell(feeling, "phase"), "missed");
  EXPECT_EQ(std::stod(LastCell(feeling, "grip_effort")), 0.0);
  EXPECT_GT(std::stod(LastCell(feeling, "finger_q1")), 0.9);  // the index flexed all the way [rad]

  const std::string blind_dir = (dir.path() / "blind").string();
  RunScenario("default", {away, "duration_s=2.6", "controller.params.proprioception=0"}, blind_dir);
  const common::CsvTable blind = common::ReadCsvTable(blind_dir + "/signals.csv");
  EXPECT_EQ(LastCell(blind, "phase"), "closing");  // stalls the motor against the stop for ever
  EXPECT_GT(std::stod(LastCell(blind, "grip_effort")), 0.0);
}

/// How many rows of `dir`'s signals.csv name `cue` among their slip cues.
int RowsFlaggedBy(const std::string& dir, const std::string& cue) {
  const common::CsvTable signals = common::ReadCsvTable(dir + "/signals.csv");
  const size_t cues = signals.Column("slip_cues");
  int rows = 0;
  for (const std::vector<std::string>& row : signals.rows) rows += row[cues].find(cue) != std::string::npos ? 1 : 0;
  return rows;
}

TEST(LearnedCueInTheReferenceTest, TheShippedModelFlagsTheAddedMassBesideTheHandTunedCues) {
  TempDir dir;
  const std::string with_dir = (dir.path() / "with").string();
  const nlohmann::json with =
      RunScenario("added_mass_step", {"controller.params.learned_cue=1"}, with_dir);
  EXPECT_TRUE(Passed(with, "not_dropped"));
  EXPECT_GT(RowsFlaggedBy(with_dir, "learned"), 0);  // the cue's own label in slip_cues
  const std::string without_dir = (dir.path() / "without").string();
  RunScenario("added_mass_step", {}, without_dir);
  EXPECT_EQ(RowsFlaggedBy(without_dir, "learned"), 0);
}

}  // namespace
}  // namespace graspbed::controller
