// `graspbed hw`: the shared control loop against the tactile readout and hand electronics over a
// serial link. `graspbed emulate`: the simulated hand behind a pseudo-terminal, speaking the same
// protocol as the device, so `hw` runs end to end without hardware. docs/hardware.md.

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/command_registry.h"
#include "app/stop_signal.h"
#include "common/yaml_map.h"
#include "controller/control_loop.h"
#include "controller/grasp_controller.h"
#include "controller/plugin_loader.h"
#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/layout.h"
#include "sensor/readout.h"
#include "hardware/device_emulator.h"
#include "hardware/hardware_backend.h"
#include "sim/scenario/metrics.h"
#include "sim/scenario/runner.h"
#include "sim/scenario/scenario_config.h"
#include "sim/scenario/script_player.h"
#include "sim/sim_rig.h"

namespace graspbed::app {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// ---- hw ----------------------------------------------------------------------------------------------

/// Everything `hw --config FILE` can set (docs/hardware.md "Configuration").
struct HwRunConfig {
  hardware::HardwareConfig serial;
  /// The controller section exactly as in a scenario (name, params, grip_ceiling_n, rate_hz,
  /// stale_timeout_s), so a controller tuned in simulation runs with the same numbers on the hand.
  /// rate_hz: control ticks per second when frames do not arrive (ticks also follow every frame).
  scenario::ControllerOptions controller;
  controller::ControlLoopConfig loop;  ///< readout, inversion; stale timeout from `controller`
};

/// Reads `hw --config FILE`; an empty path gives the defaults (the reference controller).
HwRunConfig LoadHwRunConfig(const std::string& path) {
  YAML::Node no_file(YAML::NodeType::Map);
  const common::YamlMap root = path.empty() ? common::YamlMap(no_file, "(no --config)", "")
                                            : common::YamlMap::LoadFile(path);
  HwRunConfig config;
  if (const auto section = root.GetMap("serial")) config.serial = hardware::HardwareConfigFromYaml(*section);
  if (const auto section = root.GetMap("controller")) {
    config.controller = scenario::LoadControllerOptions(*section, "grip_slip");
  } else {
    YAML::Node empty(YAML::NodeType::Map);
    config.controller = scenario::LoadControllerOptions(common::YamlMap(empty, root.file(), "controller"),
                                                        "grip_slip");
  }
  config.loop.stale_timeout_s = config.controller.stale_timeout_s;
  if (const auto section = root.GetMap("readout")) config.loop.readout = sensor::LoadReadoutConfig(*section);
  if (const auto section = root.GetMap("inversion")) {
    config.loop.inversion = sensor::LoadInversionConfig(*section);
  }
  root.RejectUnknownKeys();
  return config;
}

/// Writes one CSV row per decoded frame, off the control loop's thread: frames come from the link's
/// tap; this thread runs its own readout and inversion on every one of them (the same configuration
/// and the same re-tare on a new device session as the loop), so no frame is missing from the log
/// even when the loop took only the newest. The file is written as PATH.partial and renamed at the end.
class FrameLogger {
 public:
  FrameLogger(std::string path, hardware::SerialLink& link, const sensor::Layout& layout,
              const sensor::Calibration& calibration, const controller::ControlLoopConfig& config,
              double nominal_r0_ohm)
      : path_(std::move(path)),
        link_(link),
        unit_count_(layout.unit_count()),
        readout_(config.readout, layout.unit_count(), nominal_r0_ohm),
        inversion_(layout, calibration, config.inversion) {
    out_.open(path_ + ".partial", std::ios::trunc);
    if (!out_) throw std::invalid_argument("--log " + path_ + ": cannot write this file");
    out_ << "seq,device_time_s";
    for (int k = 0; k < unit_count_; ++k) {
      // Column names as docs/hardware.md gives them; units: r [Ohm], fn/ft [N], valid 0/1 (docs/hardware.md).
      out_ << ",r1_" << k << ",r2_" << k << ",fn_" << k << ",ft_" << k << ",valid_" << k;
    }
    out_ << '\n';
    thread_ = std::thread([this] { Run(); });
  }
  /// Stops the writer thread; a log that was not Finish()ed stays PATH.partial (never looks complete).
  ~FrameLogger() { StopThread(); }
  FrameLogger(const FrameLogger&) = delete;
  FrameLogger& operator=(const FrameLogger&) = delete;

