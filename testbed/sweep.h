#pragma once
/// Sweeps: a grid or a seeded random sample over scenario parameters (any dotted key --set accepts:
/// object.mass_kg x object.friction x controller.name ...), one result row per run, shardable over
/// machines (--shard K/N: a Slurm job array, GNU parallel) and merged afterwards. Spec format:
/// docs/scenarios.md ("Sweeps").
///
/// Output directory of a sweep (or one shard of it):
///   results.jsonl  one JSON object per run, by run index
///   results.csv    the same rows as CSV
///   manifest.json  spec fingerprint, total runs, shard K/N, the run indices it holds, completed
/// Rows are appended to results.jsonl.partial as runs finish; the final files appear (by rename)
/// only when every run of the shard has finished, so an interrupted shard never looks complete.

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "testbed/runner.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {

/// One swept key: either a list of values (grid axis, or random choice) or a range (random only).
struct SweepParameter {
  std::string key;                  ///< dotted key, as for --set
  std::vector<std::string> values;  ///< YAML value texts; empty for a range
  double min = 0.0;                 ///< range [min, max] (random mode)
  double max = 0.0;
  bool log_scale = false;  ///< sample the range log-uniformly (min > 0)
  bool integer = false;    ///< round the sample to a whole number
};

/// A parsed sweep spec.
struct SweepSpec {
  std::string source_file;
  std::string scenario_path;    ///< base scenario, resolved relative to the spec file
  bool random = false;          ///< mode: grid (false) or random
  int samples = 0;              ///< random mode: number of runs
  uint64_t seed = 1;            ///< random mode: sampling seed
  std::vector<Override> fixed;  ///< `set:` overrides applied to every run first
  std::vector<SweepParameter> parameters;
  std::string fingerprint;  ///< hash of the spec and base scenario texts (merge checks it)
};

/// Loads and validates a spec; errors are common::ConfigError "file:line: key = value: reason".
SweepSpec LoadSweepSpec(const std::string& path);

/// One run of a sweep: its index and the overrides that make it.
struct SweepRun {
  int index = 0;
  std::vector<Override> overrides;  ///< fixed ones first, then one per parameter
};

/// Every run of the sweep in index order (grid: last parameter fastest; random: sample i drawn from
/// its own stream seeded by (seed, i), so the runs do not depend on sharding).
std::vector<SweepRun> ExpandSweep(const SweepSpec& spec);

/// --shard K/N: shard K (1-based) of N takes the runs with index % N == K - 1.
struct Shard {
  int index = 1;
  int count = 1;
};
/// Parses "K/N" (1 <= K <= N); throws std::invalid_argument otherwise.
Shard ParseShard(const std::string& text);
std::vector<SweepRun> ShardRuns(const std::vector<SweepRun>& runs, const Shard& shard);

/// Settings of a sweep run.
struct SweepOptions {
  Shard shard;
  int jobs = 1;
  std::string out_dir = "out/sweep";
  const std::atomic<bool>* stop = nullptr;
  /// Called (under a lock) after each run with (runs finished, runs in this shard).
  std::function<void(int, int)> on_finished;
  ControllerFactory make_controller;  ///< RunOptions::make_controller for every run; may be empty
  /// Adds observers to each run's options (e.g. `--video`); empty: none.
  PrepareRun prepare_run;
};

/// What a sweep (shard) did.
struct SweepOutcome {
  int runs = 0;  ///< runs in this shard
  int finished = 0;
  int passed = 0;
  bool completed = false;
  double wall_s = 0.0;
};

/// Validates every run of the shard (loads its scenario with its overrides), then runs them and
/// writes the output directory. Throws common::ConfigError for a run whose overrides are invalid
/// (before anything runs).
SweepOutcome RunSweep(const SweepSpec& spec, const SweepOptions& options);

/// The result row of one run (flat: run, scenario, each parameter, passed, completed, the metrics).
nlohmann::json SweepRow(const SweepSpec& spec, const SweepRun& run, const RunResult& result);

/// Combines the output directories of shards into `out_dir`. Refuses (std::invalid_argument naming
/// the directories) shards of different sweeps, a shard given twice, a missing shard, an incomplete
/// shard, and rows that overlap or leave gaps. Returns the number of rows written.
int MergeSweeps(const std::vector<std::string>& shard_dirs, const std::string& out_dir);

}  // namespace graspbed::testbed
