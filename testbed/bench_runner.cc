// RunScenario for backend serial and backend replay (docs/hardware.md, "One runner, three backends"):
// the loop, readout, inversion, controller and intent script of a simulated run, against the hand
// over a serial link or against a recording, with the outputs a simulated run writes less what only
// the simulation knows (ground truth: truth columns, metrics and plots are absent, not zero).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/plot.h"
#include "common/yaml_map.h"
#include "controller/control_loop.h"
#include "controller/grasp_controller.h"
#include "hardware/frame_logger.h"
#include "hardware/hardware_backend.h"
#include "hardware/intent_input.h"
#include "hardware/recorded_session.h"
#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "testbed/run_outputs.h"
#include "testbed/runner.h"

namespace graspbed::testbed::internal {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Per-unit columns of a bench run: the frame and the estimate, no truth.
constexpr const char* kBenchUnitNames[] = {"r1_ohm", "r2_ohm", "fn_est_n", "ft_est_n", "validity"};
constexpr size_t kBenchPerUnit = std::size(kBenchUnitNames);
// Replay: the recorded command beside the new one, after the per-unit columns.
constexpr const char* kRecordedNames[] = {"recorded_grip_effort", "recorded_motor_enable", "recorded_brake",
                                          "command_differs"};
static_assert(kLoopColumnCount + std::size(kRecordedNames) <= kSignalBoundFixedColumns &&
                  kBenchPerUnit <= kSignalBoundColumnsPerUnit,
              "the loader's bound on signal memory must count every column");
// Storage reserved for a serial session's rows beyond duration x rate (ticks also follow frames).
constexpr double kSerialRowMargin = 1.5;

bool IsIntentAction(ActionKind kind) {
  return kind == ActionKind::kClose || kind == ActionKind::kOpen || kind == ActionKind::kIdle;
}

controller::GraspIntent IntentOf(ActionKind kind) {
  return kind == ActionKind::kClose  ? controller::GraspIntent::kClose
         : kind == ActionKind::kOpen ? controller::GraspIntent::kOpen
                                     : controller::GraspIntent::kIdle;
}

std::string Where(const ScenarioConfig& config, const Action& action) {
  return (config.source_file.empty() ? std::string("scenario") : config.source_file) +
         (action.line > 0 ? ":" + std::to_string(action.line) : std::string()) + ": ";
}

/// What a person at the bench is asked to do for an action only the simulator can perform.
std::string PromptText(const Action& action) {
  char text[200];
  switch (action.kind) {
    case ActionKind::kLift:
      std::snprintf(text, sizeof(text), "lift the hand by %.0f mm over %.2f s", action.height_m * 1e3,
                    action.duration_s);
      return text;
    case ActionKind::kAddMass:
      std::snprintf(text, sizeof(text), "add %.0f g to the object", action.mass_kg * 1e3);
      return text;
    case ActionKind::kPull:
      std::snprintf(text, sizeof(text), "pull the object with (%.1f, %.1f, %.1f) N", action.vector[0],
                    action.vector[1], action.vector[2]);
      return text;
    default:
      return std::string(ActionName(action.kind)) + " (as at line " + std::to_string(action.line) + ")";
  }
}

/// Refuses a script the bench cannot play: for serial, event actions and (without prompts) every
/// action but close/open/idle; the message names the action, its line and what is allowed.
void CheckBenchScript(const ScenarioConfig& config, const RunOptions& options) {
  if (config.backend != Backend::kSerial) return;  // a replay's recording already holds what happened
  std::vector<std::string> refused;
  for (const Action& action : config.script) {
    if (action.after != ScriptEvent::kNone) {
      throw common::ConfigError(Where(config, action) + "script action " + ActionName(action.kind) +
                                " after: " + EventName(action.after) +
                                ": backend serial plays fixed-time actions only (give it an at_s)");
    }
    if (!IsIntentAction(action.kind) && !options.prompt_actions) {
      refused.push_back(Where(config, action) + ActionName(action.kind));
    }
  }
  if (refused.empty()) return;
  std::string message = "backend serial cannot perform these script actions (they need the simulator):";
  for (const std::string& entry : refused) message += "\n  " + entry;
  message +=
      "\nallowed on the bench: close, open, idle (at a fixed at_s); or run with --prompt-actions to have the "
      "others announced at their times for a person at the bench to perform";
  throw common::ConfigError(message);
}

/// Writes into HandCommands nowhere: the actuator of a replay, which only compares.
class NoActuator final : public hand::HandActuator {
 public:
  hand::WriteStatus Write(const hand::HandCommand&) override { return hand::WriteStatus::kOk; }
  std::string name() const override { return "none"; }
};

/// A controller phase and when it began (the loop's clock) [s].
struct PhaseChange {
  std::string phase;
  double time_s = 0.0;
};

struct IntentLogEntry {
  std::string intent;
  std::string source;       ///< "script", "recording", or the live input's ("key", "stdin", "fifo")
  double received_s = 0.0;  ///< script: its at_s; live: when the input read it [s]
  double applied_s = 0.0;   ///< the tick that first ran with it [s]
  long live_index = -1;     ///< index in IntentInput::events(), for live commands
};

struct PromptEntry {
  std::string action;
  std::string text;
  int line = 0;
  double at_s = 0.0;
  double shown_s = 0.0;
};

void WriteBenchPlots(const RunResult& result, const common::SignalLog& log, const sensor::Layout& layout, bool replay,
                     const std::string& dir) {
  if (log.rows() < 2) return;
  const std::vector<double> time = log.ColumnValues("time_s");
  const int units = layout.unit_count();
  const std::string title = result.config.name + " (" + result.config.controller.name + ", " +
                            BackendName(result.config.backend) + ")";
  plot::Figure forces;
  forces.title = title + ": forces";
  forces.columns = 1;
  const plot::Chart per_unit = PerUnitFnChart(log, time, units);
  plot::Chart totals = MakeChart("Total normal force (sensed)", "time [s]", "force [N]");
  totals.series.push_back(Line(log, time, "est_total_fn_n", "estimated (valid units)"));
  totals.markers = ScriptMarkers(result);
  totals.include_zero_y = true;
  forces.panels = {per_unit, totals};
  plot::WritePng(forces, dir + "/forces.png");

  plot::Figure grip;
  grip.title = title + ": grip";
  plot::Chart effort =
      MakeChart(replay ? "Grip motor command: this controller and the recording" : "Grip motor command",
                "time [s]", "effort [-]");
  effort.series = {Line(log, time, "grip_effort", replay ? "this controller" : "effort")};
  if (replay) effort.series.push_back(Line(log, time, "recorded_grip_effort", "recorded", 1.0, true));
  effort.markers = ScriptMarkers(result);
  effort.include_zero_y = true;
  plot::Chart force = MakeChart("Grip force", "time [s]", "force [N]");
  force.series = {Line(log, time, "grip_target_n", "controller target"),
                  Line(log, time, "est_total_fn_n", "estimated")};
  force.include_zero_y = true;
  grip.panels = {effort, force};
  plot::WritePng(grip, dir + "/grip.png");
  WriteTaxelMaps(result, log, layout, time, title, dir);
}

}  // namespace

