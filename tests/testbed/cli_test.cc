// The real `graspbed` executable ($GRASPBED_BINARY): run's exit codes and outputs, nothing written on
// bad input, determinism, suites in parallel against serial, sweeps sharded and merged against one
// unsharded sweep, progress output off a terminal and on one, and Ctrl-C (SIGINT) during a run, a
// suite and a sweep.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/support/cli_runner.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"
#include "tests/testbed/scenario_test_util.h"

extern char** environ;

namespace graspbed::testbed {
namespace {

namespace fs = std::filesystem;
using graspbed::test_support::CliBinary;
using graspbed::test_support::CliResult;
using graspbed::test_support::ReadText;
using graspbed::test_support::RunCli;
using graspbed::test_support::TempDir;
using test_support::HeldBoxScenario;

// Exit codes of the CLI (app/command_registry.h, app/cmd_run.cc).
constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInterrupted = 130;

// How long a test waits for a child's progress before giving up: a deadline, not a pass criterion
// (a wait returns as soon as the progress shows). A suite computes each run's oracle grip before the
// run starts; for the 60 s scenario below that took over 30 s with both cores loaded by two busy
// loops beside ctest -j2 (2026-11-27), and 6 s idle.
constexpr auto kPatience = std::chrono::seconds(120);

nlohmann::json ReadJson(const std::string& path) {
  const std::string text = ReadText(path);
  if (text.empty()) {
    ADD_FAILURE() << "cannot read " << path;
    return nlohmann::json::object();
  }
  return nlohmann::json::parse(text);
}

// Every file below `dir`, relative, sorted.
std::set<std::string> FilesUnder(const fs::path& dir) {
  std::set<std::string> files;
  if (!fs::exists(dir)) return files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) files.insert(fs::relative(entry.path(), dir).string());
  }
  return files;
}

// No temporary file of an atomic write is left below `dir`.
void ExpectNoTemporaries(const fs::path& dir) {
  for (const std::string& file : FilesUnder(dir)) EXPECT_EQ(file.find(".tmp-"), std::string::npos) << file;
}

// A summary's metrics without the wall-clock ones (which differ between identical runs).
nlohmann::json Deterministic(nlohmann::json summary) {
  summary.erase("real_time_factor");
  if (summary.contains("metrics")) summary["metrics"].erase("wall_s");
  summary.erase("wall_s");
  summary.erase("source_file");
  return summary;
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY must point at the CLI";
  }
  TempDir dir_;
};

// ---- run: exit codes and outputs ---------------------------------------------------------------------

