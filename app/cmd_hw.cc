// `graspbed hw`: a session on the hand without a scenario -- a thin alias of `graspbed run --backend
// serial` (one intent once tared, its own --config, no outputs but the frame log). `graspbed emulate`: the
// simulated hand behind a pseudo-terminal, speaking the same protocol as the device, so `hw` runs end to end
// without hardware. docs/hardware.md.

#include <sched.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
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
#include "sim/scenario/emulated_hand.h"
#include "sim/scenario/runner.h"
#include "sim/scenario/scenario_config.h"

namespace graspbed::app {
namespace {

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
  const common::YamlMap root =
      path.empty() ? common::YamlMap(no_file, "(no --config)", "") : common::YamlMap::LoadFile(path);
  HwRunConfig config;
  if (const auto section = root.GetMap("serial")) config.serial = hardware::LoadHardwareConfig(*section);
  if (const auto section = root.GetMap("controller")) {
    config.controller = scenario::LoadControllerOptions(*section, "grip_slip");
  } else {
    YAML::Node empty(YAML::NodeType::Map);
    config.controller =
        scenario::LoadControllerOptions(common::YamlMap(empty, root.file(), "controller"), "grip_slip");
  }
  config.loop.stale_timeout_s = config.controller.stale_timeout_s;
  if (const auto section = root.GetMap("readout")) config.loop.readout = sensor::LoadReadoutConfig(*section);
  if (const auto section = root.GetMap("inversion")) {
    config.loop.inversion = sensor::LoadInversionConfig(*section);
  }
  root.RejectUnknownKeys();
  return config;
}

struct HwOptions {
  std::string port;
  std::string config;
  std::string layout;
  std::string calibration;
  std::string controller;           ///< empty: the config's (default grip_slip)
  std::vector<std::string> params;  ///< NAME=VALUE controller parameters
  std::string intent = "close";
  double duration_s = 0.0;
  int tare_frames = -1;
  std::string log;
  bool json = false;
  bool latency_report = false;
  int realtime_priority = 0;
};

/// Runs this thread, and the link threads it starts from now on (they inherit it), under SCHED_FIFO
/// at `priority` (1-99), so other processes on the cores cannot delay a frame's answer.
/// @throws std::runtime_error naming what the machine must allow when it is refused (exit 1).
void UseRealTimePriority(int priority) {
  sched_param parameters{};
  parameters.sched_priority = priority;
  if (::sched_setscheduler(0, SCHED_FIFO, &parameters) != 0) {
    const int error = errno;
    throw std::runtime_error(
        "--realtime-priority " + std::to_string(priority) + ": SCHED_FIFO refused (" + std::strerror(error) +
        "): needs the CAP_SYS_NICE capability (root has it unless a container drops it; for a user, setcap "
        "cap_sys_nice+ep on the binary) or an rtprio limit of at least " + std::to_string(priority) +
        " for your user (/etc/security/limits.conf)");
  }
}

/// Frames whose loop latency `hw --latency-report` keeps (17 min at 1 kHz, 8 MB).
constexpr size_t kLatencyReportFrames = size_t{1} << 20;

controller::GraspIntent ParseIntent(const std::string& text) {
  const std::optional<controller::GraspIntent> intent = controller::IntentFromName(text);
  if (!intent) throw std::invalid_argument("--intent " + text + ": must be close, open or idle");
  return *intent;
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
  controller::MakeController(chosen.name, chosen.params);

  // The session is a scenario on backend serial with one intent, given once the tare is done (the
  // first baseline_frames frames at the sensor's rate), and no outputs but the frame log.
  scenario::ScenarioConfig scenario;
  scenario.name = "hw";
  scenario.backend = scenario::Backend::kSerial;
  scenario.serial = config.serial;
  scenario.log = options.log;
  scenario.controller = chosen;
  scenario.sensor.layout = options.layout.empty() ? sensor::DefaultLayoutPath() : options.layout;
  scenario.sensor.readout = config.loop.readout;
  scenario.sensor.inversion = config.loop.inversion;
  scenario.duration_s =
      options.duration_s > 0.0 ? options.duration_s : std::numeric_limits<double>::infinity();
  scenario::Action action;
  action.kind = intent == controller::GraspIntent::kClose  ? scenario::ActionKind::kClose
                : intent == controller::GraspIntent::kOpen ? scenario::ActionKind::kOpen
                                                           : scenario::ActionKind::kIdle;
  action.at_s = config.loop.readout.baseline_frames / scenario.sensor.sample_rate_hz;
  scenario.script = {action};
  scenario::RunOptions run;
  run.stop = &StopRequested();
  run.calibration = calibration;
  if (options.latency_report) run.latency_frames = kLatencyReportFrames;
  if (options.realtime_priority > 0) UseRealTimePriority(options.realtime_priority);
  // Before the port is opened: Ctrl-C while waiting for HELLO still ends with the port restored.
  StopSignalGuard signals;
  const scenario::RunResult result = scenario::RunScenario(scenario, run);

  // hw's own summary keys (docs/hardware.md), from the run's.
  const nlohmann::json& bench = result.bench;
  nlohmann::json summary = {{"port", config.serial.port},
                            {"layout", layout.name},
                            {"controller", bench.at("controller")},
                            {"duration_s", result.metrics.sim_s}};
  for (const char* key : {"frames", "corrupt", "dropped", "unknown_packets", "reconnects", "stale_periods",
                          "sessions", "ticks", "loop_frames", "stale_ticks", "disconnected_ticks",
                          "actuator_failures", "retares", "motor_commands"}) {
    summary[key] = bench.at(key);
  }
  summary["tare_frames"] = config.loop.readout.baseline_frames;
  summary["peak_total_fn_n"] = bench.at("peak_est_total_fn_n");
  summary["final_total_fn_n"] = bench.at("final_est_total_fn_n");
  summary["final_valid_units"] = bench.at("final_valid_units");
  summary["interrupted"] = !result.completed;
  for (const char* key : {"log", "log_rows", "log_rows_lost", "log_error", "last_error"}) {
    if (bench.contains(key)) summary[key] = bench.at(key);
  }
  if (bench.contains("latency")) summary["latency"] = bench.at("latency");
  const bool connected_at_end = bench.at("connected_at_end").get<bool>();
  summary["connected_at_end"] = connected_at_end;
  const std::string log_error = bench.value("log_error", std::string());
  if (options.json) {
    std::cout << summary.dump(2) << '\n';
  } else {
    std::cout << "hw " << config.serial.port << ": " << result.metrics.sim_s << " s, " << bench.at("frames")
              << " frames, " << bench.at("corrupt") << " corrupt, " << bench.at("dropped") << " dropped, "
              << bench.at("unknown_packets") << " unknown, " << bench.at("reconnects") << " reconnects, "
              << bench.at("stale_periods") << " stale periods, " << bench.at("sessions")
              << " sessions; peak grip " << bench.at("peak_est_total_fn_n") << " N (sensed)"
              << (connected_at_end ? "" : "; device DISCONNECTED at the end")
              << (log_error.empty() ? "" : "; log: " + log_error) << '\n';
    if (bench.contains("latency")) {
      const nlohmann::json& latency = bench.at("latency");
      std::printf("loop latency (frame decoded -> its command written), %llu frames: p50 %.0f us, p99 %.0f us, "
                  "p99.9 %.0f us, max %.0f us; %llu over 1 ms, %llu over 5 ms\n",
                  latency.at("frames_answered").get<unsigned long long>(), latency.at("p50_us").get<double>(),
                  latency.at("p99_us").get<double>(), latency.at("p999_us").get<double>(),
                  latency.at("max_us").get<double>(), latency.at("over_1ms").get<unsigned long long>(),
                  latency.at("over_5ms").get<unsigned long long>());
    }
  }
  // The run failed (exit 1) when the device was gone at the end or the log could not be completed.
  if (!connected_at_end || !log_error.empty())
    throw CLI::RuntimeError(kExitFailed);  // main() returns it silently
}

// ---- emulate -----------------------------------------------------------------------------------------

struct EmulateOptions {
  std::string link;
  std::string scenario;
  double duration_s = -1.0;
  bool json = false;
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
  scenario::EmulatedHand device(config, layout);