RunResult RunOnBench(const ScenarioConfig& config, const RunOptions& options) {
  const auto wall_start = Clock::now();
  RunResult result;
  result.config = config;
  result.out_dir = options.out_dir;
  const bool serial = config.backend == Backend::kSerial;
  const bool replay = config.backend == Backend::kReplay;

  CheckBenchScript(config, options);
  const sensor::Layout layout = sensor::LoadLayout(ResolveLayoutPath(config));
  const int units = layout.unit_count();
  // The host inverts with the sensor's nominal constants, as a simulated run does.
  const sensor::Calibration calibration =
      options.calibration ? *options.calibration
                          : sensor::NominalCalibration(config.sensor.strain_model.nominal, units);
  controller::ControlLoopConfig loop_config;
  loop_config.stale_timeout_s = config.controller.stale_timeout_s;
  loop_config.readout = config.sensor.readout;
  loop_config.inversion = config.sensor.inversion;
  loop_config.Validate();
  std::unique_ptr<controller::GraspController> grasp;
  std::vector<std::string> diagnostic_columns;
  try {
    grasp = options.make_controller
                ? options.make_controller(config.controller)
                : controller::MakeController(config.controller.name, config.controller.params);
    diagnostic_columns = DiagnosticColumns(*grasp);
  } catch (const std::invalid_argument& error) {
    throw common::ConfigError((config.source_file.empty() ? "" : config.source_file + ": ") + error.what());
  }

  // A FIFO that cannot be made is refused before anything else is touched.
  std::unique_ptr<hardware::IntentInput> live;
  if (serial && (options.intent_stdin || !options.intent_fifo.empty())) {
    live = std::make_unique<hardware::IntentInput>(
        hardware::IntentInputConfig{.read_stdin = options.intent_stdin, .fifo_path = options.intent_fifo});
  }
  // The recording (replay) or the link (serial); both refused, like all bad input, before any output.
  std::optional<hardware::RecordedSession> recording;
  std::unique_ptr<hardware::ReplayBackend> replay_backend;
  std::unique_ptr<hardware::HardwareBackend> serial_backend;
  std::unique_ptr<hardware::HardwareActuator> serial_actuator;
  NoActuator no_actuator;
  if (replay) {
    recording = hardware::LoadRecordedSession(config.log, units);
    replay_backend =
        std::make_unique<hardware::ReplayBackend>(*recording, config.sensor.strain_model.nominal.r0_ohm);
  } else {
    if (!config.log.empty() && !std::ofstream(config.log + ".partial", std::ios::trunc)) {
      throw std::invalid_argument("--log " + config.log + ": cannot write this file");
    }
    serial_backend = std::make_unique<hardware::HardwareBackend>(config.serial, units, layout.name);
    serial_actuator = std::make_unique<hardware::HardwareActuator>(*serial_backend, config.serial);
    if (!config.log.empty()) serial_backend->link()->EnableTap(16384);
    if (options.latency_frames > 0) serial_actuator->link()->EnableLatencyRecording(options.latency_frames);
  }
  if (serial) {
    try {
      serial_backend->Start();
      serial_actuator->Start();
    } catch (const std::runtime_error& error) {
      // Missing port, no permission, busy, no HELLO, wrong unit count: refused before running.
      if (!config.log.empty()) fs::remove(config.log + ".partial");
      throw std::invalid_argument(error.what());
    }
  }
  sensor::TactileBackend& backend =
      replay ? static_cast<sensor::TactileBackend&>(*replay_backend) : *serial_backend;
  hand::HandActuator& actuator = replay ? static_cast<hand::HandActuator&>(no_actuator) : *serial_actuator;
  controller::ControlLoop loop(backend, *grasp, actuator, layout, calibration, loop_config);
  std::unique_ptr<hardware::FrameLogger> frame_logger;
  if (serial && !config.log.empty()) {
    hardware::SerialLink& link = *serial_backend->link();
    frame_logger = std::make_unique<hardware::FrameLogger>(
        config.log, [&link](hardware::TappedFrame* entry) { return link.PopTap(entry); }, layout, calibration,
        loop_config.readout, loop_config.inversion, serial_backend->nominal_r0_ohm());
  }

  if (!options.out_dir.empty()) {
    PrepareOutputDir(options.out_dir);
    common::WriteFileAtomic(options.out_dir + "/config.yaml", EmitScenarioYaml(config));
  }

  std::vector<std::string> columns(kLoopColumnNames, kLoopColumnNames + kLoopColumnCount);
  for (int u = 0; u < units; ++u) {
    for (const char* name : kBenchUnitNames) columns.push_back(std::string(name) + "_" + std::to_string(u));
  }
  const size_t recorded_first = columns.size();
  if (replay) columns.insert(columns.end(), std::begin(kRecordedNames), std::end(kRecordedNames));
  const size_t diagnostics_first = columns.size();
  columns.insert(columns.end(), diagnostic_columns.begin(), diagnostic_columns.end());
  std::vector<std::string> text_columns = {"intent", "phase", "slip_cues"};
  if (replay) text_columns.push_back("recorded_phase");
  // Without an output directory (`graspbed hw`, possibly until Ctrl-C) no rows are kept.
  const size_t capacity_rows =
      options.out_dir.empty() ? 0
      : replay                ? recording->ticks() + 1
                              : static_cast<size_t>(std::ceil(
                                    config.duration_s * std::max(config.controller.rate_hz, config.sensor.sample_rate_hz) *
                                    kSerialRowMargin)) +
                     16;
  common::SignalLog log(columns, text_columns, capacity_rows);

  // The script: intent actions go to the controller, the others (serial with --prompt-actions) to
  // the person at the bench. A replay of a recording with its own intent column follows that.
  const bool intent_from_recording = replay && !recording->intent.empty();
  controller::GraspIntent intent = controller::GraspIntent::kIdle;
  if (config.controller.grip_ceiling_n > 0.0) grasp->SetGripCeiling(config.controller.grip_ceiling_n);
  grasp->SetIntent(intent);
  std::vector<ActionTiming> timings(config.script.size());
  std::vector<IntentLogEntry> intents;
  std::vector<PromptEntry> prompts;
  std::vector<PhaseChange> phases;
  intents.reserve(1024);
  phases.reserve(1024);
  size_t next_action = 0;
  double first_close_s = -1.0;
  const char* last_phase = nullptr;

  const auto set_intent = [&](controller::GraspIntent next, const std::string& source, double received_s,
                              double applied_s) {
    intent = next;
    grasp->SetIntent(intent);
    if (intent == controller::GraspIntent::kClose && first_close_s < 0.0) first_close_s = applied_s;
    if (intents.size() < intents.capacity())
      intents.push_back({controller::ToString(intent), source, received_s, applied_s});
  };
  // Due script actions at loop time `t` (fixed times, in order).
  const auto fire_script = [&](double t) {
    while (next_action < config.script.size() && config.script[next_action].at_s <= t) {
      const Action& action = config.script[next_action];
      timings[next_action].fired_s = t;
      if (IsIntentAction(action.kind)) {
        if (!intent_from_recording) set_intent(IntentOf(action.kind), "script", action.at_s, t);
      } else if (serial) {
        const std::string text = PromptText(action);
        std::fprintf(stderr, "\a>>> at %.2f s: %s now (%s, line %d)\n", t, text.c_str(),
                     ActionName(action.kind), action.line);
        prompts.push_back({ActionName(action.kind), text, action.line, action.at_s, t});
      }
      ++next_action;
    }
  };

  bool stopped = false;
  bool quit = false;
  uint64_t commands_compared = 0;
  uint64_t commands_differing = 0;
  double max_effort_difference = 0.0;
  double first_difference_s = -1.0;
  double peak_total_fn_n = 0.0;
  double t = 0.0;
  const auto record_row = [&](double time_s, size_t tick) {
    const controller::ControllerTelemetry telemetry = grasp->telemetry();
    if (last_phase == nullptr || std::string_view(last_phase) != telemetry.phase) {
      last_phase = telemetry.phase;
      if (phases.size() < phases.capacity()) phases.push_back({telemetry.phase, time_s});
    }
    if (!loop.state().stale) peak_total_fn_n = std::max(peak_total_fn_n, loop.state().total_fn_n);
    const char** text = nullptr;
    double* row = log.AppendRow(&text);
    if (row == nullptr) return;
    text[0] = controller::ToString(intent);
    text[1] = telemetry.phase;
    text[2] = telemetry.slip_cues;
    WriteLoopCells(row, time_s, loop, telemetry);
    WriteDiagnosticCells(row, diagnostics_first, diagnostic_columns.size(), *grasp);
    const sensor::RawFrame& frame = loop.frame();
    const sensor::TactileState& state = loop.state();
    for (int u = 0; u < units; ++u) {
      double* cell = row + kLoopColumnCount + static_cast<size_t>(u) * kBenchPerUnit;
      cell[0] = frame.r1_ohm[u];
      cell[1] = frame.r2_ohm[u];
      cell[2] = state.fn_n[u];
      cell[3] = state.ft_n[u];
      cell[4] = static_cast<double>(state.validity[u]);
    }
    if (replay && !recording->commands.empty()) {
      const hand::HandCommand& recorded = recording->commands[tick];
      const hand::HandCommand& now = loop.command();
      // Bit for bit: the same controller on the same input must write the same doubles.
      const bool differs = recorded.grip_effort != now.grip_effort || recorded.enable != now.enable ||
                           recorded.brake != now.brake;
      double* cell = row + recorded_first;
      cell[0] = recorded.grip_effort;
      cell[1] = recorded.enable ? 1.0 : 0.0;
      cell[2] = recorded.brake ? 1.0 : 0.0;
      cell[3] = differs ? 1.0 : 0.0;
      ++commands_compared;
      if (differs) {
        ++commands_differing;
        if (first_difference_s < 0.0) first_difference_s = time_s;
      }
      max_effort_difference =
          std::max(max_effort_difference, std::abs(recorded.grip_effort - now.grip_effort));
    }
    if (replay) text[3] = recording->phase.empty() ? "" : recording->phase[tick].c_str();
  };

  if (replay) {
    const hardware::RecordedSession& session = *recording;
    std::string recorded_intent;
    for (size_t k = 0; k < session.ticks(); ++k) {
      if (options.stop != nullptr && options.stop->load(std::memory_order_relaxed)) {
        stopped = true;
        break;
      }
      t = session.time_s[k];
      fire_script(t);
      if (intent_from_recording && session.intent[k] != recorded_intent) {
        recorded_intent = session.intent[k];
        const auto next = controller::IntentFromName(recorded_intent);
        if (next && *next != intent) set_intent(*next, "recording", t, t);
      }
      replay_backend->Seek(k);
      loop.Tick(t);
      record_row(t, k);
      if (options.progress && k % 1000 == 0) options.progress(t, session.time_s.back());
    }
  } else {
    hardware::SerialLink& link = *serial_backend->link();
    const double period_s = 1.0 / config.controller.rate_hz;
    const Clock::time_point start = Clock::now();
    if (live) live->Start(start);
    // The operator's cue (and a test's): the session runs and takes intent from now on.
    std::string inputs;
    if (live && options.intent_stdin) inputs += live->keys() ? "keys c/o/i/q" : "lines on stdin";
    if (!options.intent_fifo.empty())
      inputs += (inputs.empty() ? "" : ", ") + ("lines on " + options.intent_fifo);
    char length[32] = "until stopped";
    if (std::isfinite(config.duration_s)) std::snprintf(length, sizeof(length), "%.1f s", config.duration_s);
    std::fprintf(stderr, "run: backend serial on %s: session started (%s; live intent: %s)\n",
                 config.serial.port.c_str(), length, inputs.empty() ? "none" : inputs.c_str());
    uint64_t seen = 0;
    double next_progress_s = 0.0;
    for (;;) {
      if (options.stop != nullptr && options.stop->load(std::memory_order_relaxed)) {
        stopped = true;
        break;
      }
      // Tick on every frame arrival, and at rate_hz when frames stop (stale detection, commands).
      link.WaitForFrame(seen, period_s);
      seen = link.published();
      t = std::chrono::duration<double>(Clock::now() - start).count();
      if (t >= config.duration_s) break;
      fire_script(t);
      hardware::IntentCommand command;
      size_t index = 0;
      while (live && live->Poll(&command, &index)) {
        if (command == hardware::IntentCommand::kQuit) {
          quit = true;
          break;
        }
        const controller::GraspIntent next =
            command == hardware::IntentCommand::kClose  ? controller::GraspIntent::kClose
            : command == hardware::IntentCommand::kOpen ? controller::GraspIntent::kOpen
                                                        : controller::GraspIntent::kIdle;
        set_intent(next, "live", -1.0, t);
        intents.back().live_index = static_cast<long>(index);  // source and time from the input below
      }
      if (quit) break;
      loop.Tick(t);
      record_row(t, 0);
      if (options.progress && t >= next_progress_s) {
        options.progress(t, config.duration_s);
        next_progress_s = t + 0.1;
      }
    }
  }

  // Live commands: their source and reception time from the input's own record.
  if (live) {
    live->Stop();
    const std::vector<hardware::IntentInputEvent> received = live->events();
    for (IntentLogEntry& entry : intents) {
      if (entry.live_index < 0) continue;
      entry.source = received[static_cast<size_t>(entry.live_index)].source;
      entry.received_s = received[static_cast<size_t>(entry.live_index)].received_s;
    }
  }
  const double end_s = t;
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  bool connected_at_end = true;
  nlohmann::json bench = {{"backend", BackendName(config.backend)}, {"controller", grasp->name()}};
  if (serial) {
    hardware::SerialLink& link = *serial_backend->link();
    connected_at_end = link.connected();
    // The clean shutdown order of docs/protocol.md: stream stop, motor off, restore, close.
    serial_backend->Stop();
    serial_actuator->Stop();
    if (frame_logger) frame_logger->Finish();
    const sensor::BackendCounters counters = serial_backend->counters();
    bench["port"] = config.serial.port;
    bench["frames"] = counters.frames;
    bench["corrupt"] = counters.corrupt;
    bench["dropped"] = counters.dropped;
    bench["reordered"] = link.reordered();
    bench["unknown_packets"] = counters.unknown_packets;
    bench["reconnects"] = counters.reconnects;
    bench["stale_periods"] = counters.stale_periods;
    bench["sessions"] = counters.sessions;
    bench["motor_commands"] = link.motor_commands_sent();
    if (options.latency_frames > 0) {
      const hardware::LatencySummary latency = serial_actuator->link()->latency();
      bench["latency"] = {{"frames_answered", latency.frames}, {"not_kept", latency.not_kept},
                          {"p50_us", latency.p50_us},          {"p99_us", latency.p99_us},
                          {"p999_us", latency.p999_us},        {"max_us", latency.max_us},
                          {"over_1ms", latency.over_1ms},      {"over_5ms", latency.over_5ms}};
    }
    bench["connected_at_end"] = connected_at_end;
    if (!link.last_error().empty()) bench["last_error"] = link.last_error();
    if (frame_logger) {
      bench["log"] = config.log;
      bench["log_rows"] = frame_logger->rows();
      bench["log_rows_lost"] = link.tap_overflows();
      if (!frame_logger->error().empty()) bench["log_error"] = frame_logger->error();
    }
    bench["ended_by"] = stopped ? "signal" : quit ? "quit" : "duration";
    bench["live_intent"] = live ? (live->keys() ? "keys" : "lines") : "none";
    if (!options.intent_fifo.empty()) bench["intent_fifo"] = options.intent_fifo;
  } else {
    bench["recording"] = recording->path;
    bench["recording_kind"] = recording->kind_name();
    bench["recorded_ticks"] = recording->ticks();
    bench["intent_from"] = intent_from_recording ? "recording" : "script";
    bench["commands_recorded"] = !recording->commands.empty();
    if (!recording->commands.empty()) {
      bench["commands_compared"] = commands_compared;
      bench["commands_differing"] = commands_differing;
      bench["max_effort_difference"] = max_effort_difference;
      bench["first_difference_s"] =
          first_difference_s >= 0.0 ? nlohmann::json(first_difference_s) : nlohmann::json(nullptr);
    }
  }
  const controller::LoopCounters& ticks = loop.counters();
  bench["ticks"] = ticks.ticks;
  bench["loop_frames"] = ticks.frames;
  bench["stale_ticks"] = ticks.stale_ticks;
  bench["disconnected_ticks"] = ticks.disconnected_ticks;
  bench["actuator_failures"] = ticks.actuator_failures;
  bench["retares"] = ticks.retares;
  bench["peak_est_total_fn_n"] = peak_total_fn_n;
  bench["final_est_total_fn_n"] = loop.state().total_fn_n;
  bench["final_valid_units"] = loop.state().valid_count;
  bench["first_close_s"] = first_close_s >= 0.0 ? nlohmann::json(first_close_s) : nlohmann::json(nullptr);
  nlohmann::json phase_list = nlohmann::json::array();
  for (const PhaseChange& change : phases)
    phase_list.push_back({{"phase", change.phase}, {"start_s", change.time_s}});
  bench["phases"] = phase_list;
  nlohmann::json intent_list = nlohmann::json::array();
  for (const IntentLogEntry& entry : intents) {
    intent_list.push_back({{"intent", entry.intent},
                           {"source", entry.source},
                           {"received_s", entry.received_s},
                           {"applied_s", entry.applied_s}});
  }
  bench["intent_events"] = intent_list;
  nlohmann::json prompt_list = nlohmann::json::array();
  for (const PromptEntry& prompt : prompts) {
    prompt_list.push_back({{"action", prompt.action},
                           {"text", prompt.text},
                           {"line", prompt.line},
                           {"at_s", prompt.at_s},
                           {"shown_s", prompt.shown_s}});
  }
  bench["prompts"] = prompt_list;

  // Every expectation of the scenario needs the ground truth (the object's motion, the squeeze, true
  // loads, true slip): listed, not scored.
  for (ExpectationOutcome& outcome : EvaluateExpectations(config.expectations, Metrics{})) {
    if (outcome.name == "no_physics_fault") continue;
    outcome.passed = true;
    outcome.value = std::nullopt;
    outcome.value_text = "not scored";
    outcome.note = std::string("needs the simulation's ground truth; backend ") + BackendName(config.backend);
    result.outcomes.push_back(std::move(outcome));
  }
  result.bench = bench;
  result.script_timings = timings;
  result.completed = !stopped;
  const bool log_failed = frame_logger && !frame_logger->error().empty();
  result.passed = result.completed && connected_at_end && !log_failed;
  result.metrics.sim_s = end_s;
  result.metrics.wall_s = wall_s;
  result.real_time_factor = wall_s > 0.0 ? end_s / wall_s : 0.0;
  result.frames = ticks.frames;
  result.stale_ticks = ticks.stale_ticks;
  result.control_ticks = ticks.ticks;
  result.signal_rows_lost = log.lost_rows();

  if (options.on_signals) options.on_signals(log);
  if (!options.out_dir.empty()) {
    common::WriteCsvAtomic(log, options.out_dir + "/signals.csv");
    if (options.write_plots) WriteBenchPlots(result, log, layout, replay, options.out_dir);
    common::WriteFileAtomic(options.out_dir + "/summary.json", SummaryJson(result).dump(2) + "\n");
    if (result.completed) fs::remove(fs::path(options.out_dir) / kIncompleteMarker);
  }
  return result;
}

