#pragma once
/// `graspbed emulate`: the simulated hand (EmulatedHand) behind a DeviceEmulator on a pseudo-terminal,
/// speaking the device's protocol, so `graspbed hw` and `graspbed run --backend serial` run end to end
/// without hardware; with a soak schedule, the SoakInjector's faults on top (docs/hardware.md, "The
/// soak"). An EmulatorSession loads everything when made (bad input is refused before the link
/// exists); Run() serves hosts until the session's end and returns the device's summary.

#include <atomic>
#include <memory>
#include <ostream>
#include <string>

#include <nlohmann/json.hpp>

#include "hardware/device_emulator.h"
#include "hardware/soak.h"
#include "sensor/layout.h"
#include "testbed/emulated_hand.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {

/// What `graspbed emulate` takes on its command line.
struct EmulateOptions {
  std::string link;      ///< path of the symlink to the pty to create
  std::string scenario;  ///< scenario YAML (wrist and object script); empty: a plain device until stopped
  /// Simulated seconds after the host's first stream start [s]; < 0: the scenario's (in a soak: none).
  double duration_s = -1.0;
  /// Highest wire protocol version the device speaks (1 or 2; docs/protocol.md): 2 sends the
  /// hand's proprioception (HAND) to a host that selects it, 1 is a device from before HAND.
  int protocol_version = 2;
  // The soak's fault schedule (docs/hardware.md, "The soak"); on when soak_cycles > 0.
  int soak_cycles = 0;           ///< cycles of the schedule; 0: no soak
  double soak_period_s = 60.0;   ///< one cycle [s]
  double soak_downtime_s = 0.5;  ///< how long the device stays away at each disconnect [s]
};

/// The simulated device, made and not yet serving. Owns the emulator and its thread.
class EmulatorSession {
 public:
  /// Loads the scenario, its layout and the hand's model; checks the soak schedule. Creates no link.
  /// @throws std::invalid_argument (common::ConfigError) for a bad scenario or schedule.
  explicit EmulatorSession(const EmulateOptions& options);
  ~EmulatorSession();
  EmulatorSession(const EmulatorSession&) = delete;
  EmulatorSession& operator=(const EmulatorSession&) = delete;

  /// Makes the link and serves hosts until the session ends: `duration_s` simulated seconds from the
  /// first stream start, the host's end (with a scenario: its stream stop, one host run being one
  /// trial; in a soak: its STREAM_CONTROL stop) or `stop`. Writes one line saying where the device
  /// waits to `progress`. Returns the summary of `emulate --json`: ground truth and run metrics as
  /// the host left the hand, the emulator's counters, "ended_by" (duration, host_stopped or signal)
  /// and, in a soak, "soak". Call once.
  /// @throws std::runtime_error when the link cannot be made.
  nlohmann::json Run(const std::atomic<bool>& stop, std::ostream& progress);

 private:
  bool soak() const { return options_.soak_cycles > 0; }

  const EmulateOptions options_;
  ScenarioConfig config_;
  sensor::Layout layout_;
  std::unique_ptr<EmulatedHand> device_;
  hardware::SoakSchedule schedule_;
  bool host_streamed_ = false;  // emulator thread only
  std::unique_ptr<hardware::DeviceEmulator> emulator_;
};

/// The line `emulate` prints without --json, from Run()'s summary.
std::string EmulateSummaryText(const nlohmann::json& summary);

}  // namespace graspbed::testbed
