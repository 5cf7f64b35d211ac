#pragma once
/// The oracle grip: the lightest constant grip that holds a scenario, physiology's slip force
/// (Johansson and Westling 1984: people hold 10-40 % above it). Found by bisection on the
/// `constant_grip` controller over the scenario's own scene and script, run on the ideal sensor;
/// every grip figure of a run (grip_efficiency, peak_grip_ratio) is judged against it
/// (docs/scenarios.md, "The oracle grip").
///
/// "Holds" means: grasped at every close command, not dropped, no gross slip event
/// (MetricsConfig::gross_slip_m) and no
/// physics fault. The oracle grip is the mean true squeeze over the held time of the lightest
/// holding run, so a controller's mean grip compares with it in the same units whatever its sensor
/// reports; the constant_grip setpoint that gave it is kept beside it.
///
/// Results are cached per resolved oracle configuration (a hash of its config.yaml text less the
/// run's name, and of the graspbed build that searched) for the life of the process, so a suite or a
/// scorecard pays once per distinct scenario, whatever the number of controllers or threads asking.
/// They are also kept across processes as <hash>.json in the disk cache (OracleDiskCacheDir): the
/// build's file, size and modification time are part of the hash, so a rebuilt graspbed never reads
/// the searches of another build.

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "testbed/metrics.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {

/// Settings of the bisection.
struct OracleOptions {
  double relative_resolution = 0.02;  ///< stop when the bracket is narrower than this x its top [-]
  double absolute_resolution_n = 0.02;  ///< ... or narrower than this [N]
  double first_guess_n = 2.0;          ///< first setpoint tried; doubled until one holds, else halved [N]
  const std::atomic<bool>* stop = nullptr;  ///< set: the search ends early (result incomplete)
};

/// One constant_grip run of the search.
struct OracleStep {
  double setpoint_n = 0.0;      ///< constant_grip's grip_n [N]
  bool held = false;            ///< grasped at every close, not dropped, no gross slip, no physics fault
  double mean_grip_n = 0.0;     ///< mean true squeeze over the held time [N]
  double peak_grip_n = 0.0;     ///< [N]
  double max_slip_mm = 0.0;     ///< [mm]
  std::string outcome;          ///< "held", "dropped at 1.62 s", "gross slip of 0.8 mm at 1.7 s", ...
};

struct RunResult;  // testbed/runner.h

/// The oracle's hold rule on one finished constant_grip run at `setpoint_n`: held when it had no
/// physics fault, grasped at every close command, dropped nothing, had no gross slip
/// (Metrics::gross, a slip >= metrics.gross_slip_m after the grasp was established), held it on the
/// sensorised pad (the mesas carried at least metrics.min_sensed_grip_share of the finger's squeeze,
/// where the scenario checks grasped_on_sensor) and ran to its end;
/// otherwise the first of those that failed, in that order, is the outcome.
OracleStep JudgeOracleStep(double setpoint_n, const RunResult& result);

/// The result of one search.
struct OracleSearch {
  OracleGrip grip;                   ///< the oracle grip (mean squeeze of the lightest holding run)
  std::optional<double> setpoint_n;  ///< constant_grip's grip_n of that run [N]
  double stall_pinch_n = 0.0;        ///< the motor's stall pinch force, the top of the search [N]
  std::vector<OracleStep> steps;     ///< in the order run
  std::string config_hash;           ///< hex hash of the oracle configuration it was cached under
  bool completed = true;             ///< false when stopped early
};

/// Both figures `graspbed oracle` prints.
struct OracleReport {
  OracleSearch full;  ///< the scenario as written
  /// The scenario until its first disturbance action (IsDisturbance), nullopt when it has none.
  std::optional<OracleSearch> until_disturbance;
  /// Name and script index of that action; "" / -1 when none.
  std::string first_disturbance;
  int first_disturbance_index = -1;
};

/// Whether `kind` loads the held object from outside (add_mass, pull, set_friction, shake): what a
/// disturbance scenario's oracle must rise with.
bool IsDisturbance(ActionKind kind);
/// Whether `kind` acts on the sensor only (faults, noise, dropped frames, latency): left out of the
/// oracle's runs, which ask what the physics needs.
bool IsSensorAction(ActionKind kind);

/// The configuration one search step runs: `config`'s scene, seed, duration and physical script
/// (sensor actions removed), constant_grip at `setpoint_n` at the default control rate with no task
/// ceiling (nothing of the controller under test), the ideal sensor
/// with the paper's sensitivities (same layout and rate), no latency or dropped frames, no
/// expectations, the simulation backend.
ScenarioConfig OracleStepConfig(const ScenarioConfig& config, double setpoint_n);
/// `config` until its first disturbance action: that action and every later one in the script
/// removed, and a fixed-time one's at_s as the new duration. nullopt when the script has none.
std::optional<ScenarioConfig> UntilFirstDisturbance(const ScenarioConfig& config);
/// The motor's stall pinch force of `config`'s hand [N] (the prosthetic hand's digit motors or the
/// jaw's tendon motor).
double StallPinchForceN(const ScenarioConfig& config);

/// The oracle grip of `config` (cached). @throws what RunScenario throws for a config it refuses.
OracleSearch FindOracleGrip(const ScenarioConfig& config, const OracleOptions& options = {});
/// Both searches of `graspbed oracle`.
OracleReport RunOracleReport(const ScenarioConfig& config, const OracleOptions& options = {});

/// JSON of a report: oracle_grip_n, oracle_grip_until_disturbance_n (null with a reason when
/// absent), the setpoints, the first disturbance and each search's steps.
nlohmann::json OracleReportJson(const ScenarioConfig& config, const OracleReport& report);
/// The same as a short table for the terminal.
std::string OracleReportTable(const ScenarioConfig& config, const OracleReport& report);

/// The directory of the disk cache, "" when it is off: $GRASPBED_ORACLE_CACHE_DIR when set ("" or
/// "off" turn it off), else $XDG_CACHE_HOME/graspbed/oracle, else $HOME/.cache/graspbed/oracle (off
/// without HOME). SetOracleDiskCacheOff() (`--no-oracle-cache`) turns it off for the process.
std::string OracleDiskCacheDir();
/// Turns the disk cache off for the rest of the process (the in-process cache stays).
void SetOracleDiskCacheOff();

/// Searches run since the process started and how many were answered from the cache (tests).
struct OracleCacheCounters {
  uint64_t searches = 0;
  uint64_t cache_hits = 0;
};
OracleCacheCounters OracleCacheCountersNow();

}  // namespace graspbed::testbed
