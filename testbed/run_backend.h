#pragma once
/// The one run loop and what a backend gives it (docs/hardware.md, "One runner, three backends").
/// RunScenario (runner.cc) builds the backend `config.backend` names and runs the loop, written once:
/// prepare the outputs, reserve the signal rows, then per control tick: advance the backend to the
/// tick (it plays the script's actions due before it and runs the tick), log the row (the loop's
/// columns, the backend's block, the controller's diagnostics), report progress; at the end the
/// backend scores the run and the loop writes signals.csv, the backend's own files and plots, and
/// summary.json. What differs between backends is behind RunBackend:
///   sim     physics steps between ticks; ground truth (metrics, truth columns, states.csv)
///   serial  real-time frames on the wire, live intent, prompts for actions only the simulator can do
///   replay  the recorded frames, with the recorded commands compared to the new ones
/// Internal to graspbed_testbed_run.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/config_error.h"
#include "common/signal_log.h"
#include "controller/control_loop.h"
#include "controller/grasp_controller.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed::internal {

/// One backend of a run. Built (and refusing bad input) before any output is written; then driven by
/// the loop from one thread. NextTick() and Record() run once per control tick: no allocation, no I/O
/// there (the serial backend's prompts for a person at the bench excepted).
class RunBackend {
 public:
  virtual ~RunBackend() = default;

  /// The numeric columns of the backend's block in signals.csv: after the loop's columns
  /// (internal::LoopColumn), before the controller's diagnostic ones.
  virtual std::vector<std::string> Columns() const = 0;
  /// Text columns after intent, phase and slip_cues (none by default).
  virtual std::vector<std::string> TextColumns() const { return {}; }
  /// Signal rows to reserve (0: keep none, e.g. `graspbed hw` without an output directory).
  virtual size_t RowCapacity() const = 0;
  /// How long the run lasts [s] (progress callbacks report against it; may be infinite).
  virtual double duration_s() const = 0;

  /// The controller under test and the loop that ticks it.
  virtual controller::GraspController& controller() = 0;
  virtual const controller::ControlLoop& loop() const = 0;
  /// The intent the last tick ran with.
  virtual controller::GraspIntent intent() const = 0;
  /// The controller's telemetry after the last tick, read once by NextTick().
  virtual const controller::ControllerTelemetry& telemetry() const = 0;

  /// Called once, after the outputs are prepared and before the first tick.
  virtual void Start() {}
  /// Advances to the next control tick and runs it: the script's actions due before it, then the
  /// tick, then what the backend keeps per tick whether or not a row is logged (metrics, counters).
  /// Returns the tick's time [s], or nothing when the run has ended (its duration, the recording's
  /// end, a quit, a physics fault, or `stop` seen between physics steps).
  virtual std::optional<double> NextTick() = 0;
  /// Fills the backend's block of the tick's row: `cells` (Columns().size()) and `texts`
  /// (TextColumns().size()).
  virtual void Record(double time_s, double* cells, const char** texts) = 0;
  /// After the tick's row is logged: observers (stills, video frames, the state log). Returns true
  /// when the run should end here (RunOptions::stop_after_instants).
  virtual bool AfterTick(double /*time_s*/) { return false; }

  /// Scores the run once the loop has ended (`completed`: not stopped early; `wall_s`: the loop's
  /// wall-clock time [s]): fills result's metrics (sim_s and wall_s at least), outcomes, script
  /// timings, counters and bench record. Shuts a link down.
  virtual void Finish(bool completed, double wall_s, RunResult& result) = 0;
  /// False when the run fails for a reason beside its expectations (the hand disconnected, the frame
  /// log could not be written).
  virtual bool Healthy() const { return true; }
  /// Writes the backend's files beside signals.csv and summary.json (states.csv) and, when `plots`,
  /// its PNG plots, into `dir`.
  virtual void WriteOutputs(const RunResult& result, const common::SignalLog& log, bool plots,
                            const std::string& dir) = 0;
};

/// The simulation of `config` (sim_run.cc). Computes the oracle grip first when `options` ask for it.
/// Throws common::ConfigError naming the scenario file for a scene or controller the rig refuses.
std::unique_ptr<RunBackend> MakeSimRun(const ScenarioConfig& config, const RunOptions& options);
/// The hand over the serial link `config.serial` names (bench_run.cc): the link is opened and the
/// handshake done here. Throws std::invalid_argument for a port that cannot be used, common::ConfigError
/// for a script the bench cannot play.
std::unique_ptr<RunBackend> MakeSerialRun(const ScenarioConfig& config, const RunOptions& options);
/// The recording `config.log` names, replayed tick by tick (bench_run.cc). Throws
/// std::invalid_argument naming the file when it cannot be read.
std::unique_ptr<RunBackend> MakeReplayRun(const ScenarioConfig& config, const RunOptions& options);

/// `error`, something the run refused in `config`, as a ConfigError that names the scenario file.
common::ConfigError RefusedIn(const ScenarioConfig& config, const std::exception& error);

/// The controller `config.controller` names, or options.make_controller's. An invalid_argument
/// becomes a common::ConfigError naming the scenario file.
std::unique_ptr<controller::GraspController> MakeRunController(const ScenarioConfig& config,
                                                               const RunOptions& options);

}  // namespace graspbed::testbed::internal