  /// Writes what is left, closes and renames the file. Call after the link has stopped. On a write
  /// or rename failure the file stays PATH.partial and error() says why.
  void Finish() {
    if (!StopThread()) return;
    out_.flush();
    out_.close();
    if (out_.fail()) {
      error_ = "writing " + path_ + ".partial failed (disk full?); left as .partial";
      return;
    }
    std::error_code rename_error;
    std::filesystem::rename(path_ + ".partial", path_, rename_error);
    if (rename_error) error_ = "renaming " + path_ + ".partial failed: " + rename_error.message();
  }
  uint64_t rows() const { return rows_; }
  /// Empty unless Finish() could not complete the file.
  const std::string& error() const { return error_; }

 private:
  /// Joins the writer thread once it has drained the tap; false when it was already stopped.
  bool StopThread() {
    if (!thread_.joinable()) return false;
    done_ = true;
    thread_.join();
    return true;
  }

  void Run() {
    for (;;) {
      const bool last_round = done_.load();
      bool any = false;
      while (link_.PopTap(&entry_)) {
        Write();
        any = true;
      }
      if (last_round) return;
      if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  void Write() {
    if (entry_.session != session_) {
      session_ = entry_.session;
      readout_.Reset();
    }
    readout_.Process(entry_.frame, &readout_frame_);
    inversion_.Invert(readout_frame_, &state_);
    char buffer[96];
    std::snprintf(buffer, sizeof(buffer), "%u,%.6f", entry_.frame.sequence, entry_.frame.time_s);
    out_ << buffer;
    for (int k = 0; k < unit_count_; ++k) {
      std::snprintf(buffer, sizeof(buffer), ",%.3f,%.3f,%.5f,%.5f,%d", entry_.frame.r1_ohm[k],
                    entry_.frame.r2_ohm[k], state_.fn_n[k], state_.ft_n[k],
                    state_.validity[k] == sensor::UnitValidity::kValid ? 1 : 0);
      out_ << buffer;
    }
    out_ << '\n';
    ++rows_;
  }

  std::string path_;
  hardware::SerialLink& link_;
  int unit_count_;
  sensor::Readout readout_;
  sensor::Inversion inversion_;
  hardware::TappedFrame entry_;
  sensor::ReadoutFrame readout_frame_;
  sensor::TactileState state_;
  uint64_t session_ = 1;
  std::ofstream out_;
  std::thread thread_;
  std::atomic<bool> done_{false};
  std::atomic<uint64_t> rows_{0};
  std::string error_;
};

struct HwOptions {
  std::string port;
  std::string config;
  std::string layout;
  std::string calibration;
  std::string controller;  ///< empty: the config's (default grip_slip)
  std::vector<std::string> params;  ///< NAME=VALUE controller parameters
  std::string intent = "close";
  double duration_s = 0.0;
  int tare_frames = -1;
  std::string log;
  bool json = false;
};

controller::GraspIntent ParseIntent(const std::string& text) {
  if (text == "close") return controller::GraspIntent::kClose;
  if (text == "open") return controller::GraspIntent::kOpen;
  if (text == "idle") return controller::GraspIntent::kIdle;
  throw std::invalid_argument("--intent " + text + ": must be close, open or idle");
}

void RunHw(const HwOptions& options) {
  HwRunConfig config = LoadHwRunConfig(options.config);
  if (!options.port.empty()) config.serial.port = options.port;
  if (config.serial.port.empty()) {
    throw std::invalid_argument("hw: no serial port: give --port PATH or serial.port in --config");
  }
  if (options.tare_frames >= 0) config.loop.readout.baseline_frames = options.tare_frames;
  config.serial.Validate();
  config.loop.Validate();
  const controller::GraspIntent intent = ParseIntent(options.intent);
  const sensor::Layout layout =
      sensor::LoadLayout(options.layout.empty() ? sensor::DefaultLayoutPath() : options.layout);
  const int units = layout.unit_count();
  const sensor::Calibration calibration = options.calibration.empty()
                                              ? sensor::PaperCalibration(units)
                                              : sensor::LoadCalibration(options.calibration, units);
  // --controller picks another controller than the config's; the config's parameters belong to its own.
  scenario::ControllerOptions& chosen = config.controller;
  const std::string requested = controller::ResolvePluginName(options.controller, ".");
  if (!requested.empty() && requested != chosen.name) {
    chosen.name = requested;
    chosen.params.clear();
    for (const auto& parameter : controller::ControllerParameters(chosen.name)) {
      chosen.params[parameter.name] = parameter.default_value;
    }
  }
  for (const std::string& assignment : options.params) {
    const size_t equals = assignment.find('=');
    const std::string number = equals == std::string::npos ? "" : assignment.substr(equals + 1);
    char* end = nullptr;
    const double value = std::strtod(number.c_str(), &end);
    if (equals == 0 || number.empty() || end != number.c_str() + number.size() || !std::isfinite(value)) {
      throw std::invalid_argument("--param " + assignment + ": expected NAME=NUMBER");
    }
    chosen.params[assignment.substr(0, equals)] = value;
  }
  // The factory names an unknown parameter, a value out of its range or a cross-field conflict.
  std::unique_ptr<controller::GraspController> grasp = controller::MakeController(chosen.name, chosen.params);
  if (chosen.grip_ceiling_n > 0.0) grasp->SetGripCeiling(chosen.grip_ceiling_n);
  // The log must be writable before the port is touched (refused, like all bad input, up front).
  if (!options.log.empty() && !std::ofstream(options.log + ".partial", std::ios::trunc)) {
    throw std::invalid_argument("--log " + options.log + ": cannot write this file");
  }

  hardware::HardwareBackend backend(config.serial, units, layout.name);
  hardware::HardwareActuator actuator(backend, config.serial);
  hardware::SerialLink& link = *backend.link();
  if (!options.log.empty()) link.EnableTap(16384);
  // Before the port is opened: Ctrl-C while waiting for HELLO still ends with the port restored.
  StopSignalGuard signals;
  try {
    backend.Start();
    actuator.Start();
  } catch (const std::runtime_error& error) {
    // Missing port, no permission, busy, no HELLO, wrong unit count: refused before running.
    if (!options.log.empty()) std::filesystem::remove(options.log + ".partial");
    throw std::invalid_argument(error.what());
  }
  controller::ControlLoop loop(backend, *grasp, actuator, layout, calibration, config.loop);
  std::unique_ptr<FrameLogger> logger;
  if (!options.log.empty()) {
    logger = std::make_unique<FrameLogger>(options.log, link, layout, calibration, config.loop,
                                           backend.nominal_r0_ohm());
  }

  // Tick on every frame arrival, and at rate_hz when frames stop (stale detection, commands).
  const double period_s = 1.0 / chosen.rate_hz;
  const Clock::time_point start = Clock::now();
  uint64_t seen = 0;
  bool intent_given = false;
  double peak_total_fn_n = 0.0;
  while (!StopRequested().load()) {
    if (options.duration_s > 0.0 && SecondsSince(start) >= options.duration_s) break;
    link.WaitForFrame(seen, period_s);
    seen = link.published();
    loop.Tick(SecondsSince(start));
    // The first baseline_frames frames are the tare (no load on the fingertip); then the intent.
    if (!intent_given && loop.counters().frames >= static_cast<uint64_t>(config.loop.readout.baseline_frames)) {
      grasp->SetIntent(intent);
      intent_given = true;
    }
    if (!loop.state().stale) peak_total_fn_n = std::max(peak_total_fn_n, loop.state().total_fn_n);
  }
  const double run_s = SecondsSince(start);
  const bool connected_at_end = link.connected();  // before Stop() closes the port
  // The clean shutdown order of docs/protocol.md: stream stop, motor off (both sent by the link's
  // shutdown when the motor shares the port; a separate motor port is switched off just after),
  // restore, close.
  backend.Stop();
  actuator.Stop();
  if (logger) logger->Finish();

  const sensor::BackendCounters counters = backend.counters();
  const controller::LoopCounters& ticks = loop.counters();
  nlohmann::json summary = {
      {"port", config.serial.port},
      {"layout", layout.name},
      {"controller", grasp->name()},
      {"duration_s", run_s},
      {"frames", counters.frames},
      {"corrupt", counters.corrupt},
      {"dropped", counters.dropped},
      {"unknown_packets", counters.unknown_packets},
      {"reconnects", counters.reconnects},
      {"stale_periods", counters.stale_periods},
      {"sessions", counters.sessions},
      {"ticks", ticks.ticks},
      {"loop_frames", ticks.frames},
      {"stale_ticks", ticks.stale_ticks},
      {"disconnected_ticks", ticks.disconnected_ticks},
      {"actuator_failures", ticks.actuator_failures},
      {"retares", ticks.retares},
      {"motor_commands", link.motor_commands_sent()},
      {"tare_frames", config.loop.readout.baseline_frames},
      {"peak_total_fn_n", peak_total_fn_n},
      {"final_total_fn_n", loop.state().total_fn_n},
      {"final_valid_units", loop.state().valid_count},
      {"interrupted", StopRequested().load()},
  };
  if (logger) {
    summary["log"] = options.log;
    summary["log_rows"] = logger->rows();
    summary["log_rows_lost"] = link.tap_overflows();
    if (!logger->error().empty()) summary["log_error"] = logger->error();
  }
  // The run failed (exit 1) when the device was gone at the end or the log could not be completed.
  summary["connected_at_end"] = connected_at_end;
  const bool failed = !connected_at_end || (logger && !logger->error().empty());
  if (!link.last_error().empty()) summary["last_error"] = link.last_error();
  if (options.json) {
    std::cout << summary.dump(2) << '\n';
  } else {
    std::cout << "hw " << config.serial.port << ": " << run_s << " s, " << counters.frames << " frames, "
              << counters.corrupt << " corrupt, " << counters.dropped << " dropped, " << counters.unknown_packets
              << " unknown, " << counters.reconnects << " reconnects, " << counters.stale_periods
              << " stale periods, " << counters.sessions << " sessions; peak grip " << peak_total_fn_n
              << " N (sensed)" << (connected_at_end ? "" : "; device DISCONNECTED at the end")
              << (logger && !logger->error().empty() ? "; log: " + logger->error() : "") << '\n';
  }
  if (failed) throw CLI::RuntimeError(kExitFailed);  // main() returns the code silently
}

// ---- emulate -----------------------------------------------------------------------------------------

struct EmulateOptions {
  std::string link;
  std::string scenario;
  double duration_s = -1.0;
  bool json = false;
};

/// The simulated hand behind the emulator's callbacks. The scenario's script moves the wrist and the
/// object; grasp intent belongs to the host's controller, so close/open actions are not played
/// (ScriptPlayer gives them to a controller nobody ticks). Simulated time starts with the first
/// STREAM_CONTROL start and advances one sensor period per emulator tick. The outcome is scored as
/// `graspbed run` scores it (MetricsTracker on the ground truth, once per frame) while the host is in
/// control, and frozen when the host first stops streaming (stream stop or closing the port).
class SimulatedDevice {
 public:
  SimulatedDevice(const scenario::ScenarioConfig& config, const sensor::Layout& layout)
      : config_(config),
        rig_(layout, sensor::PaperCalibration(layout.unit_count()), RigConfig(config),
             controller::MakeController("open_loop", {})),
        player_(config),
        tracker_(config.metrics, config.scene.object.crush_limit_n, config.sensor.inversion.contact_threshold_n),
        period_s_(1.0 / config.sensor.sample_rate_hz),
        wall_start_(Clock::now()) {
    player_.Start(rig_);
    initial_object_z_m_ = rig_.simulation().truth().object_position_m[2];
    // The tracker sees no estimates (the host has them): a stale state keeps it to ground truth.
    no_estimate_.stale = true;
  }

  static sim::SimRigConfig RigConfig(const scenario::ScenarioConfig& config) {
    sim::SimRigConfig rig;
    rig.scene = config.scene;
    rig.backend.sample_rate_hz = config.sensor.sample_rate_hz;
    rig.backend.latency_s = config.sensor.latency_s;
    rig.backend.max_latency_s = scenario::MaxLatencyS(config);  // add_latency actions in the script
    rig.backend.drop_probability = 0.0;  // link faults are the emulator's business here
    rig.backend.strain_model = config.sensor.strain_model;
    rig.loop.readout = config.sensor.readout;
    rig.loop.inversion = config.sensor.inversion;
    rig.seed = config.seed;
    return rig;
  }

  /// Emulator thread: advances the simulation by one sensor period once streaming has begun.
  void Frame(bool streaming, sensor::RawFrame* frame) {
    if (streaming) started_ = true;
    if (started_ && !streaming) host_done_ = true;
    if (started_) {
      target_s_ += period_s_;
      sim::Simulation& simulation = rig_.simulation();
      while (simulation.time_s() < target_s_) {
        player_.Update(simulation.time_s(), rig_);
        simulation.Step();
        rig_.backend().Poll();
      }
      const sim::GroundTruth truth = simulation.truth();
      std::lock_guard lock(mutex_);
      sim_time_s_ = simulation.time_s();
      if (!host_done_) {
        scenario::TickSample sample;
        sample.time_s = sim_time_s_;
        sample.intent = host_intent_;  // the host's controller closes and opens, not the script
        sample.truth = &truth;
        sample.state = &no_estimate_;
        tracker_.Update(sample);
        outcome_time_s_ = sim_time_s_;
        outcome_wall_s_ = SecondsSince(wall_start_);
        peak_squeeze_n_ = std::max(peak_squeeze_n_, truth.object_squeeze_n);
        last_truth_ = truth;
        physics_fault_ = rig_.simulation().fault();
      }
    }
    sensor::RawFrame fresh;
    while (rig_.backend().Read(&fresh) == sensor::ReadStatus::kOk) latest_ = fresh;
    if (latest_.unit_count == 0) {  // nothing sampled yet: unloaded gauges
      latest_.unit_count = frame->unit_count;
      latest_.r1_ohm.fill(rig_.backend().nominal_r0_ohm());
      latest_.r2_ohm.fill(rig_.backend().nominal_r0_ohm());
    }
    frame->flags = latest_.flags;
    std::copy_n(latest_.r1_ohm.begin(), frame->unit_count, frame->r1_ohm.begin());
    std::copy_n(latest_.r2_ohm.begin(), frame->unit_count, frame->r2_ohm.begin());
  }

  /// Emulator thread: the motor state the device drives.
  void Motor(const hardware::EmulatedMotor& motor) {
    rig_.actuator().Write({.grip_effort = motor.effort, .enable = motor.enable, .brake = motor.brake});
    // What the host means, as far as the motor shows it: closing effort = grasp, opening effort =
    // release. The motor going off (watchdog, stream loss) is no decision of the host's.
    if (motor.enable && motor.effort > 0.0) host_intent_ = controller::GraspIntent::kClose;
    if (motor.enable && motor.effort < 0.0) host_intent_ = controller::GraspIntent::kOpen;
    if (host_intent_ == controller::GraspIntent::kClose) {
      std::lock_guard lock(mutex_);
      if (host_close_s_ < 0.0) host_close_s_ = rig_.simulation().time_s();
    }
  }

  /// Ground truth and the metrics of `graspbed run` (same keys) as the host left the hand.
  nlohmann::json Summary() const {
    std::lock_guard lock(mutex_);
    scenario::RunResult result;
    result.config = config_;
    result.metrics = tracker_.Finish(outcome_time_s_, outcome_wall_s_, player_.first_close_time_s());
    result.metrics.physics_fault = physics_fault_.occurred;
    result.metrics.physics_fault_cause = physics_fault_.occurred ? physics_fault_.cause_text() : "";
    result.metrics.physics_fault_time_s = physics_fault_.time_s;
    nlohmann::json metrics = scenario::SummaryJson(result)["metrics"];
    // The host's controller, not the emulator, sees slip flags and estimates: leave out what it
    // cannot score.
    for (const char* key : {"slip_detect_latency_ms", "false_slip_per_min", "fn_rmse_n", "ft_rmse_n",
                            "missed_slip_events", "controller_slip_flags", "false_slip_flags",
                            "estimation_samples"}) {
      metrics.erase(key);
    }
    return {
        {"sim_time_s", outcome_time_s_},
        {"host_close_time_s", host_close_s_ >= 0.0 ? nlohmann::json(host_close_s_) : nlohmann::json(nullptr)},
        {"object_lift_m", last_truth_.object_position_m[2] - initial_object_z_m_},
        {"object_height_above_table_m", last_truth_.object_height_above_table_m},
        {"peak_squeeze_n", peak_squeeze_n_},
        {"final_squeeze_n", last_truth_.object_squeeze_n},
        {"finger_contacts", last_truth_.finger_contacts},
        {"thumb_contacts", last_truth_.thumb_contacts},
        {"metrics", metrics},
    };
  }
  bool started() const { return started_.load(); }
  /// True once a host that streamed has stopped (the outcome is frozen).
  bool host_done() const { return host_done_.load(); }
  double sim_time_s() const {
    std::lock_guard lock(mutex_);
    return sim_time_s_;
  }

 private:
  scenario::ScenarioConfig config_;
  sim::SimRig rig_;
  scenario::ScriptPlayer player_;
  scenario::MetricsTracker tracker_;
  sensor::TactileState no_estimate_;
  double period_s_;
  Clock::time_point wall_start_;
  double target_s_ = 0.0;
  std::atomic<bool> started_{false};
  std::atomic<bool> host_done_{false};
  controller::GraspIntent host_intent_ = controller::GraspIntent::kIdle;  ///< emulator thread only
  sensor::RawFrame latest_;
  double initial_object_z_m_ = 0.0;
  mutable std::mutex mutex_;  // guards the values below, read by the main thread
  double sim_time_s_ = 0.0;
  double outcome_time_s_ = 0.0;
  double outcome_wall_s_ = 0.0;
  double peak_squeeze_n_ = 0.0;
  double host_close_s_ = -1.0;  // simulated time of the host's first closing command; < 0 none
  sim::GroundTruth last_truth_;
  sim::PhysicsFault physics_fault_;
};

void RunEmulate(const EmulateOptions& options) {
  scenario::ScenarioConfig config;
  if (!options.scenario.empty()) {
    config = scenario::LoadScenario(options.scenario);
  } else {
    config.name = "plain";
    config.duration_s = 0.0;  // no scenario: until stopped
  }
  const sensor::Layout layout = sensor::LoadLayout(scenario::ResolveLayoutPath(config));
  SimulatedDevice device(config, layout);

  hardware::EmulatorConfig emulator_config;
  emulator_config.link_path = options.link;
  emulator_config.unit_count = layout.unit_count();
  emulator_config.frame_rate_hz = static_cast<int>(std::lround(config.sensor.sample_rate_hz));
  emulator_config.nominal_r0_ohm = config.sensor.strain_model.nominal.r0_ohm;
  hardware::DeviceEmulator emulator(
      emulator_config,
      [&device](double, bool streaming, sensor::RawFrame* frame) { device.Frame(streaming, frame); },
      [&device](const hardware::EmulatedMotor& motor) { device.Motor(motor); });
  StopSignalGuard signals;
  emulator.Start();
  std::cerr << "emulate: device '" << config.name << "' (" << layout.unit_count() << " units) at "
            << options.link << " -> " << emulator.slave_path() << "; waiting for a host\n";
  // Ends after `duration` simulated seconds from the first stream start (default: the scenario's),
  // when the host stops streaming (with a scenario: one host run is one trial), or on SIGINT/SIGTERM.
  const double duration_s = options.duration_s >= 0.0 ? options.duration_s : config.duration_s;
  const bool one_trial = !options.scenario.empty();
  std::string ended_by = "signal";
  while (!StopRequested().load()) {
    if (duration_s > 0.0 && device.started() && device.sim_time_s() >= duration_s) {
      ended_by = "duration";
      break;
    }
    if (one_trial && device.host_done()) {
      ended_by = "host_stopped";
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const hardware::EmulatorStats stats = emulator.stats();
  emulator.Stop();

  nlohmann::json summary = device.Summary();
  summary["scenario"] = config.name;
  summary["link"] = options.link;
  summary["ended_by"] = ended_by;
  summary["frames_sent"] = stats.frames_sent;
  summary["frames_overflowed"] = stats.frames_overflowed;
  summary["hellos_sent"] = stats.hellos_sent;
  summary["motor_commands"] = stats.motor_commands;
  summary["max_command_interval_s"] = stats.max_command_interval_s;
  summary["watchdog_trips"] = stats.watchdog_trips;
  summary["stream_starts"] = stats.stream_starts;
  summary["connects"] = stats.connects;
  summary["commands_before_hello"] = stats.commands_before_hello;
  summary["host_corrupt"] = stats.host_corrupt;
  if (options.json) {
    std::cout << summary.dump(2) << '\n';
    return;
  }
  const nlohmann::json& metrics = summary["metrics"];
  std::cout << "emulate " << options.link << " (" << ended_by << "): " << summary["sim_time_s"].get<double>()
            << " s simulated, " << stats.frames_sent << " frames sent, " << stats.motor_commands
            << " motor commands, " << stats.watchdog_trips << " watchdog trips; object "
            << (!metrics["grasped"].get<bool>() ? "not grasped"
                : metrics["dropped"].get<bool>() ? "DROPPED"
                                                 : "held")
            << ", lifted "
            << 1e3 * summary["object_lift_m"].get<double>() << " mm, peak grip "
            << metrics["peak_grip_n"].get<double>() << " N, slip " << metrics["max_slip_mm"].get<double>()
            << " mm\n";
}

void AddHwCommands(CLI::App& root) {
  auto hw_options = std::make_shared<HwOptions>();
  CLI::App* hw = root.add_subcommand(
      "hw", "Run a controller against the tactile readout and hand over a serial link (or the emulator)");
  hw->add_option("--port", hw_options->port, "Serial device, e.g. /dev/ttyACM0 or an emulator link");
  hw->add_option("--config", hw_options->config,
                 "YAML with serial:, controller:, readout:, inversion: sections (docs/hardware.md)")
      ->check(CLI::ExistingFile);
  hw->add_option("--layout", hw_options->layout, "Layout file (default: sensor/layouts/default_20.yaml)");
  hw->add_option("--calibration", hw_options->calibration, "Calibration file (default: paper values)");
  hw->add_option("--controller", hw_options->controller,
                 "Controller: a built-in name or plugin:LIBRARY (default: the controller of --config, else grip_slip)");
  hw->add_option("--param", hw_options->params,
                 "Controller parameter NAME=VALUE, as in a scenario's controller.params (repeatable)");
  hw->add_option("--intent", hw_options->intent, "Intent once tared: close, open or idle")->capture_default_str();
  hw->add_option("--duration", hw_options->duration_s, "Stop cleanly after S seconds (0: until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  hw->add_option("--tare-frames", hw_options->tare_frames,
                 "Frames averaged for the tare baseline at start (default: readout.baseline_frames = 100)")
      ->check(CLI::PositiveNumber);
  hw->add_option("--log", hw_options->log, "CSV with one row per decoded frame");
  hw->add_flag("--json", hw_options->json, "Print a JSON summary at the end");
  hw->callback([hw_options] { RunHw(*hw_options); });

  auto emulate_options = std::make_shared<EmulateOptions>();
  CLI::App* emulate = root.add_subcommand(
      "emulate", "Serve the simulated hand as a serial device on a pseudo-terminal (symlinked at --link)");
  emulate->add_option("--link", emulate_options->link, "Path of the symlink to create")->required();
  emulate->add_option("scenario", emulate_options->scenario, "Scenario YAML (wrist and object script)")
      ->check(CLI::ExistingFile);
  emulate->add_option("--duration", emulate_options->duration_s,
                      "Simulated seconds after the host starts streaming (default: the scenario's; "
                      "without a scenario, until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  emulate->add_flag("--json", emulate_options->json,
                    "Print a JSON summary at the end: ground truth and run metrics as the host left the hand");
  emulate->callback([emulate_options] { RunEmulate(*emulate_options); });
}

const bool kRegistered = RegisterCommands(&AddHwCommands);

}  // namespace
}  // namespace graspbed::app