TEST_F(CliTest, RunExitsZeroWhenEveryExpectationHoldsAndWritesEveryOutput) {
  const std::string file =
      dir_.Write("held.yaml", HeldBoxScenario(0.5, "", "expectations: {not_dropped: true}\n"));
  const std::string out = dir_.Path("out");
  const CliResult result = RunCli("run " + file + " --out " + out);
  EXPECT_EQ(result.exit_code, kExitOk) << result.out << result.err;
  EXPECT_NE(result.out.find("scenario held, controller open_loop, seed 1: PASSED"), std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("[pass] not_dropped"), std::string::npos) << result.out;
  // Off a terminal there is no progress line: stderr stays empty.
  EXPECT_EQ(result.err, "");
  const std::set<std::string> expected = {
      "config.yaml", "signals.csv", "states.csv", "summary.json",  "forces.png",   "estimate_vs_truth.png",
      "grip.png",    "slip.png",    "height.png", "taxels_fn.png", "taxels_ft.png"};
  EXPECT_EQ(FilesUnder(out), expected);
  const nlohmann::json summary = ReadJson(out + "/summary.json");
  EXPECT_EQ(summary.at("passed"), true);
  EXPECT_EQ(summary.at("completed"), true);
  for (const char* key :
       {"dropped", "max_slip_mm", "peak_grip_n", "crushed", "slip_detect_latency_ms", "false_slip_per_min",
        "fn_rmse_n", "ft_rmse_n", "time_to_stable_s", "sim_s", "wall_s"}) {
    EXPECT_TRUE(summary.at("metrics").contains(key)) << key;
  }
  EXPECT_NEAR(summary.at("metrics").at("sim_s").get<double>(), 0.5, 1e-6);
  // One row per control tick after the header: 1 kHz on 1 ms steps, one at the end of each step
  // (1, 2, ..., 500 ms; the tick due at 0 runs at the end of the first step, with the one due then).
  const std::string csv = ReadText(out + "/signals.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 500);
  // PNG files start with the PNG signature.
  EXPECT_EQ(ReadText(out + "/grip.png").substr(1, 3), "PNG");
}

TEST_F(CliTest, RunExitsOneWhenAnExpectationFailsAndJsonGoesToStdout) {
  const std::string file = dir_.Write(
      "tight.yaml", HeldBoxScenario(0.3, "", "expectations: {not_dropped: true, max_peak_grip_n: 1}\n"));
  const std::string out = dir_.Path("out");
  const CliResult table = RunCli("run " + file + " --out " + out + " --no-plots");
  EXPECT_EQ(table.exit_code, kExitFailed) << table.out << table.err;
  EXPECT_NE(table.out.find("FAILED"), std::string::npos);
  EXPECT_NE(table.out.find("[FAIL] max_peak_grip_n"), std::string::npos) << table.out;
  EXPECT_EQ(FilesUnder(out),
            (std::set<std::string>{"config.yaml", "signals.csv", "states.csv", "summary.json"}));

  const CliResult json = RunCli("run " + file + " --out " + out + " --no-plots --json");
  EXPECT_EQ(json.exit_code, kExitFailed);
  const nlohmann::json summary = nlohmann::json::parse(json.out);
  EXPECT_EQ(summary.at("passed"), false);
  EXPECT_EQ(summary.at("completed"), true);
  bool found = false;
  for (const nlohmann::json& e : summary.at("expectations")) {
    if (e.at("name") == "max_peak_grip_n") {
      found = true;
      EXPECT_EQ(e.at("passed"), false);
    }
    if (e.at("name") == "not_dropped") {
      EXPECT_EQ(e.at("passed"), true);
    }
  }
  EXPECT_TRUE(found);
  // --set can turn the failure into a pass.
  const CliResult relaxed =
      RunCli("run " + file + " --out " + out + " --no-plots --set expectations.max_peak_grip_n=50");
  EXPECT_EQ(relaxed.exit_code, kExitOk) << relaxed.out << relaxed.err;
}

TEST_F(CliTest, RunExitsTwoOnBadInputWithFileLineAndKeyAndWritesNothing) {
  const std::string good = dir_.Write("good.yaml", HeldBoxScenario(0.3));
  const std::string bad = dir_.Write("bad.yaml", "duration_s: 0.3\nobject:\n  shape: box\n  mas_kg: 0.1\n");
  const std::string wrap =
      dir_.Write("wrap.yaml", "duration_s: 0.3\nobject: {shape: cylinder}\nhand: {grasp: wrap}\n");
  const struct {
    std::string arguments;
    std::string message;
  } cases[] = {
      {"run " + bad, bad + ":4: object.mas_kg: unknown key; valid keys: "},
      {"run " + good + " --set object.mass_kg=-2", "--set object.mass_kg=-2: "},
      {"run " + good + " --set object.mass_kg", "--set object.mass_kg: expected key=value"},
      {"run " + good + " --controller pid", "controller.name = pid: unknown name; valid names: "},
      {"run " + good + " --set script[0].action=jump",
       "script[0].action = jump: unknown name; valid names: close"},
      {"run " + dir_.Path("missing.yaml"), dir_.Path("missing.yaml") + ": cannot open scenario file"},
      // A wrap of a cylinder the hand cannot wrap names the keys and why.
      {"run " + wrap + " --set \"object.size_m=[0.02,0.02,0.1]\"",
       "object.size_m / hand.grasp wrap: a wrap of a 20 mm cylinder: too small"},
      {"run " + good + " --seed -1", ""},
      {"run", ""},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.arguments);
    const std::string out = dir_.Path("out_bad");
    const CliResult result = RunCli(c.arguments + " --out " + out);
    EXPECT_EQ(result.exit_code, kExitBadInput) << result.out << result.err;
    EXPECT_NE(result.err.find(c.message), std::string::npos) << result.err;
    EXPECT_EQ(result.out, "");
    EXPECT_FALSE(fs::exists(out)) << "bad input must not create the output directory";
  }
  // An existing result is left as it was when a later run is refused.
  const std::string out = dir_.Path("kept");
  ASSERT_EQ(RunCli("run " + good + " --out " + out + " --no-plots").exit_code, kExitOk);
  const std::string before = ReadText(out + "/summary.json");
  EXPECT_EQ(RunCli("run " + good + " --out " + out + " --set object.mass_kg=-2").exit_code, kExitBadInput);
  EXPECT_EQ(ReadText(out + "/summary.json"), before);
  EXPECT_FALSE(fs::exists(out + "/INCOMPLETE"));
  // An output directory that cannot be made (under a regular file) is bad input too, not a failed run.
  const std::string file_in_the_way = dir_.Write("not_a_dir", "x");
  const CliResult unwritable = RunCli("run " + good + " --no-plots --out " + file_in_the_way + "/out");
  EXPECT_EQ(unwritable.exit_code, kExitBadInput) << unwritable.err;
  EXPECT_NE(unwritable.err.find("--out " + file_in_the_way + "/out: cannot create the output directory"),
            std::string::npos)
      << unwritable.err;
}

// ---- determinism ------------------------------------------------------------------------------------------

