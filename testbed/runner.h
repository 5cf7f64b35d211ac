#pragma once
/// Running one scenario on its backend (`backend: sim | serial | replay`): one run loop, the backends
/// behind testbed/run_backend.h (sim_run.cc; serial and replay in bench_run.cc, docs/hardware.md).
/// On the simulation: builds the rig (simulation, simulated sensor, control loop, controller,
/// actuator), plays the script, scores the run and writes its outputs:
///   DIR/config.yaml   the fully resolved configuration (loads again to reproduce the run)
///   DIR/signals.csv   one row per control tick (docs/scenarios.md, "Outputs")
///   DIR/summary.json  metrics, every expectation with its outcome, and `passed`
///   DIR/states.csv    the simulation state (qpos, qvel, ctrl) every 5 ms, for replays (docs/scenarios.md)
///   DIR/*.png         forces, estimate vs truth, grip, slip, height
/// Every file is written to a temporary name and renamed; while a run is in progress, or after it
/// was interrupted, DIR/INCOMPLETE exists and summary.json (if any) says "completed": false.

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sensor/calibration.h"

#include "common/signal_log.h"
#include "testbed/metrics.h"
#include "testbed/scenario_config.h"
#include "testbed/script_player.h"

namespace graspbed::sim {
class SimRig;
struct SimRigConfig;
}  // namespace graspbed::sim