  hardware::EmulatorConfig emulator_config;
  emulator_config.link_path = options.link;
  emulator_config.unit_count = layout.unit_count();
  emulator_config.frame_rate_hz = static_cast<int>(std::lround(config.sensor.sample_rate_hz));
  emulator_config.nominal_r0_ohm = config.sensor.strain_model.nominal.r0_ohm;
  hardware::DeviceEmulator emulator(
      emulator_config,
      [&device](double, bool streaming, sensor::RawFrame* frame) { device.Frame(streaming, frame); },
      [&device](const hardware::EmulatedMotor& motor) {
        device.Motor({.grip_effort = motor.effort, .enable = motor.enable, .brake = motor.brake});
      });
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
            << (!metrics["grasped"].get<bool>()  ? "not grasped"
                : metrics["dropped"].get<bool>() ? "DROPPED"
                                                 : "held")
            << ", lifted " << 1e3 * summary["object_lift_m"].get<double>() << " mm, peak grip "
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
  hw->add_option(
      "--controller", hw_options->controller,
      "Controller: a built-in name or plugin:LIBRARY (default: the controller of --config, else grip_slip)");
  hw->add_option("--param", hw_options->params,
                 "Controller parameter NAME=VALUE, as in a scenario's controller.params (repeatable)");
  hw->add_option("--intent", hw_options->intent, "Intent once tared: close, open or idle")
      ->capture_default_str();
  hw->add_option("--duration", hw_options->duration_s, "Stop cleanly after S seconds (0: until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  hw->add_option("--tare-frames", hw_options->tare_frames,
                 "Frames averaged for the tare baseline at start (default: readout.baseline_frames = 100)")
      ->check(CLI::PositiveNumber);
  hw->add_option("--log", hw_options->log, "CSV with one row per decoded frame");
  hw->add_flag("--json", hw_options->json, "Print a JSON summary at the end");
  hw->add_option("--realtime-priority", hw_options->realtime_priority,
                 "Run the loop and the serial threads under SCHED_FIFO at this priority (1-99), so a busy "
                 "machine cannot delay the answer to a frame; needs root, CAP_SYS_NICE or an rtprio limit")
      ->check(CLI::Range(1, 99));
  hw->add_flag("--latency-report", hw_options->latency_report,
               "Measure the loop latency, from each frame's decode to the write of the command that answers "
               "it, and print its p50, p99, p99.9 and max (JSON: \"latency\")");
  hw->callback([hw_options] { RunHw(*hw_options); });

  auto emulate_options = std::make_shared<EmulateOptions>();
  CLI::App* emulate = root.add_subcommand(
      "emulate", "Serve the simulated hand as a serial device on a pseudo-terminal (symlinked at --link)");
  emulate->add_option("--link", emulate_options->link, "Path of the symlink to create")->required();
  emulate->add_option("scenario", emulate_options->scenario, "Scenario YAML (wrist and object script)")
      ->check(CLI::ExistingFile);
  emulate
      ->add_option("--duration", emulate_options->duration_s,
                   "Simulated seconds after the host starts streaming (default: the scenario's; "
                   "without a scenario, until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  emulate->add_flag(
      "--json", emulate_options->json,
      "Print a JSON summary at the end: ground truth and run metrics as the host left the hand");
  emulate->callback([emulate_options] { RunEmulate(*emulate_options); });
}

const bool kRegistered = RegisterCommands(&AddHwCommands);

}  // namespace
}  // namespace graspbed::app