TEST_F(CliTest, SameSeedGivesIdenticalSignalsAndADifferentSeedDoes) {
  // Noise, R0 spread and random frame loss all drawn from the seed.
  const std::string file =
      dir_.Write("noisy.yaml", HeldBoxScenario(0.4, "",
                                               "seed: 5\nsensor: {drop_probability: 0.05, strain_model: "
                                               "{noise_ohm: 2, r0_spread_fraction: 0.01}}\n"));
  const auto signals = [&](const std::string& name, const std::string& extra) {
    const CliResult result = RunCli("run " + file + " --no-plots --out " + dir_.Path(name) + extra);
    EXPECT_EQ(result.exit_code, kExitOk) << result.err;
    return ReadText(dir_.Path(name) + "/signals.csv");
  };
  const std::string first = signals("a", "");
  const std::string second = signals("b", "");
  ASSERT_GT(first.size(), 10000u);
  EXPECT_TRUE(first == second) << "same scenario and seed, different signals.csv";
  EXPECT_EQ(Deterministic(ReadJson(dir_.Path("a") + "/summary.json")),
            Deterministic(ReadJson(dir_.Path("b") + "/summary.json")));
  EXPECT_EQ(ReadText(dir_.Path("a") + "/config.yaml"), ReadText(dir_.Path("b") + "/config.yaml"));
  const std::string reseeded = signals("c", " --seed 6");
  EXPECT_FALSE(first == reseeded) << "a different seed must change the noisy signals";
  // The resolved config.yaml reproduces the run byte for byte.
  const CliResult again = RunCli("run " + dir_.Path("a") + "/config.yaml --no-plots --out " + dir_.Path("d"));
  EXPECT_EQ(again.exit_code, kExitOk) << again.err;
  EXPECT_TRUE(ReadText(dir_.Path("d") + "/signals.csv") == first) << "config.yaml does not reproduce the run";
}

// ---- suites
// --------------------------------------------------------------------------------------------------

TEST_F(CliTest, SuiteInParallelGivesTheSameResultsAsSerial) {
  const std::string suite = dir_.Path("suite");
  dir_.Write("suite/a_hold.yaml", HeldBoxScenario(0.4, "", "expectations: {not_dropped: true}\n"));
  dir_.Write("suite/b_heavy.yaml", HeldBoxScenario(0.6, "  - {at_s: 0.45, action: add_mass, mass_kg: 2}\n",
                                                   "expectations: {not_dropped: true}\n"));
  dir_.Write(
      "suite/c_noisy.yaml",
      HeldBoxScenario(0.3, "",
                      "seed: 3\nsensor: {strain_model: {noise_ohm: 2}}\nexpectations: {max_slip_mm: 5}\n"));
  dir_.Write("suite/notes.txt", "not a scenario\n");
  const CliResult serial = RunCli("suite " + suite + " -j 1 --no-plots --out " + dir_.Path("j1"));
  const CliResult parallel = RunCli("suite " + suite + " -j 2 --no-plots --out " + dir_.Path("j2"));
  EXPECT_EQ(serial.exit_code, kExitFailed) << serial.out << serial.err;  // b_heavy drops its box
  EXPECT_EQ(parallel.exit_code, kExitFailed) << parallel.out << parallel.err;
  EXPECT_EQ(serial.err, "");
  EXPECT_EQ(parallel.err, "");
  EXPECT_NE(serial.out.find("2 passed, 1 failed, 3 scenarios"), std::string::npos) << serial.out;
  EXPECT_NE(parallel.out.find("with 2 jobs"), std::string::npos) << parallel.out;
  const nlohmann::json j1 = ReadJson(dir_.Path("j1") + "/suite.json");
  const nlohmann::json j2 = ReadJson(dir_.Path("j2") + "/suite.json");
  EXPECT_EQ(j1.at("jobs"), 1);
  EXPECT_EQ(j2.at("jobs"), 2);
  EXPECT_EQ(j1.at("completed"), true);
  ASSERT_EQ(j1.at("runs").size(), 3u);
  ASSERT_EQ(j2.at("runs").size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const std::string name = j1.at("runs")[i].at("scenario");
    SCOPED_TRACE(name);
    EXPECT_EQ(Deterministic(j1.at("runs")[i]), Deterministic(j2.at("runs")[i]));
    EXPECT_TRUE(ReadText(dir_.Path("j1/" + name + "/signals.csv")) ==
                ReadText(dir_.Path("j2/" + name + "/signals.csv")));
    EXPECT_EQ(j1.at("runs")[i].at("passed"), name != "b_heavy");
  }
  ExpectNoTemporaries(dir_.Path("j2"));
}