namespace graspbed::testbed {

/// When a run computes its scenario's oracle grip (testbed/oracle.h) to score its grip against.
enum class OracleMode {
  kIfExpected,  ///< only when the scenario states max_grip_efficiency (`graspbed run` by default)
  kAlways,      ///< every simulated run (`run --oracle`, suites, the scorecard; cached per scenario)
  kNever,       ///< never (the oracle's own runs)
};

/// Builds a run's controller from its resolved controller section (RunOptions::make_controller).
using ControllerFactory =
    std::function<std::unique_ptr<controller::GraspController>(const ControllerOptions&)>;
struct RunResult;

/// What a per-frame observer (RunOptions::on_frame) sees: the rig at a control tick, after that
/// tick's row is logged, and the script played so far. Observers only read.
struct FrameContext {
  double time_s = 0.0;        ///< simulated time of the control tick [s]
  double frame_time_s = 0.0;  ///< the frame's nominal time, index * frame_period_s [s]
  sim::SimRig& rig;
  const ScriptPlayer& player;
};

/// How to run and what to write.
struct RunOptions {
  std::string out_dir;      ///< "" = write nothing (suites and sweeps that only need the summary)
  bool write_plots = true;  ///< PNGs in out_dir
  /// Set (e.g. by SIGINT) to stop the run at the next control tick; the run then ends with
  /// completed = false. May be nullptr.
  const std::atomic<bool>* stop = nullptr;
  /// Called about every 0.1 s of simulated time with (simulated time, duration) [s]; may be empty.
  std::function<void(double, double)> progress;
  /// Called before every physics step with the rig, after the script's update for that instant;
  /// tests inject faults through it (e.g. a NaN into the state). May be empty.
  std::function<void(sim::SimRig&)> before_step;
  /// Instants [s], ascending, at which `at_instant` is called with (instant, rig): at the first
  /// control tick at or after each instant, after that tick's row is logged, so the rig shows the
  /// state, estimate and command of that tick. Used to render stills; the callback may allocate
  /// and do I/O (it runs inside the simulated-time loop, so keep it rare).
  std::vector<double> instants_s;
  std::function<void(double instant_s, sim::SimRig& rig)> at_instant;
  /// End the run once every instant was served (the run then counts as stopped: completed = false).
  bool stop_after_instants = false;
  /// Builds the run's controller instead of controller::MakeController(config.controller.name,
  /// config.controller.params), e.g. a controller written in Python; config.controller.name is then
  /// only its label in the outputs. Called once per run, before the rig is built; may be
  /// called from several threads at once in a suite. May be empty.
  ControllerFactory make_controller;
  /// Called once at the end of the run with the whole per-tick signal log (the rows of signals.csv),
  /// before the outputs are written; e.g. to hand the signals to Python without a file. May be empty.
  std::function<void(const common::SignalLog&)> on_signals;
  /// Per-frame observer (videos): called at the first control tick at or after each multiple of
  /// frame_period_s [s] (0, period, 2 period, ... up to duration_s), one call per frame. It may
  /// allocate and do I/O; it must not change the rig, so a run gives the same results with or without
  /// it. Empty (the default): nothing is done per step.
  double frame_period_s = 0.0;
  std::function<void(const FrameContext&)> on_frame;
  /// Called once after the loop with the result, before summary.json is written and the INCOMPLETE
  /// marker removed (a video is finished there). An exception from it propagates.
  std::function<void(const RunResult&)> on_finished;
  /// backend serial: record the loop latency (a frame's decode to its command's write) of up to this
  /// many frames, reported in summary.json's "bench" as "latency" (docs/hardware.md, "Loop latency");
  /// 0: off. Allocated before the session (8 bytes a frame).
  size_t latency_frames = 0;
  /// Whether the run computes the oracle grip (simulation only; more simulated runs, cached).
  OracleMode oracle = OracleMode::kIfExpected;
  /// backend serial: script actions that need the simulator (lift, pull, add_mass, ...) are printed
  /// on stderr at their times as prompts for a person at the bench, instead of refusing the scenario.
  bool prompt_actions = false;
  /// backend serial: live intent from standard input (keys c/o/i/q on a terminal, lines
  /// close/open/idle/quit otherwise).
  bool intent_stdin = false;
  /// backend serial: live intent lines from this FIFO, e.g. an EMG classifier's ("" none; created
  /// when missing).
  std::string intent_fifo;
  /// backend serial and replay: the host's calibration (e.g. `graspbed hw --calibration`); unset:
  /// the sensor's nominal constants, as in simulation.
  std::optional<sensor::Calibration> calibration;
};

/// Lets a suite or sweep add observers (e.g. a video) to the options of each run it starts: called on
/// the worker thread that then runs `config`, with a name for the run's files ("<scenario>" in
/// suites, "run_<index>" in sweeps).
using PrepareRun =
    std::function<void(const ScenarioConfig& config, const std::string& run_name, RunOptions& run)>;

/// The result of one run.
struct RunResult {
  ScenarioConfig config;
  Metrics metrics;
  std::vector<ExpectationOutcome> outcomes;  ///< expectations, then one per event action of the script
  std::vector<ActionTiming> script_timings;  ///< per script action (config.script order)
  /// Ran to its end: duration_s, or a physics fault, which ends a run at once (metrics say which);
  /// false: stopped early by `RunOptions::stop`.
  bool completed = false;
  bool passed = false;            ///< completed and every expectation held
  double real_time_factor = 0.0;  ///< simulated seconds per wall-clock second
  uint64_t frames = 0;            ///< sensor frames delivered
  uint64_t dropped_frames = 0;    ///< frames lost on the simulated link
  uint64_t stale_ticks = 0;       ///< control ticks on stale data
  uint64_t control_ticks = 0;
  size_t signal_rows_lost = 0;  ///< rows beyond the reserved signal storage (should be 0)
  std::string out_dir;          ///< where the outputs went ("" none)
  /// backend serial or replay: link counters, intent events, prompts, controller phases, the
  /// replayed commands' comparison (summary.json "bench", docs/hardware.md); null for sim.
  nlohmann::json bench;
};

/// Runs `config` on config.backend. Throws std::invalid_argument (common::ConfigError naming the scenario
/// file) for a configuration the rig refuses, e.g. a scene whose bodies start inside each other, before any
/// output is written; std::runtime_error when outputs cannot be written. A physics fault (NaN, a
/// MuJoCo warning) is a result, not an exception: it ends the run at once, the outputs so far are
/// written, and the run fails (metrics.physics_fault with its cause and time).
RunResult RunScenario(const ScenarioConfig& config, const RunOptions& options = {});

/// The simulated rig `config` describes: scene, simulated sensor (rate, latency up to the script's
/// add_latency actions, frame drops, strain model), the loop's readout, inversion and stale timeout,
/// the control rate and the seed. RunScenario and the emulator (EmulatedHand) build their rigs from it.
sim::SimRigConfig RigConfigFor(const ScenarioConfig& config);

/// summary.json content for `result`.
nlohmann::json SummaryJson(const RunResult& result);

/// A short human-readable table: one line per metric that matters and per expectation.
std::string SummaryTable(const RunResult& result);

}  // namespace graspbed::testbed
