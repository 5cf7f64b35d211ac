// The bench backends of the run loop (run_backend.h, docs/hardware.md "One runner, three backends"):
// the hand over a serial link, and a recording replayed. The loop, readout, inversion, controller and
// intent script of a simulated run, with the outputs a simulated run writes less what only the
// simulation knows (ground truth: truth columns, metrics and plots are absent, not zero).
#include <algorithm>
#include <array>
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
#include "hardware/serial_hand_sensor.h"
#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "testbed/run_outputs.h"
#include "testbed/run_backend.h"
#include "testbed/runner.h"

namespace graspbed::testbed::internal {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Replay: the recorded command beside the new one, after the per-unit columns.
constexpr const char* kRecordedNames[] = {"recorded_grip_effort", "recorded_motor_enable", "recorded_brake",
                                          "command_differs"};
static_assert(kLoopColumnCount + std::size(kRecordedNames) <= kSignalBoundFixedColumns,
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

/// The frame log's hand columns: signals.csv's, filled as WriteLoopCells fills them.
hardware::HandLogColumns HandLogColumns() {
  hardware::HandLogColumns columns;
  columns.names.assign(HandColumnNames().begin(), HandColumnNames().end());
  columns.write = [](const hand::HandState& hand, double* cells) {
    std::array<double, kLoopColumnCount> row{};
    WriteHandCells(row.data(), hand);
    std::copy(row.begin() + kHandTime, row.end(), cells);
  };
  return columns;
}

/// The hand state of a recording, tick by tick: Seek(k) before the loop's k-th tick, then Read()
/// gives that tick's recorded state (ReadHandCells), true when its sample time differs from the
/// previous tick's (a new reading). A recording without hand columns gives an unknown hand (no
/// digits, every field unknown). Never allocates.
class ReplayHandSensor final : public hand::HandSensor {
 public:
  explicit ReplayHandSensor(const hardware::RecordedSession& recording) : recording_(recording) {}
  void Seek(size_t tick) { tick_ = tick; }
  bool Read(double /*time_s*/, hand::HandState* state) override {
    if (!recording_.has_hand()) return false;
    const double* cells = recording_.hand_cells.data() + tick_ * recording_.hand_column_count;
    std::copy_n(cells, recording_.hand_column_count, row_.begin() + kHandTime);
    const double time_s = row_[kHandTime];
    const bool same = std::isnan(time_s) ? std::isnan(last_time_s_) : time_s == last_time_s_;
    last_time_s_ = time_s;
    *state = ReadHandCells(row_.data(), /*has_columns=*/true);
    return !same;
  }
  std::string name() const override { return "replay"; }

 private:
  const hardware::RecordedSession& recording_;
  std::array<double, kLoopColumnCount> row_{};
  size_t tick_ = 0;
  double last_time_s_ = std::nan("");
};

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
  const std::string title = result.config.name + " (" + result.config.controller.name + ", " +
                            BackendName(result.config.backend) + ")";
  plot::Figure forces;
  forces.title = title + ": forces";
  forces.columns = 1;
  const plot::Chart per_unit = PerUnitFnChart(log, time, layout);
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


/// What the serial and the replay backend share: the controller and its loop on the host's
/// calibration, the intent script (intent actions to the controller; on serial, prompts for the
/// others), and the bench record (intent events, prompts, controller phases).
class BenchRun : public RunBackend {
 public:
  BenchRun(const ScenarioConfig& config, const RunOptions& options)
      : config_(config),
        options_(options),
        layout_(sensor::LoadLayout(ResolveLayoutPath(config))),
        units_(layout_.unit_count()),
        // The host inverts with the sensor's nominal constants, as a simulated run does.
        calibration_(options.calibration ? *options.calibration
                                         : sensor::NominalCalibration(config.sensor.strain_model.nominal, units_)),
        grasp_(MakeRunController(config, options)),
        timings_(config.script.size()) {
    loop_config_.stale_timeout_s = config.controller.stale_timeout_s;
    loop_config_.readout = config.sensor.readout;
    loop_config_.inversion = config.sensor.inversion;
    loop_config_.Validate();
    intents_.reserve(1024);
    phases_.reserve(1024);
  }

  std::vector<std::string> Columns() const override { return UnitColumns(units_, /*with_truth=*/false); }
  controller::GraspController& controller() override { return *grasp_; }
  const controller::ControlLoop& loop() const override { return *loop_; }
  controller::GraspIntent intent() const override { return intent_; }
  const controller::ControllerTelemetry& telemetry() const override { return telemetry_; }
  void Start() override {
    if (config_.controller.grip_ceiling_n > 0.0) grasp_->SetGripCeiling(config_.controller.grip_ceiling_n);
    grasp_->SetIntent(intent_);
  }
  void Record(double /*time_s*/, double* cells, const char** /*texts*/) override {
    WriteUnitCells(cells, units_, *loop_, {});
  }

 protected:
  void SetIntent(controller::GraspIntent next, const std::string& source, double received_s, double applied_s) {
    intent_ = next;
    grasp_->SetIntent(intent_);
    if (intent_ == controller::GraspIntent::kClose && first_close_s_ < 0.0) first_close_s_ = applied_s;
    if (intents_.size() < intents_.capacity())
      intents_.push_back({controller::ToString(intent_), source, received_s, applied_s});
  }

  /// Fires the script's actions due at loop time `t` (fixed times, in order). `play_intent` false:
  /// the recording's own intent column is followed instead.
  void FireScript(double t, bool play_intent) {
    while (next_action_ < config_.script.size() && config_.script[next_action_].at_s <= t) {
      const Action& action = config_.script[next_action_];
      timings_[next_action_].fired_s = t;
      if (IsIntentAction(action.kind)) {
        if (play_intent) SetIntent(IntentOf(action.kind), "script", action.at_s, t);
      } else if (config_.backend == Backend::kSerial) {
        const std::string text = PromptText(action);
        std::fprintf(stderr, "\a>>> at %.2f s: %s now (%s, line %d)\n", t, text.c_str(),
                     ActionName(action.kind), action.line);
        prompts_.push_back({ActionName(action.kind), text, action.line, action.at_s, t});
      }
      ++next_action_;
    }
  }

  /// Ticks the loop at `t` [s] and keeps the bench record's per-tick figures.
  void Tick(double t) {
    loop_->Tick(t);
    end_s_ = t;
    telemetry_ = grasp_->telemetry();
    if (last_phase_ == nullptr || std::string_view(last_phase_) != telemetry_.phase) {
      last_phase_ = telemetry_.phase;
      if (phases_.size() < phases_.capacity()) phases_.push_back({telemetry_.phase, t});
    }
    if (!loop_->state().stale) peak_total_fn_n_ = std::max(peak_total_fn_n_, loop_->state().total_fn_n);
  }

  /// The bench record both backends share, and the result's figures; `bench` holds the backend's own.
  void FinishBench(nlohmann::json bench, double wall_s, RunResult& result) {
    const controller::LoopCounters& ticks = loop_->counters();
    bench["ticks"] = ticks.ticks;
    bench["loop_frames"] = ticks.frames;
    bench["stale_ticks"] = ticks.stale_ticks;
    bench["disconnected_ticks"] = ticks.disconnected_ticks;
    bench["actuator_failures"] = ticks.actuator_failures;
    bench["retares"] = ticks.retares;
    bench["hand_readings"] = ticks.hand_readings;
    bench["hand_stale_ticks"] = ticks.hand_stale_ticks;
    bench["peak_est_total_fn_n"] = peak_total_fn_n_;
    bench["final_est_total_fn_n"] = loop_->state().total_fn_n;
    bench["final_valid_units"] = loop_->state().valid_count;
    bench["first_close_s"] = first_close_s_ >= 0.0 ? nlohmann::json(first_close_s_) : nlohmann::json(nullptr);
    nlohmann::json phase_list = nlohmann::json::array();
    for (const PhaseChange& change : phases_)
      phase_list.push_back({{"phase", change.phase}, {"start_s", change.time_s}});
    bench["phases"] = phase_list;
    nlohmann::json intent_list = nlohmann::json::array();
    for (const IntentLogEntry& entry : intents_) {
      intent_list.push_back({{"intent", entry.intent},
                             {"source", entry.source},
                             {"received_s", entry.received_s},
                             {"applied_s", entry.applied_s}});
    }
    bench["intent_events"] = intent_list;
    nlohmann::json prompt_list = nlohmann::json::array();
    for (const PromptEntry& prompt : prompts_) {
      prompt_list.push_back({{"action", prompt.action},
                             {"text", prompt.text},
                             {"line", prompt.line},
                             {"at_s", prompt.at_s},
                             {"shown_s", prompt.shown_s}});
    }
    bench["prompts"] = prompt_list;
    // Every expectation of the scenario needs the ground truth (the object's motion, the squeeze, true
    // loads, true slip): listed, not scored.
    for (ExpectationOutcome& outcome : EvaluateExpectations(config_.expectations, Metrics{}, config_.metrics)) {
      if (outcome.name == "no_physics_fault") continue;
      outcome.passed = true;
      outcome.value = std::nullopt;
      outcome.value_text = "not scored";
      outcome.note = std::string("needs the simulation's ground truth; backend ") + BackendName(config_.backend);
      result.outcomes.push_back(std::move(outcome));
    }
    result.bench = std::move(bench);
    result.script_timings = timings_;
    result.metrics.sim_s = end_s_;
    result.metrics.wall_s = wall_s;
    result.frames = ticks.frames;
    result.stale_ticks = ticks.stale_ticks;
    result.control_ticks = ticks.ticks;
  }

  const ScenarioConfig& config_;
  const RunOptions& options_;
  const sensor::Layout layout_;
  const int units_;
  const sensor::Calibration calibration_;
  controller::ControlLoopConfig loop_config_;
  std::unique_ptr<controller::GraspController> grasp_;
  std::unique_ptr<controller::ControlLoop> loop_;  ///< built by the backend, on its sensor and actuator
  std::vector<IntentLogEntry> intents_;
  double end_s_ = 0.0;  ///< the last tick's time [s]

 private:
  controller::GraspIntent intent_ = controller::GraspIntent::kIdle;
  controller::ControllerTelemetry telemetry_;
  std::vector<ActionTiming> timings_;
  std::vector<PromptEntry> prompts_;
  std::vector<PhaseChange> phases_;
  size_t next_action_ = 0;
  double first_close_s_ = -1.0;
  const char* last_phase_ = nullptr;
  double peak_total_fn_n_ = 0.0;
};

/// RunBackend on the hand over a serial link: a tick on every frame's arrival, and at rate_hz when
/// frames stop (stale detection, commands); live intent from stdin or a FIFO.
class SerialRun final : public BenchRun {
 public:
  SerialRun(const ScenarioConfig& config, const RunOptions& options) : BenchRun(config, options) {
    CheckBenchScript(config, options);
    // A FIFO that cannot be made is refused before anything else is touched.
    if (options.intent_stdin || !options.intent_fifo.empty()) {
      live_ = std::make_unique<hardware::IntentInput>(
          hardware::IntentInputConfig{.read_stdin = options.intent_stdin, .fifo_path = options.intent_fifo});
    }
    if (!config.log.empty() && !std::ofstream(config.log + ".partial", std::ios::trunc)) {
      throw std::invalid_argument("--log " + config.log + ": cannot write this file");
    }
    backend_ = std::make_unique<hardware::HardwareBackend>(config.serial, units_, layout_.name);
    actuator_ = std::make_unique<hardware::HardwareActuator>(*backend_, config.serial);
    if (!config.log.empty()) backend_->link()->EnableTap(16384);
    if (options.latency_frames > 0) actuator_->link()->EnableLatencyRecording(options.latency_frames);
    try {
      backend_->Start();
      actuator_->Start();
    } catch (const std::runtime_error& error) {
      // Missing port, no permission, busy, no HELLO, wrong unit count: refused before running.
      if (!config.log.empty()) fs::remove(config.log + ".partial");
      throw std::invalid_argument(error.what());
    }
    // The hand's proprioception from the link's HANDs (none from a version-1 device: unknown).
    hand_sensor_ = std::make_unique<hardware::SerialHandSensor>(backend_->link());
    loop_ = std::make_unique<controller::ControlLoop>(*backend_, *hand_sensor_, *grasp_, *actuator_, layout_,
                                                      calibration_, loop_config_);
    if (!config.log.empty()) {
      hardware::SerialLink& link = *backend_->link();
      frame_logger_ = std::make_unique<hardware::FrameLogger>(
          config.log, [&link](hardware::TappedFrame* entry) { return link.PopTap(entry); }, layout_,
          calibration_, loop_config_.readout, loop_config_.inversion, backend_->nominal_r0_ohm(),
          HandLogColumns());
    }
  }

  size_t RowCapacity() const override {
    // Without an output directory (`graspbed hw`, possibly until Ctrl-C) no rows are kept.
    if (options_.out_dir.empty()) return 0;
    return static_cast<size_t>(std::ceil(config_.duration_s *
                                         std::max(config_.controller.rate_hz, config_.sensor.sample_rate_hz) *
                                         kSerialRowMargin)) +
           16;
  }
  double duration_s() const override { return config_.duration_s; }

  void Start() override {
    BenchRun::Start();
    start_ = Clock::now();
    if (live_) live_->Start(start_);
    // The operator's cue (and a test's): the session runs and takes intent from now on.
    std::string inputs;
    if (live_ && options_.intent_stdin) inputs += live_->keys() ? "keys c/o/i/q" : "lines on stdin";
    if (!options_.intent_fifo.empty())
      inputs += (inputs.empty() ? "" : ", ") + ("lines on " + options_.intent_fifo);
    char length[32] = "until stopped";
    if (std::isfinite(config_.duration_s)) std::snprintf(length, sizeof(length), "%.1f s", config_.duration_s);
    std::fprintf(stderr, "run: backend serial on %s: session started (%s; live intent: %s)\n",
                 config_.serial.port.c_str(), length,
                 inputs.empty() ? "none, the intent follows the script" : inputs.c_str());
  }

  std::optional<double> NextTick() override {
    hardware::SerialLink& link = *backend_->link();
    link.WaitForFrame(seen_, 1.0 / config_.controller.rate_hz);
    seen_ = link.published();
    const double t = std::chrono::duration<double>(Clock::now() - start_).count();
    end_s_ = t;  // the session's length, also when it ends here
    if (t >= config_.duration_s) return std::nullopt;
    FireScript(t, /*play_intent=*/true);
    hardware::IntentCommand command;
    size_t index = 0;
    while (live_ && live_->Poll(&command, &index)) {
      if (command == hardware::IntentCommand::kQuit) {
        quit_ = true;
        return std::nullopt;
      }
      const controller::GraspIntent next = command == hardware::IntentCommand::kClose ? controller::GraspIntent::kClose
                                           : command == hardware::IntentCommand::kOpen
                                               ? controller::GraspIntent::kOpen
                                               : controller::GraspIntent::kIdle;
      SetIntent(next, "live", -1.0, t);
      intents_.back().live_index = static_cast<long>(index);  // source and time from the input below
    }
    Tick(t);
    return t;
  }

  void Finish(bool completed, double wall_s, RunResult& result) override {
    // Live commands: their source and reception time from the input's own record.
    if (live_) {
      live_->Stop();
      const std::vector<hardware::IntentInputEvent> received = live_->events();
      for (IntentLogEntry& entry : intents_) {
        if (entry.live_index < 0) continue;
        entry.source = received[static_cast<size_t>(entry.live_index)].source;
        entry.received_s = received[static_cast<size_t>(entry.live_index)].received_s;
      }
    }
    hardware::SerialLink& link = *backend_->link();
    connected_at_end_ = link.connected();
    // The clean shutdown order of docs/protocol.md: stream stop, motor off, restore, close.
    backend_->Stop();
    actuator_->Stop();
    if (frame_logger_) frame_logger_->Finish();
    FinishBench(LinkRecord(completed), wall_s, result);
  }

  bool Healthy() const override { return connected_at_end_ && !(frame_logger_ && !frame_logger_->error().empty()); }

  void WriteOutputs(const RunResult& result, const common::SignalLog& log, bool plots,
                    const std::string& dir) override {
    if (plots) WriteBenchPlots(result, log, layout_, /*replay=*/false, dir);
  }

 private:
  // The link's counters and the session's record (summary.json "bench").
  nlohmann::json LinkRecord(bool completed) const {
    hardware::SerialLink& link = *backend_->link();
    const sensor::BackendCounters counters = backend_->counters();
    nlohmann::json bench = {{"backend", BackendName(config_.backend)}, {"controller", grasp_->name()}};
    bench["port"] = config_.serial.port;
    bench["frames"] = counters.frames;
    bench["corrupt"] = counters.corrupt;
    bench["dropped"] = counters.dropped;
    bench["reordered"] = link.reordered();
    bench["unknown_packets"] = counters.unknown_packets;
    bench["reconnects"] = counters.reconnects;
    bench["stale_periods"] = counters.stale_periods;
    bench["sessions"] = counters.sessions;
    bench["motor_commands"] = link.motor_commands_sent();
    const hardware::HandCounters hand = link.hand_counters();
    bench["protocol_version"] = link.protocol_version();
    bench["hand_messages"] = hand.messages;
    bench["hand_malformed"] = hand.malformed;
    bench["hand_dropped"] = hand.dropped;
    bench["hand_late"] = hand.late;
    if (options_.latency_frames > 0) {
      const hardware::LatencySummary latency = actuator_->link()->latency();
      bench["latency"] = {{"frames_answered", latency.frames}, {"not_kept", latency.not_kept},
                          {"p50_us", latency.p50_us},          {"p99_us", latency.p99_us},
                          {"p999_us", latency.p999_us},        {"max_us", latency.max_us},
                          {"over_1ms", latency.over_1ms},      {"over_5ms", latency.over_5ms}};
    }
    bench["connected_at_end"] = connected_at_end_;
    if (!link.last_error().empty()) bench["last_error"] = link.last_error();
    if (frame_logger_) {
      bench["log"] = config_.log;
      bench["log_rows"] = frame_logger_->rows();
      bench["log_rows_lost"] = link.tap_overflows();
      if (!frame_logger_->error().empty()) bench["log_error"] = frame_logger_->error();
    }
    bench["ended_by"] = !completed ? "signal" : quit_ ? "quit" : "duration";
    bench["live_intent"] = live_ ? (live_->keys() ? "keys" : "lines") : "none";
    if (!options_.intent_fifo.empty()) bench["intent_fifo"] = options_.intent_fifo;
    return bench;
  }

  std::unique_ptr<hardware::IntentInput> live_;
  std::unique_ptr<hardware::HardwareBackend> backend_;
  std::unique_ptr<hardware::HardwareActuator> actuator_;
  std::unique_ptr<hardware::SerialHandSensor> hand_sensor_;
  std::unique_ptr<hardware::FrameLogger> frame_logger_;
  Clock::time_point start_;
  uint64_t seen_ = 0;
  bool quit_ = false;
  bool connected_at_end_ = true;
};

/// RunBackend on a recording: its frames tick by tick at their recorded times; its commands, when
/// recorded, compared bit for bit with the new controller's.
class ReplayRun final : public BenchRun {
 public:
  ReplayRun(const ScenarioConfig& config, const RunOptions& options)
      : BenchRun(config, options),
        recording_(hardware::LoadRecordedSession(config.log, units_, HandColumnNames())),
        replay_backend_(recording_, config.sensor.strain_model.nominal.r0_ohm),
        replay_hand_(recording_),
        intent_from_recording_(!recording_.intent.empty()),
        recorded_offset_(BenchRun::Columns().size()) {
    loop_ = std::make_unique<controller::ControlLoop>(replay_backend_, replay_hand_, *grasp_, no_actuator_,
                                                      layout_, calibration_, loop_config_);
  }

  std::vector<std::string> Columns() const override {
    std::vector<std::string> names = BenchRun::Columns();
    names.insert(names.end(), std::begin(kRecordedNames), std::end(kRecordedNames));
    return names;
  }
  std::vector<std::string> TextColumns() const override { return {"recorded_phase"}; }
  size_t RowCapacity() const override { return options_.out_dir.empty() ? 0 : recording_.ticks() + 1; }
  double duration_s() const override { return recording_.time_s.empty() ? 0.0 : recording_.time_s.back(); }

  std::optional<double> NextTick() override {
    if (next_tick_ >= recording_.ticks()) return std::nullopt;
    const size_t k = next_tick_++;
    const double t = recording_.time_s[k];
    FireScript(t, /*play_intent=*/!intent_from_recording_);
    if (intent_from_recording_ && recording_.intent[k] != recorded_intent_) {
      recorded_intent_ = recording_.intent[k];
      const auto next = controller::IntentFromName(recorded_intent_);
      if (next && *next != intent()) SetIntent(*next, "recording", t, t);
    }
    replay_backend_.Seek(k);
    replay_hand_.Seek(k);
    Tick(t);
    if (!recording_.commands.empty()) Compare(t, recording_.commands[k]);
    return t;
  }

  void Record(double time_s, double* cells, const char** texts) override {
    BenchRun::Record(time_s, cells, texts);
    const size_t k = next_tick_ - 1;
    if (!recording_.commands.empty()) {
      const hand::HandCommand& recorded = recording_.commands[k];
      double* cell = cells + recorded_offset_;
      cell[0] = recorded.grip_effort;
      cell[1] = recorded.enable ? 1.0 : 0.0;
      cell[2] = recorded.brake ? 1.0 : 0.0;
      cell[3] = Differs(recorded) ? 1.0 : 0.0;
    }
    texts[0] = recording_.phase.empty() ? "" : recording_.phase[k].c_str();
  }

  void Finish(bool /*completed*/, double wall_s, RunResult& result) override {
    nlohmann::json bench = {{"backend", BackendName(config_.backend)}, {"controller", grasp_->name()}};
    bench["recording"] = recording_.path;
    bench["recording_kind"] = recording_.kind_name();
    bench["recorded_ticks"] = recording_.ticks();
    bench["intent_from"] = intent_from_recording_ ? "recording" : "script";
    bench["commands_recorded"] = !recording_.commands.empty();
    bench["hand_recorded"] = recording_.has_hand();
    if (!recording_.commands.empty()) {
      bench["commands_compared"] = commands_compared_;
      bench["commands_differing"] = commands_differing_;
      bench["max_effort_difference"] = max_effort_difference_;
      bench["first_difference_s"] =
          first_difference_s_ >= 0.0 ? nlohmann::json(first_difference_s_) : nlohmann::json(nullptr);
    }
    FinishBench(std::move(bench), wall_s, result);
  }

  void WriteOutputs(const RunResult& result, const common::SignalLog& log, bool plots,
                    const std::string& dir) override {
    if (plots) WriteBenchPlots(result, log, layout_, /*replay=*/true, dir);
  }

 private:
  // Bit for bit: the same controller on the same input must write the same doubles.
  bool Differs(const hand::HandCommand& recorded) const {
    const hand::HandCommand& now = loop_->command();
    return recorded.grip_effort != now.grip_effort || recorded.enable != now.enable || recorded.brake != now.brake;
  }

  void Compare(double t, const hand::HandCommand& recorded) {
    ++commands_compared_;
    if (Differs(recorded)) {
      ++commands_differing_;
      if (first_difference_s_ < 0.0) first_difference_s_ = t;
    }
    max_effort_difference_ = std::max(max_effort_difference_, std::abs(recorded.grip_effort - loop_->command().grip_effort));
  }

  const hardware::RecordedSession recording_;
  hardware::ReplayBackend replay_backend_;
  ReplayHandSensor replay_hand_;
  NoActuator no_actuator_;
  const bool intent_from_recording_;
  const size_t recorded_offset_;  ///< the recorded command's first cell in the backend's block
  std::string recorded_intent_;
  size_t next_tick_ = 0;
  uint64_t commands_compared_ = 0;
  uint64_t commands_differing_ = 0;
  double max_effort_difference_ = 0.0;
  double first_difference_s_ = -1.0;
};

}  // namespace

std::unique_ptr<RunBackend> MakeSerialRun(const ScenarioConfig& config, const RunOptions& options) {
  return std::make_unique<SerialRun>(config, options);
}

std::unique_ptr<RunBackend> MakeReplayRun(const ScenarioConfig& config, const RunOptions& options) {
  return std::make_unique<ReplayRun>(config, options);
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