TEST_F(CliTest, SuiteWithOneBadFileRunsNothing) {
  dir_.Write("suite/a.yaml", HeldBoxScenario(0.3));
  dir_.Write("suite/b.yaml", "duration_s: 0.3\nscript:\n  - {at_s: 0.1, action: jump}\n");
  const CliResult result = RunCli("suite " + dir_.Path("suite") + " --out " + dir_.Path("out"));
  EXPECT_EQ(result.exit_code, kExitBadInput);
  EXPECT_NE(result.err.find(dir_.Path("suite/b.yaml") + ":3: script[0].action = jump: unknown name"),
            std::string::npos)
      << result.err;
  EXPECT_FALSE(fs::exists(dir_.Path("out")));
  // Two files with the same scenario name would share an output directory.
  dir_.Write("twins/a.yaml", "name: same\n" + HeldBoxScenario(0.3));
  dir_.Write("twins/b.yaml", "name: same\n" + HeldBoxScenario(0.3));
  const CliResult twins = RunCli("suite " + dir_.Path("twins") + " --out " + dir_.Path("out"));
  EXPECT_EQ(twins.exit_code, kExitBadInput);
  EXPECT_NE(twins.err.find("name = same: another scenario of the suite has the same name"), std::string::npos)
      << twins.err;
  EXPECT_EQ(RunCli("suite " + dir_.Path("empty_dir_that_is_missing")).exit_code, kExitBadInput);
}

// ---- sweeps, shards and merge
// ---------------------------------------------------------------------------------

// Rows of a results.jsonl without the wall-clock column.
std::vector<nlohmann::json> Rows(const std::string& dir) {
  std::vector<nlohmann::json> rows;
  std::istringstream lines(ReadText(dir + "/results.jsonl"));
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty()) continue;
    nlohmann::json row = nlohmann::json::parse(line);
    row.erase("wall_s");
    rows.push_back(row);
  }
  return rows;
}

// results.csv without its wall_s column.
std::string CsvWithoutWall(const std::string& path) {
  std::istringstream lines(ReadText(path));
  std::string line;
  std::string text;
  int wall_column = -1;
  while (std::getline(lines, line)) {
    std::vector<std::string> cells;
    std::stringstream stream(line);
    std::string cell;
    while (std::getline(stream, cell, ',')) cells.push_back(cell);
    if (wall_column < 0) {
      for (size_t c = 0; c < cells.size(); ++c) {
        if (cells[c] == "wall_s") wall_column = static_cast<int>(c);
      }
    }
    for (size_t c = 0; c < cells.size(); ++c) {
      if (static_cast<int>(c) != wall_column) text += cells[c] + ";";
    }
    text += "\n";
  }
  return text;
}

TEST_F(CliTest, ShardedSweepMergesToTheRowsOfOneUnshardedSweep) {
  dir_.Write("base.yaml", HeldBoxScenario(0.3, "", "expectations: {max_peak_grip_n: 12}\n"));
  const std::string grid = dir_.Write("grid.yaml", R"(scenario: base.yaml
set: {duration_s: 0.25}
parameters:
  object.mass_kg: [0.1, 0.3]
  controller.params.close_effort: [0.3, 0.7]
  seed: [1]
)");
  const CliResult whole = RunCli("sweep " + grid + " --out " + dir_.Path("whole"));
  ASSERT_EQ(whole.exit_code, kExitOk) << whole.out << whole.err;
  EXPECT_EQ(whole.err, "");
  const CliResult first = RunCli("sweep " + grid + " --shard 1/2 --out " + dir_.Path("s1"));
  const CliResult second = RunCli("sweep " + grid + " --shard 2/2 -j 2 --out " + dir_.Path("s2"));
  ASSERT_EQ(first.exit_code, kExitOk) << first.err;
  ASSERT_EQ(second.exit_code, kExitOk) << second.err;
  // Shard K/N (1-based) holds the runs with index % N == K - 1.
  EXPECT_EQ(ReadJson(dir_.Path("s1") + "/manifest.json").at("runs"), nlohmann::json({0, 2}));
  EXPECT_EQ(ReadJson(dir_.Path("s2") + "/manifest.json").at("runs"), nlohmann::json({1, 3}));
  const CliResult merged =
      RunCli("merge " + dir_.Path("s2") + " " + dir_.Path("s1") + " --out " + dir_.Path("m"));
  ASSERT_EQ(merged.exit_code, kExitOk) << merged.err;
  EXPECT_NE(merged.out.find("4 rows"), std::string::npos) << merged.out;

  const std::vector<nlohmann::json> expected = Rows(dir_.Path("whole"));
  ASSERT_EQ(expected.size(), 4u);
  EXPECT_EQ(Rows(dir_.Path("m")), expected);
  EXPECT_EQ(CsvWithoutWall(dir_.Path("m") + "/results.csv"),
            CsvWithoutWall(dir_.Path("whole") + "/results.csv"));
  // Grid order: last parameter fastest; the values are real parameters of the runs.
  EXPECT_EQ(expected[1].at("object.mass_kg"), 0.1);
  EXPECT_EQ(expected[1].at("controller.params.close_effort"), 0.7);
  EXPECT_EQ(expected[2].at("object.mass_kg"), 0.3);
  EXPECT_LT(expected[0].at("peak_grip_n").get<double>(), expected[1].at("peak_grip_n").get<double>());
  EXPECT_NEAR(expected[0].at("sim_s").get<double>(), 0.25, 1e-6);  // the spec's `set:` applied
  // The strong grip breaks the 12 N limit, the weak one does not.
  EXPECT_EQ(expected[0].at("passed"), true);
  EXPECT_EQ(expected[1].at("passed"), false);
  EXPECT_EQ(expected[1].at("failed_expectations"), "max_peak_grip_n");

  // Merge refuses an incomplete set of shards, a shard given twice and a foreign one.
  CliResult refused = RunCli("merge " + dir_.Path("s1") + " --out " + dir_.Path("m2"));
  EXPECT_EQ(refused.exit_code, kExitBadInput);
  EXPECT_NE(refused.err.find("missing shard(s) 2/2"), std::string::npos) << refused.err;
  refused = RunCli("merge " + dir_.Path("s1") + " " + dir_.Path("s1") + " --out " + dir_.Path("m2"));
  EXPECT_EQ(refused.exit_code, kExitBadInput);
  EXPECT_NE(refused.err.find("given twice"), std::string::npos) << refused.err;
  refused = RunCli("merge " + dir_.Path("s1") + " " + dir_.Path("whole") + " --out " + dir_.Path("m2"));
  EXPECT_EQ(refused.exit_code, kExitBadInput);
  EXPECT_FALSE(fs::exists(dir_.Path("m2") + "/results.jsonl"));
}

