#pragma once
/// `graspbed hw`: a session on the hand without a scenario file -- a scenario on backend serial with
/// one intent given once the tare is done, its own `--config` (docs/hardware.md "Configuration") and
/// no outputs but the frame log. PrepareHwSession resolves and checks everything before the port is
/// opened (so bad input is refused with the port untouched); RunHwSession runs it and returns hw's
/// summary; HwSummaryText is the line `hw` prints without --json.

#include <atomic>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "controller/control_loop.h"
#include "hardware/hardware_config.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {

/// Everything `hw --config FILE` can set (docs/hardware.md "Configuration").
struct HwRunConfig {
  hardware::HardwareConfig serial;
  /// The controller section exactly as in a scenario (name, params, grip_ceiling_n, rate_hz,
  /// stale_timeout_s), so a controller tuned in simulation runs with the same numbers on the hand.
  /// rate_hz: control ticks per second when frames do not arrive (ticks also follow every frame).
  ControllerOptions controller;
  controller::ControlLoopConfig loop;  ///< readout, inversion; stale timeout from `controller`
};

/// Reads `hw --config FILE`; an empty path gives the defaults (the reference controller).
/// @throws common::ConfigError with file, line and key for a bad or unknown entry.
HwRunConfig LoadHwRunConfig(const std::string& path);

/// What `graspbed hw` takes on its command line (messages name these options).
struct HwSessionOptions {
  std::string port;                 ///< serial device; empty: serial.port of `config`
  std::string config;               ///< `--config` YAML; empty: the defaults
  std::string layout;               ///< layout file; empty: sensor::DefaultLayoutPath()
  std::string calibration;          ///< calibration file; empty: the paper's values
  std::string controller;           ///< a built-in name or plugin:LIBRARY; empty: the config's
  std::vector<std::string> params;  ///< NAME=VALUE controller parameters, over the config's
  std::string intent = "close";     ///< close, open or idle, given once tared
  double duration_s = 0.0;          ///< stop cleanly after this long [s]; 0: until stopped
  int tare_frames = -1;             ///< frames averaged for the tare; < 0: readout.baseline_frames
  std::string log;                  ///< CSV with one row per decoded frame; empty: none
  bool latency_report = false;      ///< measure the loop latency (summary "latency")
  int realtime_priority = 0;        ///< SCHED_FIFO priority (1-99) of the loop and link; 0: none
};

/// A session resolved and checked, ready to open the port.
struct HwSession {
  ScenarioConfig scenario;    ///< backend serial, one action: the intent once tared
  RunOptions run;             ///< calibration and latency report; `stop` is RunHwSession's
  std::string layout_name;    ///< for the summary
  int realtime_priority = 0;  ///< see HwSessionOptions
};

/// Resolves `options` against `--config`: the port, the tare, the controller (another controller
/// than the config's drops the config's parameters; --param goes over them), layout and calibration.
/// Opens nothing.
/// @throws std::invalid_argument (common::ConfigError) for anything the session would refuse: no
/// port, a bad intent or --param, an unknown controller parameter or one out of its range.
HwSession PrepareHwSession(const HwSessionOptions& options);

/// How a session went.
struct HwSessionResult {
  /// hw's summary keys (docs/hardware.md), taken from the run's bench counters: `hw --json`.
  nlohmann::json summary;
  bool connected_at_end = false;  ///< the device was still there when the session ended
  std::string log_error;          ///< why the frame log could not be completed; empty when it was
  /// The session failed (exit 1): the device was gone at the end or the log is incomplete.
  bool failed() const { return !connected_at_end || !log_error.empty(); }
};

/// Runs `session` until its duration, `stop` or the end of the device, under SCHED_FIFO first when
/// it asks for it. Blocks; `stop` (may be null) is polled every control tick.
/// @throws std::runtime_error when SCHED_FIFO is refused ("--realtime-priority N: ..."), or what
/// RunScenario throws (a port that does not exist or a device that does not match the layout).
HwSessionResult RunHwSession(const HwSession& session, const std::atomic<bool>* stop);

/// The summary line (and the loop latency line with --latency-report) `hw` prints without --json.
std::string HwSummaryText(const HwSessionResult& result);

}  // namespace graspbed::testbed
