#include "testbed/emulator_session.h"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <optional>
#include <sstream>
#include <thread>

namespace graspbed::testbed {
namespace {

/// How long a trial's device waits past its scenario's end for the host to stop the stream [s].
constexpr double kHostGraceS = 5.0;

ScenarioConfig LoadEmulatedScenario(const std::string& path) {
  if (!path.empty()) return LoadScenario(path);
  ScenarioConfig config;
  config.name = "plain";
  config.duration_s = 0.0;  // no scenario: until stopped
  return config;
}

void AddEmulatorStats(const hardware::EmulatorStats& stats, nlohmann::json& summary) {
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
  summary["protocol_version"] = stats.selects > 0 ? 2 : 1;  // what the host chose (last connection aside)
  summary["selects"] = stats.selects;
  summary["hand_sent"] = stats.hand_sent;
  summary["hand_overflowed"] = stats.hand_overflowed;
}

}  // namespace

EmulatorSession::EmulatorSession(const EmulateOptions& options)
    : options_(options),
      config_(LoadEmulatedScenario(options.scenario)),
      layout_(sensor::LoadLayout(ResolveLayoutPath(config_))),
      device_(std::make_unique<EmulatedHand>(config_, layout_)) {
  hardware::EmulatorConfig emulator_config;
  emulator_config.link_path = options_.link;
  emulator_config.unit_count = layout_.unit_count();
  emulator_config.frame_rate_hz = static_cast<int>(std::lround(config_.sensor.sample_rate_hz));
  emulator_config.nominal_r0_ohm = config_.sensor.strain_model.nominal.r0_ohm;
  emulator_config.protocol_version = options_.protocol_version;
  schedule_.cycles = options_.soak_cycles;
  schedule_.period_s = options_.soak_period_s;
  schedule_.downtime_s = options_.soak_downtime_s;
  if (soak()) schedule_.Validate();
  // In a soak the device's pauses and disconnects are its own doing, not the host's end: the hand
  // is simulated (and scored) from the first stream start on until the host stops streaming.
  emulator_ = std::make_unique<hardware::DeviceEmulator>(
      emulator_config,
      [this](double, bool streaming, sensor::RawFrame* frame) {
        host_streamed_ = host_streamed_ || streaming;
        device_->Frame(soak() ? host_streamed_ : streaming, frame);
      },
      [this](const hardware::EmulatedMotor& motor) {
        device_->Motor({.grip_effort = motor.effort, .enable = motor.enable, .brake = motor.brake});
      });
  // The simulated encoders and motor current (the scenario's `proprioception:` profile) for HAND.
  emulator_->SetHandSource([this](double, hand::HandState* state) { return device_->Hand(state); });
}

// The emulator's thread calls into device_: it ends first.
EmulatorSession::~EmulatorSession() { emulator_.reset(); }

nlohmann::json EmulatorSession::Run(const std::atomic<bool>& stop, std::ostream& progress) {
  emulator_->Start();
  std::unique_ptr<hardware::SoakInjector> injector;
  if (soak()) {
    injector = std::make_unique<hardware::SoakInjector>(*emulator_, schedule_);
    injector->Start();
  }
  progress << "emulate: device '" << config_.name << "' (" << layout_.unit_count() << " units) at "
           << options_.link << " -> " << emulator_->slave_path() << "; waiting for a host";
  if (soak()) {
    progress << "; soak: " << schedule_.cycles << " cycles of " << schedule_.period_s << " s, down "
             << schedule_.downtime_s << " s each";
  }
  progress << "\n";
  const double duration_s = options_.duration_s >= 0.0 ? options_.duration_s
                            : soak()                   ? 0.0
                                                       : config_.duration_s;
  const bool one_trial = !options_.scenario.empty();
  std::string ended_by = "signal";
  // A trial's device outlives its scenario's end while the host still streams, for up to
  // kHostGraceS: a host running the same scenario ends it by its own clock, a moment later than the
  // device's (it started later), and must find the device there to stop the stream and close cleanly.
  std::optional<std::chrono::steady_clock::time_point> scenario_ended;
  while (!stop.load()) {
    if (soak() ? emulator_->stats().stream_stops > 0 : one_trial && device_->host_done()) {
      ended_by = "host_stopped";
      break;
    }
    if (duration_s > 0.0 && device_->started() && device_->sim_time_s() >= duration_s) {
      const auto now = std::chrono::steady_clock::now();
      if (!scenario_ended) scenario_ended = now;
      if (!one_trial || now - *scenario_ended >= std::chrono::duration<double>(kHostGraceS)) {
        ended_by = "duration";
        break;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (injector) injector->Stop();
  // Stopped first, so every frame it sent is counted (a frame sent after a snapshot was the one the
  // host counted beyond the device's).
  emulator_->Stop();
  const hardware::EmulatorStats stats = emulator_->stats();

  nlohmann::json summary = device_->Summary();
  summary["scenario"] = config_.name;
  summary["link"] = options_.link;
  summary["ended_by"] = ended_by;
  AddEmulatorStats(stats, summary);
  if (injector) {
    const hardware::SoakProgress soak_progress = injector->progress();
    summary["soak"] = {{"period_s", schedule_.period_s},
                       {"cycles", schedule_.cycles},
                       {"downtime_s", schedule_.downtime_s},
                       {"cycles_completed", soak_progress.cycles_completed},
                       {"final_settle_confirmed", soak_progress.final_settle_confirmed}};
  }
  return summary;
}

std::string EmulateSummaryText(const nlohmann::json& summary) {
  const nlohmann::json& metrics = summary.at("metrics");
  std::ostringstream text;
  text << "emulate " << summary.at("link").get<std::string>() << " ("
       << summary.at("ended_by").get<std::string>() << "): " << summary.at("sim_time_s").get<double>()
       << " s simulated, " << summary.at("frames_sent").get<uint64_t>() << " frames sent, "
       << summary.at("hand_sent").get<uint64_t>() << " hand messages, "
       << summary.at("motor_commands").get<uint64_t>() << " motor commands, "
       << summary.at("watchdog_trips").get<uint64_t>() << " watchdog trips; object "
       << (!metrics.at("grasped").get<bool>()  ? "not grasped"
           : metrics.at("dropped").get<bool>() ? "DROPPED"
                                               : "held")
       << ", lifted " << 1e3 * summary.at("object_lift_m").get<double>() << " mm, peak grip "
       << metrics.at("peak_grip_n").get<double>() << " N, slip " << metrics.at("max_slip_mm").get<double>()
       << " mm\n";
  return text.str();
}

}  // namespace graspbed::testbed