TEST_F(CliTest, RandomSweepSamplesDoNotDependOnSharding) {
  dir_.Write("base.yaml", HeldBoxScenario(0.2));
  const std::string spec = dir_.Write("random.yaml", R"(scenario: base.yaml
mode: random
samples: 3
seed: 11
parameters:
  object.friction: {min: 0.3, max: 1.0}
  object.mass_kg: {min: 0.05, max: 0.5, log: true}
  seed: {min: 1, max: 1000, integer: true}
)");
  ASSERT_EQ(RunCli("sweep " + spec + " --out " + dir_.Path("whole")).exit_code, kExitOk);
  for (const char* shard : {"1/3", "2/3", "3/3"}) {
    const std::string out = dir_.Path(std::string("s") + shard[0]);
    ASSERT_EQ(RunCli("sweep " + spec + " --shard " + shard + " --out " + out).exit_code, kExitOk);
  }
  ASSERT_EQ(RunCli("merge " + dir_.Path("s1") + " " + dir_.Path("s2") + " " + dir_.Path("s3") + " --out " +
                   dir_.Path("m"))
                .exit_code,
            kExitOk);
  const std::vector<nlohmann::json> rows = Rows(dir_.Path("whole"));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(Rows(dir_.Path("m")), rows);
  for (const nlohmann::json& row : rows) {
    EXPECT_GE(row.at("object.friction").get<double>(), 0.3);
    EXPECT_LE(row.at("object.friction").get<double>(), 1.0);
    EXPECT_GE(row.at("object.mass_kg").get<double>(), 0.05);
    EXPECT_LE(row.at("object.mass_kg").get<double>(), 0.5);
    const double seed = row.at("seed").get<double>();
    EXPECT_EQ(seed, std::round(seed));
  }
  EXPECT_NE(rows[0].at("object.friction"), rows[1].at("object.friction"));
}

// The shipped sweep specs run as the README gives them (the grid of the default lift over friction,
// mass and controller; a random draw of noise and seed), and the spec printed in docs/scenarios.md
// loads.
TEST_F(CliTest, TheShippedSweepSpecsAndTheDocumentedOneRun) {
  for (const char* spec : {"friction_mass", "noise_random"}) {
    SCOPED_TRACE(spec);
    const std::string out = dir_.Path(spec);
    const CliResult result = RunCli("sweep " + std::string(GRASPBED_SOURCE_DIR) + "/scenarios/sweeps/" + spec +
                                    ".yaml -j 2 --out " + out);
    ASSERT_EQ(result.exit_code, kExitOk) << result.err;
    EXPECT_NE(result.out.find(std::string(spec) == "friction_mass" ? "12 of 12 runs finished" : "40 of 40 runs"),
              std::string::npos)
        << result.out;
  }
  // The first ```yaml block after "## Sweeps" in docs/scenarios.md, its scenario path made absolute.
  const std::string doc = ReadText(std::string(GRASPBED_SOURCE_DIR) + "/docs/scenarios.md");
  const size_t section = doc.find("## Sweeps");
  ASSERT_NE(section, std::string::npos);
  const size_t start = doc.find("```yaml\n", section);
  const size_t end = doc.find("```\n", start + 8);
  ASSERT_NE(start, std::string::npos);
  std::string documented = doc.substr(start + 8, end - start - 8);
  const std::string relative = "../scenarios/default.yaml";
  ASSERT_NE(documented.find(relative), std::string::npos) << documented;
  documented.replace(documented.find(relative), relative.size(),
                     std::string(GRASPBED_SOURCE_DIR) + "/scenarios/default.yaml");
  const std::string spec = dir_.Write("documented.yaml", documented);
  const CliResult result = RunCli("sweep " + spec + " --shard 1/50 -j 2 --out " + dir_.Path("documented"));
  EXPECT_EQ(result.exit_code, kExitOk) << documented << result.err;
}

