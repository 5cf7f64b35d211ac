#pragma once
/// Suites: every scenario file of a directory, run in parallel on a pool of worker threads (each run
/// owns its own MuJoCo model and data), with a pass/fail table and one combined JSON. Every file is
/// loaded and validated before the first run starts, so bad input is refused as a whole.

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "testbed/runner.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {

/// The *.yaml files directly in `dir`, sorted by name. Throws common::ConfigError when `dir` is not a
/// directory or holds no scenario.
std::vector<std::string> ListScenarioFiles(const std::string& dir);

/// Loads every file with the same overrides; throws the first file's error. Scenario names must be
/// unique (they name the output directories).
std::vector<ScenarioConfig> LoadScenarios(const std::vector<std::string>& files,
                                          const std::vector<Override>& overrides = {});

/// One finished (or failed to run) scenario of a suite.
struct SuiteRun {
  RunResult result;
  std::string error;  ///< non-empty when the run threw (reported as failed)
  bool started = false;
};

/// Settings of a suite run.
struct SuiteOptions {
  int jobs = 1;         ///< worker threads (>= 1)
  std::string out_dir;  ///< per scenario: out_dir/<name>/; "" writes nothing
  bool write_plots = true;
  const std::atomic<bool>* stop = nullptr;  ///< stops the runs in flight and starts no new ones
  /// Called (under a lock) after each run with (runs finished, total, that run).
  std::function<void(int, int, const SuiteRun&)> on_finished;
  ControllerFactory make_controller;  ///< RunOptions::make_controller for every run; may be empty
  /// Adds observers to each run's options (e.g. `--video`); empty: none.
  PrepareRun prepare_run;
  /// Every simulated run is scored against its scenario's oracle grip (cached per scenario).
  OracleMode oracle = OracleMode::kAlways;
};

/// Results in the order of `configs`.
struct SuiteResult {
  std::vector<SuiteRun> runs;
  bool completed = false;  ///< every run ran to its end
  int passed = 0;
  int failed = 0;  ///< failed expectations, errors and interrupted runs
  double wall_s = 0.0;
  int jobs = 1;
};

/// Runs `configs` on `options.jobs` threads. Writes out_dir/suite.json (atomically) when out_dir is set.
SuiteResult RunSuite(const std::vector<ScenarioConfig>& configs, const SuiteOptions& options);

/// Combined JSON: suite totals and every run's summary.
nlohmann::json SuiteJson(const SuiteResult& result);

/// Pass/fail table, one line per scenario with its failed expectations.
std::string SuiteTable(const SuiteResult& result);

}  // namespace graspbed::testbed
