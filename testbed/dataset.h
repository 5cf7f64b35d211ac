#pragma once
/// Datasets of labelled control ticks for learning slip detection (`graspbed dataset`,
/// docs/training-slip-detector.md). Runs the runs of one or more sweep specs (docs/scenarios.md,
/// "Sweeps"; any controller) once per sensor profile, and writes per control tick what the
/// controller saw (its TactileState with the profile's noise, the features of
/// controller/slip_features.h computed from it, the command it gave) beside labels from the
/// simulation's ground truth: contact state, slip speed and distance, and whether a gross slip is
/// under way within the next h ms.
///
/// Output directory (or one shard's):
///   ticks.npz      uncompressed NumPy archive, one array per column (DatasetArrayNames below)
///   manifest.json  format, version, graspbed version, specs and seeds, profiles, layout, features,
///                  every run (overrides, split, tick range, gross slips), class counts per split
/// ticks.npz appears by rename only when every run of the shard has finished; the manifest last,
/// with "completed": true. An interrupted shard leaves a manifest with "completed": false and no
/// ticks.npz.
///
/// Splits are by run group (one sweep run: its scenario, seed and drawn parameters, under every
/// profile), never by tick: neighbouring ticks are near copies, and the same physics seen through
/// another profile would leak the test set into training.

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "testbed/sweep.h"

namespace graspbed::testbed {

/// Name and version of the dataset format (manifest "format", "version").
inline constexpr const char* kDatasetFormat = "graspbed-slip-dataset";
inline constexpr int kDatasetVersion = 1;

/// The controller's inputs a dataset records per tick, declared once: each is an array of ticks.npz
/// (per unit: ticks x units). The hand's proprioception (HandState: joint positions, motor
/// currents) joins here once GraspController::Update receives it.
struct DatasetInput {
  const char* array;  ///< array name in ticks.npz
  const char* doc;    ///< meaning, with its unit
  bool per_unit;      ///< one value per sensing unit
};
inline constexpr DatasetInput kDatasetInputs[] = {
    {"fn_n", "estimated normal force per unit, as the controller saw it (float32) [N]", true},
    {"ft_n", "estimated shear per unit along its beam (float32) [N]", true},
    {"validity", "sensor::UnitValidity per unit (0 valid, 1 open, 2 short, 3 out of range, 4 implausible, "
                 "5 not tared) (uint8)", true},
    {"stale", "1 when the state was stale (uint8)", false},
    {"total_fn_n", "sum of Fn over valid units (float32) [N]", false},
    {"shear_axial_n", "summed shear of the axial units (float32) [N]", false},
    {"shear_circumferential_n", "summed shear of the circumferential units (float32) [N]", false},
    {"grip_effort", "the controller's command: grip motor effort (float32) [-]", false},
    {"hand", "the hand state the controller saw (proprioception), one column per signals.csv hand column, "
             "manifest key hand_columns, NaN unknown (float32) [rad, m, A as signals.csv]", false},
};

/// Settings of a dataset build.
struct DatasetOptions {
  /// Sensors every sweep run is run under: `PROFILE` (sensor.profile) or `PROFILE/SENSITIVITIES`
  /// (also sensor.sensitivities), as the scorecard names sensors; empty: every realistic profile
  /// (divider_12bit, inamp_16bit, bridge_24bit) with either sensitivity source (paper, fea).
  std::vector<std::string> profiles;
  /// Horizons of the "gross slip within h" labels [ms].
  std::vector<int> horizons_ms = {10, 20, 50, 100};
  double validation_fraction = 0.15;  ///< share of run groups in the validation split
  double test_fraction = 0.15;        ///< share of run groups in the test split
  uint64_t split_seed = 1;            ///< seeds the groups' order before the split
  Shard shard;                        ///< runs whose dataset index % count == index - 1
  int jobs = 1;
  std::string out_dir = "out/dataset";
  const std::atomic<bool>* stop = nullptr;
  /// Called (under a lock) after each run with (runs finished, runs in this shard).
  std::function<void(int, int)> on_finished;
};

/// One run of a dataset: a sweep run under one profile.
struct DatasetRun {
  int index = 0;      ///< dataset run index (the order of specs, their runs, then profiles)
  int spec = 0;       ///< which spec
  int sweep_run = 0;  ///< its index in that spec's sweep
  std::string profile;
  std::vector<Override> overrides;  ///< the sweep run's, then sensor.profile (and .sensitivities)
  int group = 0;                    ///< run group: (spec, sweep run), shared by its profiles
  int split = 0;                    ///< 0 train, 1 validation, 2 test
};

/// Names of the splits, by DatasetRun::split.
inline constexpr const char* kSplitNames[] = {"train", "validation", "test"};

/// Every run of the dataset with its split. Groups are ordered by a hash of (spec fingerprint, sweep
/// run, split_seed); the first test_fraction of them (at least one when there are 3 or more groups)
/// go to test, the next validation_fraction to validation, the rest to training. Independent of
/// sharding. @throws std::invalid_argument for fractions outside [0, 1) or summing to 1 or more
std::vector<DatasetRun> ExpandDataset(const std::vector<SweepSpec>& specs, const DatasetOptions& options);

/// What a dataset build did.
struct DatasetOutcome {
  int runs = 0;  ///< runs in this shard
  int finished = 0;
  int errors = 0;  ///< runs that threw (listed in the manifest, no ticks)
  int64_t ticks = 0;
  bool completed = false;
  double wall_s = 0.0;
};

/// Loads and validates every run of the shard (refusing bad input before anything runs, and runs on
/// different layouts or control rates), runs them on `jobs` threads and writes the output directory.
/// @throws common::ConfigError for a run whose overrides are invalid
DatasetOutcome BuildDataset(const std::vector<SweepSpec>& specs, const DatasetOptions& options);

/// Per-tick labels of one run from its ground truth (exposed for tests).
struct TickLabels {
  std::vector<uint8_t> contact_state;  ///< 0 none, 1 stick, 2 partial slip, 3 gross slip
  /// Per horizon (DatasetOptions::horizons_ms): 1 when a tick of gross slip lies in [t, t + h].
  std::vector<std::vector<uint8_t>> gross_within;
  /// Per horizon: 1 when a gross slip event begins in [t, t + h].
  std::vector<std::vector<uint8_t>> onset_within;
};

/// Contact state names, by TickLabels::contact_state.
inline constexpr const char* kContactStateNames[] = {"none", "stick", "partial_slip", "gross_slip"};

/// Labels for ticks at `time_s` from the run's truth columns: the finger's true normal force
/// [N], the speed of the contacts sliding at the friction limit [mm/s], the open slip event (0/1),
/// and the run's slip events (a gross one labels its ticks from onset to end gross slip). In contact:
/// finger force above `contact_n`; partial slip: an open (micro) event or sliding above
/// `creep_mm_s`.
TickLabels LabelTicks(const std::vector<double>& time_s, const std::vector<double>& finger_fn_n,
                      const std::vector<double>& sliding_mm_s, const std::vector<double>& slip_event,
                      const std::vector<SlipEvent>& events, const std::vector<int>& horizons_ms,
                      double contact_n, double creep_mm_s);

}  // namespace graspbed::testbed