TEST_F(CliTest, SweepRefusesBadSpecsAndShardsWithFileAndLine) {
  dir_.Write("base.yaml", HeldBoxScenario(0.2));
  const std::string spec =
      dir_.Write("grid.yaml", "scenario: base.yaml\nparameters:\n  object.mass_kg: [0.1]\n");
  for (const char* shard : {"0/2", "3/2", "1", "a/b", "1/0"}) {
    SCOPED_TRACE(shard);
    const CliResult result = RunCli("sweep " + spec + " --shard " + shard + " --out " + dir_.Path("out"));
    EXPECT_EQ(result.exit_code, kExitBadInput);
    EXPECT_NE(result.err.find("expected K/N with 1 <= K <= N"), std::string::npos) << result.err;
  }
  const struct {
    std::string text;
    std::string message;
  } cases[] = {
      {"scenario: base.yaml\nparameters:\n  object.mass_kg: [-1]\n", "run 0: --set object.mass_kg=-1: "},
      {"scenario: base.yaml\nparameters:\n  object.mass: [0.1]\n", "object.mass: unknown key"},
      {"scenario: nope.yaml\nparameters:\n  seed: [1]\n",
       "bad.yaml:1: scenario = nope.yaml: no such scenario file"},
      {"scenario: base.yaml\nparameters:\n  seed: {min: 1, max: 2}\n",
       "bad.yaml:3: parameters.seed = {...}: a range {min, max} needs mode: random"},
      {"scenario: base.yaml\nmode: random\nparameters:\n  seed: [1]\n",
       "bad.yaml:1: samples = null: missing required key"},
      {"scenario: base.yaml\nsamples: 200\nparameters:\n  seed: [1]\n",
       "bad.yaml:2: samples = 200: draws runs in random mode only: set `mode: random` to sample, or remove it"},
      {"scenario: base.yaml\nparameters: {}\n", "bad.yaml:2: parameters"},
      {"scenario: base.yaml\nparameter:\n  seed: [1]\n", "bad.yaml"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.text);
    const std::string bad = dir_.Write("bad.yaml", c.text);
    const CliResult result = RunCli("sweep " + bad + " --out " + dir_.Path("out"));
    EXPECT_EQ(result.exit_code, kExitBadInput) << result.out;
    EXPECT_NE(result.err.find(c.message), std::string::npos) << result.err;
    EXPECT_FALSE(fs::exists(dir_.Path("out")));
  }
}

// ---- progress on a terminal
// --------------------------------------------------------------------------------

