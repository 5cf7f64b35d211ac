#include "testbed/hw_session.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "common/process.h"
#include "common/yaml_map.h"
#include "controller/grasp_controller.h"
#include "controller/plugin_loader.h"
#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/layout.h"
#include "sensor/readout.h"

namespace graspbed::testbed {
namespace {

/// A force for a person to read: two decimals ("4.30"), not a double's seventeen digits.
std::string FormatNewtons(double newtons) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f", newtons);
  return text;
}


/// Frames whose loop latency `hw --latency-report` keeps (17 min at 1 kHz, 8 MB).
constexpr size_t kLatencyReportFrames = size_t{1} << 20;

controller::GraspIntent ParseIntent(const std::string& text) {
  const std::optional<controller::GraspIntent> intent = controller::IntentFromName(text);
  if (!intent) throw std::invalid_argument("--intent " + text + ": must be close, open or idle");
  return *intent;
}

/// --controller picks another controller than the config's (the config's parameters belong to its
/// own); --param NAME=NUMBER goes over the parameters. The factory then names an unknown parameter,
/// a value out of its range or a cross-field conflict.
ControllerOptions ChooseController(ControllerOptions chosen, const HwSessionOptions& options) {
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
  controller::MakeController(chosen.name, chosen.params);
  return chosen;
}

/// The session as a scenario on backend serial with one intent, given once the tare is done (the
/// first baseline_frames frames at the sensor's rate), and no outputs but the frame log.
ScenarioConfig HwScenario(const HwRunConfig& config, const HwSessionOptions& options,
                          controller::GraspIntent intent) {
  ScenarioConfig scenario;
  scenario.name = "hw";
  scenario.backend = Backend::kSerial;
  scenario.serial = config.serial;
  scenario.log = options.log;
  scenario.controller = config.controller;
  scenario.sensor.layout = options.layout.empty() ? sensor::DefaultLayoutPath() : options.layout;
  scenario.sensor.readout = config.loop.readout;
  scenario.sensor.inversion = config.loop.inversion;
  scenario.duration_s =
      options.duration_s > 0.0 ? options.duration_s : std::numeric_limits<double>::infinity();
  Action action;
  action.kind = intent == controller::GraspIntent::kClose  ? ActionKind::kClose
                : intent == controller::GraspIntent::kOpen ? ActionKind::kOpen
                                                           : ActionKind::kIdle;
  action.at_s = config.loop.readout.baseline_frames / scenario.sensor.sample_rate_hz;
  scenario.script = {action};
  return scenario;
}

/// "; protocol v2, 1000 hand messages" (with the malformed when any); "" for a summary without them.
std::string HandText(const nlohmann::json& summary) {
  if (!summary.contains("protocol_version")) return "";
  std::string text = "; protocol v" + summary.at("protocol_version").dump() + ", " +
                     summary.at("hand_messages").dump() + " hand messages";
  if (summary.at("hand_malformed").get<uint64_t>() > 0)
    text += " (" + summary.at("hand_malformed").dump() + " malformed)";
  return text;
}

/// hw's own summary keys (docs/hardware.md), from the run's.
nlohmann::json HwSummary(const HwSession& session, const RunResult& result) {
  const nlohmann::json& bench = result.bench;
  nlohmann::json summary = {{"port", session.scenario.serial.port},
                            {"layout", session.layout_name},
                            {"controller", bench.at("controller")},
                            {"duration_s", result.metrics.sim_s}};
  for (const char* key : {"frames", "corrupt", "dropped", "reordered", "unknown_packets", "reconnects",
                          "stale_periods", "sessions", "ticks", "loop_frames", "stale_ticks",
                          "disconnected_ticks", "actuator_failures", "retares", "motor_commands"}) {
    summary[key] = bench.at(key);
  }
  summary["tare_frames"] = session.scenario.sensor.readout.baseline_frames;
  summary["peak_total_fn_n"] = bench.at("peak_est_total_fn_n");
  summary["final_total_fn_n"] = bench.at("final_est_total_fn_n");
  summary["final_valid_units"] = bench.at("final_valid_units");
  summary["interrupted"] = !result.completed;
  // The hand's proprioception: the protocol version chosen with the device (1: no HAND) and its HANDs.
  for (const char* key :
       {"protocol_version", "hand_messages", "hand_malformed", "hand_dropped", "hand_readings"}) {
    summary[key] = bench.at(key);
  }
  for (const char* key : {"log", "log_rows", "log_rows_lost", "log_error", "last_error"}) {
    if (bench.contains(key)) summary[key] = bench.at(key);
  }
  if (bench.contains("latency")) summary["latency"] = bench.at("latency");
  summary["connected_at_end"] = bench.at("connected_at_end").get<bool>();
  return summary;
}

}  // namespace

