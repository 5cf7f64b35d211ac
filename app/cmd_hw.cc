// `graspbed hw`: a session on the hand without a scenario -- a thin alias of `graspbed run --backend
// serial` (one intent once tared, its own --config, no outputs but the frame log). `graspbed emulate`: the
// simulated hand behind a pseudo-terminal, speaking the same protocol as the device, so `hw` runs end to end
// without hardware. docs/hardware.md.

#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

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
#include <iterator>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/command_registry.h"
#include "app/stop_signal.h"
#include "common/process.h"
#include "common/yaml_map.h"
#include "controller/control_loop.h"
#include "controller/grasp_controller.h"
#include "controller/plugin_loader.h"
#include "hardware/device_emulator.h"
#include "hardware/hardware_backend.h"
#include "hardware/soak.h"
#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/layout.h"
#include "sensor/readout.h"
#include "testbed/emulated_hand.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"

namespace graspbed::app {
namespace {

// ---- hw ----------------------------------------------------------------------------------------------

/// Everything `hw --config FILE` can set (docs/hardware.md "Configuration").
struct HwRunConfig {
  hardware::HardwareConfig serial;
  /// The controller section exactly as in a scenario (name, params, grip_ceiling_n, rate_hz,
  /// stale_timeout_s), so a controller tuned in simulation runs with the same numbers on the hand.
  /// rate_hz: control ticks per second when frames do not arrive (ticks also follow every frame).
  testbed::ControllerOptions controller;
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
    config.controller = testbed::LoadControllerOptions(*section, "grip_slip");
  } else {
    YAML::Node empty(YAML::NodeType::Map);
    config.controller =
        testbed::LoadControllerOptions(common::YamlMap(empty, root.file(), "controller"), "grip_slip");
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
  testbed::ControllerOptions& chosen = config.controller;
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
  testbed::ScenarioConfig scenario;
  scenario.name = "hw";
  scenario.backend = testbed::Backend::kSerial;
  scenario.serial = config.serial;
  scenario.log = options.log;
  scenario.controller = chosen;
  scenario.sensor.layout = options.layout.empty() ? sensor::DefaultLayoutPath() : options.layout;
  scenario.sensor.readout = config.loop.readout;
  scenario.sensor.inversion = config.loop.inversion;
  scenario.duration_s =
      options.duration_s > 0.0 ? options.duration_s : std::numeric_limits<double>::infinity();
  testbed::Action action;
  action.kind = intent == controller::GraspIntent::kClose  ? testbed::ActionKind::kClose
                : intent == controller::GraspIntent::kOpen ? testbed::ActionKind::kOpen
                                                           : testbed::ActionKind::kIdle;
  action.at_s = config.loop.readout.baseline_frames / scenario.sensor.sample_rate_hz;
  scenario.script = {action};
  testbed::RunOptions run;
  run.stop = &StopRequested();
  run.calibration = calibration;
  if (options.latency_report) run.latency_frames = kLatencyReportFrames;
  if (options.realtime_priority > 0) UseRealTimePriority(options.realtime_priority);
  // Before the port is opened: Ctrl-C while waiting for HELLO still ends with the port restored.
  StopSignalGuard signals;
  const testbed::RunResult result = testbed::RunScenario(scenario, run);

  // hw's own summary keys (docs/hardware.md), from the run's.
  const nlohmann::json& bench = result.bench;
  nlohmann::json summary = {{"port", config.serial.port},
                            {"layout", layout.name},
                            {"controller", bench.at("controller")},
                            {"duration_s", result.metrics.sim_s}};
  for (const char* key : {"frames", "corrupt", "dropped", "reordered", "unknown_packets", "reconnects",
                          "stale_periods", "sessions", "ticks", "loop_frames", "stale_ticks",
                          "disconnected_ticks", "actuator_failures", "retares", "motor_commands"}) {
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
              << bench.at("reordered") << " reordered, " << bench.at("unknown_packets") << " unknown, "
              << bench.at("reconnects") << " reconnects, " << bench.at("stale_periods") << " stale periods, "
              << bench.at("sessions") << " sessions; peak grip " << bench.at("peak_est_total_fn_n")
              << " N (sensed)" << (connected_at_end ? "" : "; device DISCONNECTED at the end")
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
  // The soak's fault schedule (docs/hardware.md, "The soak"); on when soak_cycles > 0.
  int soak_cycles = 0;
  double soak_period_s = 60.0;
  double soak_downtime_s = 0.5;
};

void RunEmulate(const EmulateOptions& options) {
  testbed::ScenarioConfig config;
  if (!options.scenario.empty()) {
    config = testbed::LoadScenario(options.scenario);
  } else {
    config.name = "plain";
    config.duration_s = 0.0;  // no scenario: until stopped
  }
  const sensor::Layout layout = sensor::LoadLayout(testbed::ResolveLayoutPath(config));
  testbed::EmulatedHand device(config, layout);

  hardware::EmulatorConfig emulator_config;
  emulator_config.link_path = options.link;
  emulator_config.unit_count = layout.unit_count();
  emulator_config.frame_rate_hz = static_cast<int>(std::lround(config.sensor.sample_rate_hz));
  emulator_config.nominal_r0_ohm = config.sensor.strain_model.nominal.r0_ohm;
  const bool soak = options.soak_cycles > 0;
  hardware::SoakSchedule schedule;
  schedule.cycles = options.soak_cycles;
  schedule.period_s = options.soak_period_s;
  schedule.downtime_s = options.soak_downtime_s;
  if (soak) schedule.Validate();
  // In a soak the device's pauses and disconnects are its own doing, not the host's end: the hand
  // is simulated (and scored) from the first stream start on until the host stops streaming.
  bool host_streamed = false;  // emulator thread only
  hardware::DeviceEmulator emulator(
      emulator_config,
      [&device, soak, &host_streamed](double, bool streaming, sensor::RawFrame* frame) {
        host_streamed = host_streamed || streaming;
        device.Frame(soak ? host_streamed : streaming, frame);
      },
      [&device](const hardware::EmulatedMotor& motor) {
        device.Motor({.grip_effort = motor.effort, .enable = motor.enable, .brake = motor.brake});
      });
  StopSignalGuard signals;
  emulator.Start();
  std::unique_ptr<hardware::SoakInjector> injector;
  if (soak) {
    injector = std::make_unique<hardware::SoakInjector>(emulator, schedule);
    injector->Start();
  }
  std::cerr << "emulate: device '" << config.name << "' (" << layout.unit_count() << " units) at "
            << options.link << " -> " << emulator.slave_path() << "; waiting for a host";
  if (soak) {
    std::cerr << "; soak: " << schedule.cycles << " cycles of " << schedule.period_s << " s, down "
              << schedule.downtime_s << " s each";
  }
  std::cerr << "\n";
  // Ends after `duration` simulated seconds from the first stream start (default: the scenario's;
  // in a soak, none), when the host stops streaming (with a scenario: one host run is one trial; in a
  // soak: its STREAM_CONTROL stop), or on SIGINT/SIGTERM.
  const double duration_s = options.duration_s >= 0.0 ? options.duration_s : soak ? 0.0 : config.duration_s;
  const bool one_trial = !options.scenario.empty();
  std::string ended_by = "signal";
  while (!StopRequested().load()) {
    if (duration_s > 0.0 && device.started() && device.sim_time_s() >= duration_s) {
      ended_by = "duration";
      break;
    }
    if (soak ? emulator.stats().stream_stops > 0 : one_trial && device.host_done()) {
      ended_by = "host_stopped";
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (injector) injector->Stop();
  const hardware::EmulatorStats stats = emulator.stats();
  emulator.Stop();

  nlohmann::json summary = device.Summary();
  summary["scenario"] = config.name;
  summary["link"] = options.link;
  summary["ended_by"] = ended_by;
  summary["frames_sent"] = stats.frames_sent;
  summary["frames_overflowed"] = stats.frames_overflowed;
  summary["frames_dropped"] = stats.frames_dropped;
  summary["frames_corrupted"] = stats.frames_corrupted;
  summary["frames_reordered"] = stats.frames_reordered;
  summary["frames_trailing"] = stats.frames_trailing;
  summary["garbage_packets"] = stats.garbage_packets;
  summary["vanishes"] = stats.vanishes;
  summary["settles"] = stats.settles;
  summary["settles_unconfirmed"] = stats.settles_unconfirmed;
  summary["hellos_sent"] = stats.hellos_sent;
  summary["motor_commands"] = stats.motor_commands;
  summary["max_command_interval_s"] = stats.max_command_interval_s;
  summary["watchdog_trips"] = stats.watchdog_trips;
  summary["stream_starts"] = stats.stream_starts;
  summary["connects"] = stats.connects;
  summary["commands_before_hello"] = stats.commands_before_hello;
  summary["host_corrupt"] = stats.host_corrupt;
  if (injector) {
    const hardware::SoakProgress progress = injector->progress();
    summary["soak"] = {{"period_s", schedule.period_s},
                       {"cycles", schedule.cycles},
                       {"downtime_s", schedule.downtime_s},
                       {"cycles_completed", progress.cycles_completed},
                       {"final_settle_confirmed", progress.final_settle_confirmed}};
  }
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

// ---- soak ------------------------------------------------------------------------------------------

struct SoakOptions {
  std::string scenario;
  double duration_s = 600.0;
  double period_s = 60.0;
  double downtime_s = 0.5;
  std::string link;
  std::string out_dir = "out/soak";
  double rss_interval_s = 1.0;
  bool keep_signals = false;
  bool json = false;
};

/// The host runs this much longer than the schedule: the final settle and the host's own start-up
/// fit in it with room on a loaded machine [s].
constexpr double kSoakHostTailS = 5.0;
/// The limit on the host's resident growth after the first tenth of the run [kB].
constexpr int64_t kSoakRssGrowthLimitKb = 1024;
/// The window of the RSS check starts after this share of the run (the first minute of ten).
constexpr double kSoakRssWarmupShare = 0.1;

double LoadAverage1Min() {
  double load = -1.0;
  if (std::FILE* file = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(file, "%lf", &load) != 1) load = -1.0;
    std::fclose(file);
  }
  return load;
}

std::string SelfExecutable() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error)
    throw std::runtime_error("soak: cannot find this executable (/proc/self/exe): " + error.message());
  return self.string();
}

/// Waits up to `timeout_s` for `pid` to exit; its exit code (128 + signal when killed), or -1 when it
/// is still running.
int WaitExit(int pid, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    int status = 0;
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (done < 0) return -2;
    if (std::chrono::steady_clock::now() >= deadline) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

/// Ends a child we started: SIGTERM (both commands end cleanly on it), SIGKILL after 10 s.
int EndChild(int pid) {
  ::kill(pid, SIGTERM);
  int code = WaitExit(pid, 10.0);
  if (code == -1) {
    ::kill(pid, SIGKILL);
    code = WaitExit(pid, 10.0);
  }
  return code;
}

nlohmann::json ReadJsonFile(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& error) {
    throw std::runtime_error("soak: " + what + " printed no JSON summary (" + path + "): " + error.what());
  }
}

void RunSoak(const SoakOptions& options) {
  namespace fs = std::filesystem;
  const double cycles_exact = options.duration_s / options.period_s;
  const int cycles = static_cast<int>(std::lround(cycles_exact));
  if (cycles < 1 || std::abs(cycles_exact - cycles) > 1e-9) {
    std::ostringstream message;
    message << "soak: --duration " << options.duration_s << " must be a whole number (>= 1) of --period "
            << options.period_s << " (one disconnect per period)";
    throw std::invalid_argument(message.str());
  }
  hardware::SoakSchedule schedule;
  schedule.cycles = cycles;
  schedule.period_s = options.period_s;
  schedule.downtime_s = options.downtime_s;
  schedule.Validate();
  const std::string link =
      options.link.empty() ? "/tmp/graspbed-soak-" + std::to_string(::getpid()) : options.link;
  const double host_duration_s = options.duration_s + kSoakHostTailS;
  const auto number = [](double value) {
    std::ostringstream text;
    text << value;
    return text.str();
  };
  // Refused here (exit 2) rather than in a child: a bad file, a duration the loader refuses (over
  // 3600 s, or a signal log over its bound). A script the bench cannot play is refused by the host.
  testbed::LoadScenario(
      options.scenario,
      {{"serial.port", link}, {"backend", "serial"}, {"duration_s", number(host_duration_s)}});
  if (fs::exists(fs::symlink_status(link))) {
    throw std::invalid_argument("soak: --link " + link + " exists already (another emulator?)");
  }
  fs::create_directories(options.out_dir);
  const std::string self = SelfExecutable();
  const std::string emulate_json = options.out_dir + "/emulate.json";
  const std::string host_json = options.out_dir + "/host.json";
  const std::string host_out = options.out_dir + "/host";
  const double load_start = LoadAverage1Min();
  double load_max = load_start;

  StopSignalGuard signals;
  const int emulator_pid = common::SpawnProcess(
      {self, "emulate", "--link", link, options.scenario, "--soak-cycles", std::to_string(cycles),
       "--soak-period", number(options.period_s), "--soak-downtime", number(options.downtime_s), "--json"},
      -1, emulate_json, options.out_dir + "/emulate.log");
  // The emulator loads the model before it makes the link.
  const auto link_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(fs::symlink_status(link))) {
    if (WaitExit(emulator_pid, 0.0) != -1) {
      throw std::runtime_error("soak: the emulator ended before it made " + link + "; see " +
                               options.out_dir + "/emulate.log");
    }
    if (StopRequested().load() || std::chrono::steady_clock::now() > link_deadline) {
      EndChild(emulator_pid);
      throw std::runtime_error("soak: no emulator link at " + link + " after 120 s");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::fprintf(stderr,
               "soak: %d cycles of %g s (%g s), host `run %s --backend serial --port %s` for %g s; "
               "load average %.2f\n",
               cycles, options.period_s, options.duration_s, options.scenario.c_str(), link.c_str(),
               host_duration_s, load_start);
  const auto host_start = std::chrono::steady_clock::now();
  const int host_pid = common::SpawnProcess(
      {self, "run", options.scenario, "--backend", "serial", "--port", link, "--out", host_out, "--no-plots",
       "--no-stdin-intent", "--json", "--set", "duration_s=" + number(host_duration_s)},
      -1, host_json, options.out_dir + "/host.log");

  // The host's resident size, sampled from outside (/proc) until it exits.
  std::vector<hardware::RssSample> rss;
  rss.reserve(static_cast<size_t>(host_duration_s / options.rss_interval_s) + 64);
  int host_exit = -1;
  double next_report_s = options.period_s;
  bool interrupted = false;
  while (host_exit == -1) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - host_start).count();
    const int64_t kb = hardware::ReadResidentKb(host_pid);
    if (kb >= 0) rss.push_back({t, kb});
    load_max = std::max(load_max, LoadAverage1Min());
    if (t >= next_report_s && t <= options.duration_s + 1.0) {
      std::fprintf(stderr, "soak: %.0f / %g s, host resident %.1f MB, load average %.2f\n", t,
                   options.duration_s, kb / 1024.0, LoadAverage1Min());
      next_report_s += options.period_s;
    }
    if (StopRequested().load() && !interrupted) {
      interrupted = true;
      ::kill(host_pid, SIGTERM);
    }
    host_exit = WaitExit(host_pid, options.rss_interval_s);
  }
  // The emulator ends when the host stops streaming; it prints its summary then. A host that was
  // refused never streamed.
  int emulator_exit = WaitExit(emulator_pid, host_exit == 0 ? 30.0 : 2.0);
  if (emulator_exit == -1) emulator_exit = EndChild(emulator_pid);
  const double load_end = LoadAverage1Min();
  if (interrupted) throw CLI::RuntimeError(130);
  if (host_exit == 2) {  // bad input to `run`: its message, as ours
    std::ifstream log(options.out_dir + "/host.log");
    std::string message((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
    while (!message.empty() && message.back() == '\n') message.pop_back();
    throw std::invalid_argument("soak: the host (run --backend serial) refused to start: " + message);
  }

  const nlohmann::json emulator = ReadJsonFile(emulate_json, "the emulator");
  const nlohmann::json host_summary = ReadJsonFile(host_json, "the host (run --backend serial)");
  if (!host_summary.contains("bench"))
    throw std::runtime_error("soak: the host's summary has no bench counters");
  const nlohmann::json& bench = host_summary.at("bench");
  const auto count = [](const nlohmann::json& object, const char* key) {
    return object.value(key, uint64_t{0});
  };
  hardware::SoakDeviceCounts device;
  device.frames_sent = count(emulator, "frames_sent");
  device.frames_dropped = count(emulator, "frames_dropped");
  device.frames_corrupted = count(emulator, "frames_corrupted");
  device.frames_reordered = count(emulator, "frames_reordered");
  device.frames_overflowed = count(emulator, "frames_overflowed");
  device.frames_trailing = count(emulator, "frames_trailing");
  device.garbage_packets = count(emulator, "garbage_packets");
  device.connects = count(emulator, "connects");
  device.vanishes = count(emulator, "vanishes");
  device.settles_unconfirmed = count(emulator, "settles_unconfirmed");
  device.cycles_planned = cycles;
  if (emulator.contains("soak")) {
    device.cycles_completed = emulator["soak"].value("cycles_completed", 0);
    device.final_settle_confirmed = emulator["soak"].value("final_settle_confirmed", false);
  }
  hardware::SoakHostCounts host;
  host.frames = count(bench, "frames");
  host.corrupt = count(bench, "corrupt");
  host.dropped = count(bench, "dropped");
  host.reordered = count(bench, "reordered");
  host.unknown_packets = count(bench, "unknown_packets");
  host.reconnects = count(bench, "reconnects");
  host.sessions = count(bench, "sessions");
  host.connected_at_end = bench.value("connected_at_end", false);
  const hardware::SoakVerdict verdict = hardware::CompareSoakCounts(device, host);
  const hardware::RssSummary memory =
      hardware::SummariseRss(rss, kSoakRssWarmupShare * options.duration_s, options.duration_s);
  const bool memory_flat = memory.samples >= 2 && memory.growth_kb < kSoakRssGrowthLimitKb;
  const bool passed = verdict.exact() && memory_flat && host_exit == 0;

  nlohmann::json report = {{"scenario", options.scenario},
                           {"duration_s", options.duration_s},
                           {"period_s", options.period_s},
                           {"cycles", cycles},
                           {"host_duration_s", host_duration_s},
                           {"host_exit", host_exit},
                           {"emulator_exit", emulator_exit},
                           {"comparable", verdict.comparable()},
                           {"not_comparable", verdict.not_comparable},
                           {"counters_exact", verdict.exact()},
                           {"passed", passed}};
  nlohmann::json comparisons = nlohmann::json::array();
  for (const hardware::SoakComparison& c : verdict.comparisons) {
    comparisons.push_back({{"counter", c.counter},
                           {"host", c.host},
                           {"expected", c.expected},
                           {"rule", c.rule},
                           {"equal", c.equal()}});
  }
  report["comparisons"] = comparisons;
  report["device"] = {{"frames_sent", device.frames_sent},
                      {"frames_dropped", device.frames_dropped},
                      {"frames_corrupted", device.frames_corrupted},
                      {"frames_reordered", device.frames_reordered},
                      {"frames_overflowed", device.frames_overflowed},
                      {"frames_trailing", device.frames_trailing},
                      {"garbage_packets", device.garbage_packets},
                      {"connects", device.connects},
                      {"vanishes", device.vanishes},
                      {"settles", count(emulator, "settles")},
                      {"settles_unconfirmed", device.settles_unconfirmed},
                      {"cycles_completed", device.cycles_completed},
                      {"final_settle_confirmed", device.final_settle_confirmed},
                      {"watchdog_trips", count(emulator, "watchdog_trips")}};
  report["host"] = {{"frames", host.frames},
                    {"corrupt", host.corrupt},
                    {"dropped", host.dropped},
                    {"reordered", host.reordered},
                    {"unknown_packets", host.unknown_packets},
                    {"reconnects", host.reconnects},
                    {"sessions", host.sessions},
                    {"stale_periods", count(bench, "stale_periods")},
                    {"actuator_failures", count(bench, "actuator_failures")},
                    {"connected_at_end", host.connected_at_end}};
  nlohmann::json samples = nlohmann::json::array();
  for (const hardware::RssSample& sample : rss) samples.push_back({sample.time_s, sample.resident_kb});
  report["rss"] = {{"window_from_s", kSoakRssWarmupShare * options.duration_s},
                   {"window_until_s", options.duration_s},
                   {"samples_in_window", memory.samples},
                   {"baseline_time_s", memory.baseline_time_s},
                   {"baseline_kb", memory.baseline_kb},
                   {"last_kb", memory.last_kb},
                   {"max_kb", memory.max_kb},
                   {"growth_kb", memory.growth_kb},
                   {"limit_kb", kSoakRssGrowthLimitKb},
                   {"flat", memory_flat},
                   {"first_sample_kb", rss.empty() ? int64_t{-1} : rss.front().resident_kb},
                   {"samples", samples}};
  report["load_average_1min"] = {{"start", load_start}, {"max", load_max}, {"end", load_end}};
  if (!options.keep_signals) fs::remove(host_out + "/signals.csv");  // a row per tick: 1-2 GB for 10 min
  common::WriteFileAtomic(options.out_dir + "/soak.json", report.dump(2) + "\n");

  if (options.json) {
    std::cout << report.dump(2) << '\n';
  } else {
    std::printf(
        "soak %s: %g s, %d cycles of %g s; load average (1 min) %.2f at start, %.2f max, %.2f at end\n",
        options.scenario.c_str(), options.duration_s, cycles, options.period_s, load_start, load_max,
        load_end);
    std::printf("  %-16s %10s %10s  %s\n", "host counter", "host", "expected", "from the device's counts");
    for (const hardware::SoakComparison& c : verdict.comparisons) {
      std::printf("  %-16s %10llu %10llu  %s%s\n", c.counter.c_str(), static_cast<unsigned long long>(c.host),
                  static_cast<unsigned long long>(c.expected), c.rule.c_str(),
                  c.equal() ? "" : "   <-- DIFFERS");
    }
    std::printf(
        "  device: %llu frames sent, %llu corrupted, %llu dropped, %llu reordered, %llu garbage blocks, "
        "%llu disconnects; %llu overflowed (the host did not read in time; in dropped)\n",
        static_cast<unsigned long long>(device.frames_sent),
        static_cast<unsigned long long>(device.frames_corrupted),
        static_cast<unsigned long long>(device.frames_dropped),
        static_cast<unsigned long long>(device.frames_reordered),
        static_cast<unsigned long long>(device.garbage_packets),
        static_cast<unsigned long long>(device.vanishes),
        static_cast<unsigned long long>(device.frames_overflowed));
    std::printf(
        "  host resident: %.1f MB at %.0f s, %.1f MB at the end of the window, %.1f MB max: growth %lld kB "
        "(limit %lld kB, %zu samples)\n",
        memory.baseline_kb / 1024.0, memory.baseline_time_s, memory.last_kb / 1024.0, memory.max_kb / 1024.0,
        static_cast<long long>(memory.growth_kb), static_cast<long long>(kSoakRssGrowthLimitKb),
        memory.samples);
    for (const std::string& reason : verdict.not_comparable)
      std::printf("  not comparable: %s\n", reason.c_str());
    if (host_exit != 0)
      std::printf("  the host exited with %d (see %s/host.log)\n", host_exit, options.out_dir.c_str());
    std::printf("  %s (report: %s/soak.json)\n", passed ? "PASSED" : "FAILED", options.out_dir.c_str());
  }
  if (!passed) throw CLI::RuntimeError(kExitFailed);
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
  emulate
      ->add_option("--soak-cycles", emulate_options->soak_cycles,
                   "Inject the soak's fault schedule for N cycles from the host's first stream start "
                   "(corrupted, dropped, reordered and truncated frames, garbage, a disconnect and "
                   "reconnect per cycle; docs/hardware.md, \"The soak\"), then pause the stream until the "
                   "host ends the session")
      ->check(CLI::PositiveNumber);
  emulate->add_option("--soak-period", emulate_options->soak_period_s, "Length of one soak cycle [s] (>= 5)")
      ->capture_default_str();
  emulate
      ->add_option("--soak-downtime", emulate_options->soak_downtime_s,
                   "How long the device stays away at each soak disconnect [s]")
      ->capture_default_str();
  emulate->callback([emulate_options] { RunEmulate(*emulate_options); });

  auto soak_options = std::make_shared<SoakOptions>();
  CLI::App* soak = root.add_subcommand(
      "soak",
      "Soak the serial path: `graspbed emulate` with the soak's fault schedule against `graspbed run "
      "--backend "
      "serial`; compares the host's counters with what the device injected, exactly, and checks the host's "
      "resident memory stays flat (exit 0 when both hold, 1 otherwise)");
  soak->add_option("scenario", soak_options->scenario,
                   "Scenario YAML for both sides (close/open/idle script)")
      ->required()
      ->check(CLI::ExistingFile);
  soak->add_option("--duration", soak_options->duration_s,
                   "Length of the fault schedule [s], a multiple of --period")
      ->capture_default_str();
  soak->add_option("--period", soak_options->period_s,
                   "One cycle of faults and one disconnect per period [s]")
      ->capture_default_str();
  soak->add_option("--downtime", soak_options->downtime_s, "How long the device stays away each time [s]")
      ->capture_default_str();
  soak->add_option("--link", soak_options->link, "Emulator link path (default /tmp/graspbed-soak-PID)");
  soak->add_option("--out", soak_options->out_dir, "Output directory: soak.json, both summaries and logs")
      ->capture_default_str();
  soak->add_option("--rss-interval", soak_options->rss_interval_s, "Host RSS sampling interval [s]")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 60.0));
  soak->add_flag("--keep-signals", soak_options->keep_signals,
                 "Keep the host's signals.csv (one row per control tick: about 2 GB for 10 minutes)");
  soak->add_flag("--json", soak_options->json, "Print the report (soak.json) on stdout instead of the table");
  soak->callback([soak_options] { RunSoak(*soak_options); });
}

const bool kRegistered = RegisterCommands(&AddHwCommands);

}  // namespace
}  // namespace graspbed::app