std::string BenchSummaryTable(const RunResult& result) {
  const nlohmann::json& b = result.bench;
  std::ostringstream out;
  char line[320];
  std::snprintf(line, sizeof(line), "scenario %s, controller %s, backend %s: %s\n",
                result.config.name.c_str(), result.config.controller.name.c_str(),
                BackendName(result.config.backend),
                !result.completed ? "INTERRUPTED"
                : result.passed   ? "PASSED"
                                  : "FAILED");
  out << line;
  if (result.config.backend == Backend::kSerial) {
    std::snprintf(line, sizeof(line),
                  "  %s: %.2f s (ended by %s), %llu frames, %llu corrupt, %llu dropped, %llu reordered, %llu "
                  "reconnects, "
                  "%llu stale periods%s\n",
                  b.value("port", std::string()).c_str(), result.metrics.sim_s,
                  b.value("ended_by", std::string()).c_str(),
                  static_cast<unsigned long long>(b.value("frames", 0ull)),
                  static_cast<unsigned long long>(b.value("corrupt", 0ull)),
                  static_cast<unsigned long long>(b.value("dropped", 0ull)),
                  static_cast<unsigned long long>(b.value("reordered", 0ull)),
                  static_cast<unsigned long long>(b.value("reconnects", 0ull)),
                  static_cast<unsigned long long>(b.value("stale_periods", 0ull)),
                  b.value("connected_at_end", true) ? "" : "; device DISCONNECTED at the end");
    out << line;
  } else {
    std::snprintf(line, sizeof(line), "  replayed %llu ticks of %s (%s), intent from the %s\n",
                  static_cast<unsigned long long>(b.value("recorded_ticks", 0ull)),
                  b.value("recording", std::string()).c_str(),
                  b.value("recording_kind", std::string()).c_str(),
                  b.value("intent_from", std::string()).c_str());
    out << line;
    if (b.value("commands_recorded", false)) {
      std::snprintf(line, sizeof(line),
                    "  commands differing from the recording: %llu of %llu (max |effort| difference %.3g)\n",
                    static_cast<unsigned long long>(b.value("commands_differing", 0ull)),
                    static_cast<unsigned long long>(b.value("commands_compared", 0ull)),
                    b.value("max_effort_difference", 0.0));
      out << line;
    }
  }
  std::snprintf(line, sizeof(line), "  sensed grip: peak %.2f N, final %.2f N on %d valid units\n",
                b.value("peak_est_total_fn_n", 0.0), b.value("final_est_total_fn_n", 0.0),
                b.value("final_valid_units", 0));
  out << line;
  out << "  phases:";
  for (const auto& phase : b.at("phases")) {
    std::snprintf(line, sizeof(line), " %s@%.3f", phase.at("phase").get<std::string>().c_str(),
                  phase.at("start_s").get<double>());
    out << line;
  }
  out << "\n";
  for (const auto& event : b.at("intent_events")) {
    std::snprintf(line, sizeof(line), "  intent %s from %s at %.3f s\n",
                  event.at("intent").get<std::string>().c_str(),
                  event.at("source").get<std::string>().c_str(), event.at("applied_s").get<double>());
    out << line;
  }
  for (const auto& prompt : b.at("prompts")) {
    std::snprintf(line, sizeof(line), "  prompted at %.2f s: %s\n", prompt.at("shown_s").get<double>(),
                  prompt.at("text").get<std::string>().c_str());
    out << line;
  }
  for (const ExpectationOutcome& o : result.outcomes) {
    std::snprintf(line, sizeof(line), "  [----] %-24s %-14s not scored: %s\n", o.name.c_str(),
                  o.limit.c_str(), o.note.c_str());
    out << line;
  }
  return out.str();
}

}  // namespace graspbed::testbed::internal