HwRunConfig LoadHwRunConfig(const std::string& path) {
  YAML::Node no_file(YAML::NodeType::Map);
  const common::YamlMap root =
      path.empty() ? common::YamlMap(no_file, "(no --config)", "") : common::YamlMap::LoadFile(path);
  HwRunConfig config;
  if (const auto section = root.GetMap("serial")) config.serial = hardware::LoadHardwareConfig(*section);
  if (const auto section = root.GetMap("controller")) {
    config.controller = LoadControllerOptions(*section, "grip_slip");
  } else {
    YAML::Node empty(YAML::NodeType::Map);
    config.controller = LoadControllerOptions(common::YamlMap(empty, root.file(), "controller"), "grip_slip");
  }
  config.loop.stale_timeout_s = config.controller.stale_timeout_s;
  if (const auto section = root.GetMap("readout")) config.loop.readout = sensor::LoadReadoutConfig(*section);
  if (const auto section = root.GetMap("inversion")) {
    config.loop.inversion = sensor::LoadInversionConfig(*section);
  }
  root.RejectUnknownKeys();
  return config;
}

HwSession PrepareHwSession(const HwSessionOptions& options) {
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
  HwSession session;
  session.run.calibration = options.calibration.empty() ? sensor::PaperCalibration(units)
                                                        : sensor::LoadCalibration(options.calibration, units);
  config.controller = ChooseController(config.controller, options);
  session.scenario = HwScenario(config, options, intent);
  if (options.latency_report) session.run.latency_frames = kLatencyReportFrames;
  session.layout_name = layout.name;
  session.realtime_priority = options.realtime_priority;
  return session;
}

HwSessionResult RunHwSession(const HwSession& session, const std::atomic<bool>* stop) {
  if (session.realtime_priority > 0) {
    try {
      common::UseRealTimePriority(session.realtime_priority);
    } catch (const std::runtime_error& error) {
      throw std::runtime_error("--realtime-priority " + std::to_string(session.realtime_priority) + ": " +
                               error.what());
    }
  }
  RunOptions run = session.run;
  run.stop = stop;
  const RunResult result = RunScenario(session.scenario, run);
  HwSessionResult outcome;
  outcome.summary = HwSummary(session, result);
  outcome.connected_at_end = outcome.summary.at("connected_at_end").get<bool>();
  outcome.log_error = result.bench.value("log_error", std::string());
  return outcome;
}

std::string HwSummaryText(const HwSessionResult& result) {
  const nlohmann::json& summary = result.summary;
  std::ostringstream text;
  text << "hw " << summary.at("port").get<std::string>() << ": " << summary.at("duration_s").get<double>()
       << " s, " << summary.at("frames") << " frames, " << summary.at("corrupt") << " corrupt, "
       << summary.at("dropped") << " dropped, " << summary.at("reordered") << " reordered, "
       << summary.at("unknown_packets") << " unknown, " << summary.at("reconnects") << " reconnects, "
       << summary.at("stale_periods") << " stale periods, " << summary.at("sessions") << " sessions"
       << HandText(summary) << "; peak grip " << FormatNewtons(summary.at("peak_total_fn_n").get<double>())
       << " N (sensed)" << (result.connected_at_end ? "" : "; device DISCONNECTED at the end")
       << (result.log_error.empty() ? "" : "; log: " + result.log_error) << '\n';
  if (summary.contains("latency")) {
    const nlohmann::json& latency = summary.at("latency");
    char line[256];
    std::snprintf(
        line, sizeof line,
        "loop latency (frame decoded -> its command written), %llu frames: p50 %.0f us, p99 %.0f us, "
        "p99.9 %.0f us, max %.0f us; %llu over 1 ms, %llu over 5 ms\n",
        latency.at("frames_answered").get<unsigned long long>(), latency.at("p50_us").get<double>(),
        latency.at("p99_us").get<double>(), latency.at("p999_us").get<double>(),
        latency.at("max_us").get<double>(), latency.at("over_1ms").get<unsigned long long>(),
        latency.at("over_5ms").get<unsigned long long>());
    text << line;
  }
  return text.str();
}

}  // namespace graspbed::testbed