TEST_F(CliTest, ProgressLineUpdatesInPlaceOnATerminal) {
  const std::string file = dir_.Write("held.yaml", HeldBoxScenario(0.6));
  // stderr on a pseudo-terminal, stdout to a file.
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const std::string slave_name = ::ptsname(master);
  const std::string binary = CliBinary();
  const std::string out = dir_.Path("out");
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::setsid();
    const int slave = ::open(slave_name.c_str(), O_RDWR);
    const int stdout_file = ::open(dir_.Path("stdout").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(slave, STDERR_FILENO);
    ::dup2(stdout_file, STDOUT_FILENO);
    ::execl(binary.c_str(), binary.c_str(), "run", file.c_str(), "--no-plots", "--out", out.c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  std::string terminal;
  char buffer[4096];
  while (true) {
    const ssize_t count = ::read(master, buffer, sizeof(buffer));
    if (count <= 0) break;  // EIO once the child has closed the terminal
    terminal.append(buffer, static_cast<size_t>(count));
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ::close(master);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == kExitOk);
  EXPECT_NE(terminal.find("\r  held: "), std::string::npos) << terminal;
  EXPECT_NE(terminal.find(" / 0.60 s simulated"), std::string::npos) << terminal;
  // The line is cleared at the end, so the table on stdout follows a clean line.
  EXPECT_NE(terminal.rfind("\r\033[K"), std::string::npos);
  EXPECT_EQ(terminal.find('\n'), std::string::npos) << "progress must overwrite one line, not add lines";
  EXPECT_NE(ReadText(dir_.Path("stdout")).find("PASSED"), std::string::npos);
}

// ---- Ctrl-C
// ----------------------------------------------------------------------------------------------------

// A child graspbed process with stdout/stderr in files.
class Child {
 public:
  Child(const std::vector<std::string>& arguments, const std::string& capture_prefix) {
    std::vector<std::string> argv = {CliBinary()};
    argv.insert(argv.end(), arguments.begin(), arguments.end());
    std::vector<char*> pointers;
    for (std::string& a : argv) pointers.push_back(a.data());
    pointers.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, (capture_prefix + ".out").c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, (capture_prefix + ".err").c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (posix_spawn(&pid_, argv[0].c_str(), &actions, nullptr, pointers.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Child() {
    if (pid_ > 0 && !reaped_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  pid_t pid() const { return pid_; }
  void Interrupt() const { ::kill(pid_, SIGINT); }
  /// Exit code, or -1 when it did not exit normally.
  int Wait() {
    int status = 0;
    ::waitpid(pid_, &status, 0);
    reaped_ = true;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  /// True when the child is still running.
  bool Running() {
    if (reaped_) return false;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      reaped_ = true;
      return false;
    }
    return true;
  }

 private:
  pid_t pid_ = -1;
  bool reaped_ = false;
};

// Waits until `path` exists (true) or the child ends or patience runs out (false).
bool WaitForFile(const std::string& path, Child& child) {
  const auto deadline = std::chrono::steady_clock::now() + kPatience;
  while (std::chrono::steady_clock::now() < deadline) {
    if (fs::exists(path)) return true;
    if (!child.Running()) return fs::exists(path);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

// A scenario long enough (60 simulated seconds) never to end on its own during a test.
std::string LongScenario() { return HeldBoxScenario(60.0); }

// Suites start the longest expected run first, so a run finishes beside a long one only with two
// workers; with one worker the long one starts first and the short one never does.
TEST_F(CliTest, CtrlCDuringASuiteKeepsFinishedRunsAndMarksTheRestIncomplete) {
  dir_.Write("suite/a_short.yaml", HeldBoxScenario(0.2, "", "expectations: {not_dropped: true}\n"));
  dir_.Write("suite/b_long.yaml", LongScenario());
  const std::string out = dir_.Path("out");
  Child child({"suite", dir_.Path("suite"), "-j", "2", "--no-plots", "--out", out}, dir_.Path("suite_cli"));
  ASSERT_GT(child.pid(), 0);
  // a_short has finished when its summary exists; b_long is running when its INCOMPLETE marker does.
  ASSERT_TRUE(WaitForFile(out + "/a_short/summary.json", child)) << ReadText(dir_.Path("suite_cli.err"));
  ASSERT_TRUE(WaitForFile(out + "/b_long/INCOMPLETE", child)) << ReadText(dir_.Path("suite_cli.err"));
  child.Interrupt();
  EXPECT_EQ(child.Wait(), kExitInterrupted) << ReadText(dir_.Path("suite_cli.err"));

  // The finished run is intact and complete.
  const nlohmann::json a = ReadJson(out + "/a_short/summary.json");
  EXPECT_EQ(a.at("completed"), true);
  EXPECT_EQ(a.at("passed"), true);
  EXPECT_FALSE(fs::exists(out + "/a_short/INCOMPLETE"));
  const std::string csv = ReadText(out + "/a_short/signals.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 200);  // 0.2 s at 1 kHz on 1 ms steps
  // The interrupted run says so: its marker stays and its summary is not complete.
  EXPECT_TRUE(fs::exists(out + "/b_long/INCOMPLETE"));
  const nlohmann::json b = ReadJson(out + "/b_long/summary.json");
  EXPECT_EQ(b.at("completed"), false);
  EXPECT_EQ(b.at("passed"), false);
  EXPECT_LT(b.at("metrics").at("sim_s").get<double>(), 60.0);
  // The suite's JSON records both, in file order.
  const nlohmann::json suite = ReadJson(out + "/suite.json");
  EXPECT_EQ(suite.at("completed"), false);
  EXPECT_EQ(suite.at("passed"), false);
  ASSERT_EQ(suite.at("runs").size(), 2u);
  EXPECT_EQ(suite.at("runs")[0].at("completed"), true);
  EXPECT_EQ(suite.at("runs")[1].at("completed"), false);
  ExpectNoTemporaries(out);
}

TEST_F(CliTest, CtrlCDuringASuiteLeavesTheRunsNotStartedWithoutADirectory) {
  dir_.Write("suite/a_never.yaml", HeldBoxScenario(0.2));
  dir_.Write("suite/b_long.yaml", LongScenario());
  const std::string out = dir_.Path("out");
  Child child({"suite", dir_.Path("suite"), "-j", "1", "--no-plots", "--out", out}, dir_.Path("suite_cli"));
  ASSERT_GT(child.pid(), 0);
  // The longest expected run starts first; a_never waits behind it.
  ASSERT_TRUE(WaitForFile(out + "/b_long/INCOMPLETE", child)) << ReadText(dir_.Path("suite_cli.err"));
  child.Interrupt();
  EXPECT_EQ(child.Wait(), kExitInterrupted) << ReadText(dir_.Path("suite_cli.err"));
  EXPECT_TRUE(fs::exists(out + "/b_long/INCOMPLETE"));
  EXPECT_FALSE(fs::exists(out + "/a_never"));
  const nlohmann::json suite = ReadJson(out + "/suite.json");
  EXPECT_EQ(suite.at("completed"), false);
  ASSERT_EQ(suite.at("runs").size(), 2u);
  EXPECT_EQ(suite.at("runs")[0].at("error"), "not run (interrupted)");
  EXPECT_EQ(suite.at("runs")[1].at("completed"), false);
  ExpectNoTemporaries(out);
}

TEST_F(CliTest, CtrlCDuringARunLeavesItMarkedIncomplete) {
  const std::string file = dir_.Write("long.yaml", LongScenario());
  const std::string out = dir_.Path("out");
  Child child({"run", file, "--no-plots", "--out", out}, dir_.Path("run_cli"));
  ASSERT_TRUE(WaitForFile(out + "/config.yaml", child));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  child.Interrupt();
  EXPECT_EQ(child.Wait(), kExitInterrupted);
  EXPECT_NE(ReadText(dir_.Path("run_cli.err")).find("interrupted at t = "), std::string::npos);
  EXPECT_NE(ReadText(dir_.Path("run_cli.out")).find("INTERRUPTED"), std::string::npos);
  EXPECT_TRUE(fs::exists(out + "/INCOMPLETE"));
  const nlohmann::json summary = ReadJson(out + "/summary.json");
  EXPECT_EQ(summary.at("completed"), false);
  EXPECT_EQ(summary.at("passed"), false);
  ExpectNoTemporaries(out);
}

TEST_F(CliTest, CtrlCDuringASweepLeavesNoResultsThatMergeWouldTake) {
  dir_.Write("base.yaml", HeldBoxScenario(0.2));
  // Run 0 is short, run 1 is long.
  const std::string spec =
      dir_.Write("spec.yaml", "scenario: base.yaml\nparameters:\n  duration_s: [0.2, 60]\n");
  const std::string out = dir_.Path("out");
  // Two workers: the long run 1 starts first (longest expected first), run 0 beside it.
  Child child({"sweep", spec, "-j", "2", "--out", out}, dir_.Path("sweep_cli"));
  // Run 0's row reaches the .partial file when it finishes.
  const auto deadline = std::chrono::steady_clock::now() + kPatience;
  while (ReadText(out + "/results.jsonl.partial").empty() && child.Running() &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_FALSE(ReadText(out + "/results.jsonl.partial").empty());
  child.Interrupt();
  EXPECT_EQ(child.Wait(), kExitInterrupted);
  EXPECT_FALSE(fs::exists(out + "/results.jsonl"));
  EXPECT_FALSE(fs::exists(out + "/results.csv"));
  const nlohmann::json manifest = ReadJson(out + "/manifest.json");
  EXPECT_EQ(manifest.at("completed"), false);
  EXPECT_EQ(manifest.at("finished_runs"), 1);
  const nlohmann::json row = nlohmann::json::parse(ReadText(out + "/results.jsonl.partial"));
  EXPECT_EQ(row.at("run"), 0);
  EXPECT_EQ(row.at("completed"), true);
  const CliResult merge = RunCli("merge " + out + " --out " + dir_.Path("merged"));
  EXPECT_EQ(merge.exit_code, kExitBadInput);
  EXPECT_NE(merge.err.find("is incomplete"), std::string::npos) << merge.err;
  ExpectNoTemporaries(out);
}

// A binary that finds no data directory (moved away from its share/graspbed, GRASPBED_DATA_DIR unset)
// says so and exits 1: the commands' option defaults name data files, and before they were
// installed inside main's error handling this ended in std::terminate (abort, exit 134).
TEST_F(CliTest, AMissingDataDirectoryIsAMessageAndExitOneNotAnAbort) {
  const std::string moved = dir_.Path("bin/graspbed");
  fs::create_directories(dir_.Path("bin"));
  fs::copy_file(CliBinary(), moved);
  const std::string err = dir_.Path("err.txt");
  const int status =
      std::system(("env -u GRASPBED_DATA_DIR " + moved + " run x.yaml >/dev/null 2>" + err).c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const std::string message = ReadText(err);
  EXPECT_NE(message.find("graspbed: error: graspbed's data"), std::string::npos) << message;
  EXPECT_NE(message.find("set GRASPBED_DATA_DIR"), std::string::npos) << message;
}


}  // namespace
}  // namespace graspbed::testbed
