#pragma once
/// Controller scorecards: one or more controllers run over a versioned benchmark set (base scenarios
/// plus seeded variations of them), their metrics pooled into one score per controller that a user
/// quotes when comparing a controller with the reference. Set format and figures: docs/controller.md
/// ("Scorecard").
///
/// Output directory of `graspbed score`:
///   scorecard.csv   one row per controller (the columns of ScorecardCsv)
///   scorecard.json  the set (name, version, runs), one object per controller, and every run's row
///   scorecard.png   bars of the headline figures, one colour per controller

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/plot.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {

/// One varied quantity of a set: a range of one key (uniform sample), or a choice among groups of
/// overrides applied together (e.g. object.shape with a matching object.size_m).
struct ScorecardVary {
  std::string key;   ///< range: dotted key as for --set; "" for a choice
  double min = 0.0;  ///< range [min, max]
  double max = 0.0;
  std::vector<std::vector<Override>> choices;  ///< choice: one group drawn with equal probability
};

/// One base scenario of a set and how many seeded variations of it run beside it.
struct ScorecardBase {
  std::string scenario_path;        ///< resolved relative to the set file
  /// Its runs' names' stem (`name:`; default the scenario file's stem); unique within a set, so one
  /// scenario file can be a base several times with different `set` overrides.
  std::string name;
  /// Overrides of every run of this base, v0 included, applied before the variations' (`set:`, a map of
  /// keys as for --set to values, e.g. {object: {name: apple}}).
  std::vector<Override> set;
  int variations = 0;               ///< seeded variations besides the base as shipped (>= 0)
  std::vector<ScorecardVary> vary;  ///< applied after the set's common ones
};

/// A parsed set.yaml.
struct ScorecardSet {
  std::string source_file;
  std::string name;
  int version = 0;
  uint64_t seed = 1;                  ///< sampling seed of the variations
  std::vector<ScorecardVary> common;  ///< varied in every variation of every base
  std::vector<ScorecardBase> bases;
};

/// Loads and validates a set file; errors are common::ConfigError "file:line: key = value: reason".
/// @throws common::ConfigError
ScorecardSet LoadScorecardSet(const std::string& path);

/// One run of a set (per controller).
struct ScorecardRun {
  std::string name;  ///< <base name>.v<k>; v0 is the base with its `set` overrides only
  std::string scenario_path;
  std::vector<Override> overrides;  ///< the base's `set`, then the sampled overrides (none for v0)
};

/// Every run of the set: per base, v0 then variations 1..N; variation k of base b is drawn from its
/// own stream seeded by (seed, b, k), so adding a base or a variation leaves the others unchanged.
std::vector<ScorecardRun> ExpandScorecardSet(const ScorecardSet& set);

/// The pooled figures of one controller over the runs of a set.
struct ControllerScore {
  std::string controller;
  int runs = 0;           ///< runs that ran to their end (errors and interrupted runs excluded)
  int errors = 0;         ///< runs that threw or were interrupted
  int passed = 0;         ///< runs that met every expectation of their scenario
  /// Gross slip events (SlipEvent::gross: >= metrics.gross_slip_m or a drop), all runs: what a hand
  /// must catch, the headline.
  int gross_slip_events = 0;
  int gross_slip_detected = 0;                 ///< of those, flagged by the controller
  std::optional<double> gross_detected_pct;    ///< 100 * detected / events; nullopt with none [%]
  std::optional<double> gross_latency_p50_ms;  ///< over the detected gross events [ms]
  std::optional<double> gross_latency_p95_ms;
  int micro_slip_events = 0;  ///< micro-slip events (the rest), reported, not targeted
  int micro_slip_detected = 0;
  std::optional<double> micro_detected_pct;  ///< [%]
  int slip_events = 0;    ///< ground-truth slip events while held, all runs (gross and micro)
  int slip_detected = 0;  ///< of those, flagged by the controller
  /// Of the events not flagged, those during which no unit was loaded (SlipEvent::sensed false).
  int missed_unsensed = 0;
  /// Of the events not flagged, those where only the thumb slid (Metrics::missed_thumb_only_slip_events).
  int missed_thumb_only = 0;
  std::optional<double> detected_pct;    ///< 100 * detected / events; nullopt with no event [%]
  std::optional<double> latency_p50_ms;  ///< over detected events [ms]
  std::optional<double> latency_p95_ms;
  int false_flags = 0;
  /// false_flags by the controller's slip_cues label (Metrics::false_slip_flags_by_cue, pooled).
  std::map<std::string, int> false_flags_by_cue;
  double held_min = 0.0;                    ///< time held, all runs [min]
  std::optional<double> false_per_min;      ///< false_flags / held_min [1/min]
  /// Lifts: the runs that held their object (Metrics::held_s > 0), one lift each [-]. Every shipped
  /// scenario lifts its object once; a regrasp's first pinch or a put-down and pick-up within a run
  /// is not a lift of its own (Metrics records the time held, not each grasp). False flags are only
  /// counted while held, so a run that never held has neither a lift nor a false flag.
  int lifts = 0;
  std::optional<double> false_per_lift;     ///< false_flags / lifts; nullopt with no lift [1/lift]
  int incipient_flags = 0;                  ///< flags near a contact sliding below the event speed
  std::optional<double> incipient_per_min;  ///< incipient_flags / held_min [1/min]
  double false_flag_min = 0.0;              ///< time the flag was up outside slip events, all runs [min]
  std::optional<double> false_flag_pct;     ///< false_flag_min / held_min [%]
  int drops = 0;
  int crushes = 0;
  /// Mean grip held / oracle grip (Metrics::grip_efficiency) over the runs with both [-].
  std::optional<double> grip_efficiency_median;
  std::optional<double> grip_efficiency_p95;
  /// Peak grip / oracle grip (Metrics::peak_grip_ratio) over the runs with an oracle grip [-].
  std::optional<double> peak_grip_ratio_median;
  std::optional<double> peak_grip_ratio_p95;
  int no_oracle = 0;  ///< runs whose oracle grip was not found (not holdable at the stall pinch)
  /// Runs that failed grasped_on_sensor: held off the sensorised pad, so their verdicts are about
  /// the grasp, not the controller.
  int off_sensor = 0;
  /// sensed_grip_share over the runs that held the object: median and lowest [-].
  std::optional<double> sensed_share_median;
  std::optional<double> sensed_share_min;
  std::optional<double> fn_rmse_n;  ///< sample-weighted RMS of the runs' Fn RMSEs [N]
  int physics_faults = 0;
};

/// Percentile `p` (0..100) of `values` by linear interpolation between order statistics (numpy's
/// default); nullopt for an empty list.
std::optional<double> Percentile(std::vector<double> values, double p);

/// Pools finished runs of one controller into its score. `errors` counts runs that did not finish.
ControllerScore ScoreRuns(const std::string& controller, const std::vector<const RunResult*>& finished,
                          int errors);

/// Settings of a scorecard run.
struct ScorecardOptions {
  std::vector<std::string> controllers = {"grip_slip", "open_loop"};
  int jobs = 1;
  int limit = 0;  ///< > 0: only the first `limit` runs of the set (smoke tests)
  /// Non-empty: every run's outputs (signals.csv, summary.json, config.yaml; no plots) go to
  /// runs_dir/<run>@<controller>/, for reading a scorecard's figures back to their runs.
  std::string runs_dir;
  /// Applied to every run after the set's own (`--set`): the same set under another option, e.g. a
  /// sensor profile or a physics setting. Figures so taken are not the set's; quote them with these.
  std::vector<Override> overrides;
  const std::atomic<bool>* stop = nullptr;
  /// Called (under a lock) after each run with (runs finished, total).
  std::function<void(int, int)> on_finished;
  /// Controllers built by the caller (e.g. written in Python), by their label in `controllers`: such
  /// a run keeps its scenario's controller section (rate, stale timeout, ceiling) and the factory
  /// builds the controller (RunOptions::make_controller).
  std::map<std::string, ControllerFactory> custom_controllers;
};

/// One row per (controller, run), for the JSON.
struct ScorecardRow {
  std::string controller;
  std::string run;
  std::vector<Override> overrides;  ///< the run's sampled overrides (controller.name not included)
  std::string error;
  RunResult result;
};

/// A finished scorecard.
struct Scorecard {
  std::string set_name;
  int set_version = 0;
  uint64_t set_seed = 0;  ///< the variations' sampling seed the runs were drawn with
  std::string set_file;
  int runs_per_controller = 0;
  std::vector<ControllerScore> scores;  ///< in the order of ScorecardOptions::controllers
  std::vector<ScorecardRow> rows;
  bool completed = false;
  double wall_s = 0.0;
  int jobs = 1;
};

/// Loads every run of the set for every controller (refusing bad input before anything runs), runs
/// them longest-first on `options.jobs` threads and scores them.
/// @throws common::ConfigError for a run whose scenario or overrides are invalid, or an unknown controller
Scorecard RunScorecard(const ScorecardSet& set, const ScorecardOptions& options);

/// The same figures per sensor (profile and sensitivity source of each run's resolved config): one
/// line per (sensor, controller) with runs, slip events detected, latency p95, false flags per
/// minute held and per lift, flag-up share, drops and median grip efficiency: the reference's
/// targets hold per profile.
std::string ScorecardBySensorTable(const Scorecard& scorecard);

/// The same figures per base scenario of the set (a run `pull_ramp.v3` counts for `pull_ramp`), to
/// see where a controller loses its events or raises its false flags.
std::string ScorecardByScenarioTable(const Scorecard& scorecard);

/// Side-by-side table: one column per controller, one line per figure.
std::string ScorecardTable(const Scorecard& scorecard);
/// Which runs failed and why, for under the table: a line per (run, controller) that finished and
/// did not pass, in the scorecard's row order, with its first failed expectation as its result
/// records it (RunResult::outcomes: name, measured value, limit and note), and a line per run that
/// threw (its error); runs that passed are not listed, runs that did not finish (interrupted) are
/// counted in one line. "  failed runs: none" when every finished run passed.
std::string ScorecardFailedRuns(const Scorecard& scorecard);
/// CSV: a header and one row per controller ("" for a figure that does not exist).
std::string ScorecardCsv(const Scorecard& scorecard);
/// JSON: set, controllers (one object each, with the same figures per sensor under "by_sensor") and
/// runs.
nlohmann::json ScorecardJson(const Scorecard& scorecard);
/// Bars of the headline figures (gross slips detected, latency p95, false flags per minute held and
/// per lift, grip efficiency median, drops + crushes, runs passed), one panel each: a filled bar per
/// controller, named under the axis, in the same colour in every panel, its value written above it; a
/// figure a controller does not have (e.g. no gross slip event) is no bar but a note saying why.
plot::Figure ScorecardFigure(const Scorecard& scorecard);
/// Writes ScorecardFigure(scorecard) as a PNG at `path`.
void WriteScorecardPlot(const Scorecard& scorecard, const std::string& path);
/// Writes scorecard.csv, scorecard.json and scorecard.png into `out_dir` (created; atomic writes).
void WriteScorecard(const Scorecard& scorecard, const std::string& out_dir);

}  // namespace graspbed::testbed
