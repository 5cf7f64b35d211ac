// `graspbed hw`: a session on the hand without a scenario -- a thin alias of `graspbed run --backend
// serial` (one intent once tared, its own --config, no outputs but the frame log). `graspbed emulate`: the
// simulated hand behind a pseudo-terminal, speaking the same protocol as the device, so `hw` runs end to end
// without hardware. `graspbed soak`: both against each other under the soak's faults. docs/hardware.md.
// The sessions themselves live in testbed/ (hw_session, emulator_session, soak_run).

#include <iostream>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "app/command_registry.h"
#include "app/stop_signal.h"
#include "testbed/emulator_session.h"
#include "testbed/hw_session.h"
#include "testbed/soak_run.h"

namespace graspbed::app {
namespace {

/// Exit code after Ctrl-C (128 + SIGINT, the shell convention).
constexpr int kExitInterrupted = 130;

// ---- hw ----------------------------------------------------------------------------------------------

struct HwOptions {
  testbed::HwSessionOptions session;
  bool json = false;
};

void RunHw(const HwOptions& options) {
  const testbed::HwSession session = testbed::PrepareHwSession(options.session);
  // Before the port is opened: Ctrl-C while waiting for HELLO still ends with the port restored.
  StopSignalGuard signals;
  const testbed::HwSessionResult result = testbed::RunHwSession(session, &StopRequested());
  if (options.json) {
    std::cout << result.summary.dump(2) << '\n';
  } else {
    std::cout << testbed::HwSummaryText(result);
  }
  // The run failed (exit 1) when the device was gone at the end or the log could not be completed.
  if (result.failed()) throw CLI::RuntimeError(kExitFailed);  // main() returns it silently
}

// ---- emulate -----------------------------------------------------------------------------------------

struct EmulateOptions {
  testbed::EmulateOptions session;
  bool json = false;
};

void RunEmulate(const EmulateOptions& options) {
  testbed::EmulatorSession session(options.session);
  StopSignalGuard signals;
  const nlohmann::json summary = session.Run(StopRequested(), std::cerr);
  if (options.json) {
    std::cout << summary.dump(2) << '\n';
  } else {
    std::cout << testbed::EmulateSummaryText(summary);
  }
}

// ---- soak ------------------------------------------------------------------------------------------

struct SoakOptions {
  testbed::SoakOptions soak;
  bool json = false;
};

void RunSoak(const SoakOptions& options) {
  const testbed::SoakPlan plan = testbed::PlanSoak(options.soak);
  StopSignalGuard signals;
  const testbed::SoakResult result = testbed::RunSoak(plan, StopRequested(), std::cerr);
  if (result.interrupted) throw CLI::RuntimeError(kExitInterrupted);
  if (options.json) {
    std::cout << result.report.dump(2) << '\n';
  } else {
    std::cout << testbed::SoakReportText(plan, result);
  }
  if (!result.passed) throw CLI::RuntimeError(kExitFailed);
}

void AddHwCommand(CLI::App& root) {
  auto hw_options = std::make_shared<HwOptions>();
  CLI::App* hw = root.add_subcommand(
      "hw", "Run a controller against the tactile readout and hand over a serial link (or the emulator)");
  hw->add_option("--port", hw_options->session.port, "Serial device, e.g. /dev/ttyACM0 or an emulator link");
  hw->add_option("--config", hw_options->session.config,
                 "YAML with serial:, controller:, readout:, inversion: sections (docs/hardware.md)")
      ->check(CLI::ExistingFile);
  hw->add_option("--layout", hw_options->session.layout,
                 "Layout file (default: sensor/layouts/default_20.yaml)");
  hw->add_option("--calibration", hw_options->session.calibration,
                 "Calibration file (default: paper values)");
  hw->add_option(
      "--controller", hw_options->session.controller,
      "Controller: a built-in name or plugin:LIBRARY (default: the controller of --config, else grip_slip)");
  hw->add_option("--param", hw_options->session.params,
                 "Controller parameter NAME=VALUE, as in a scenario's controller.params (repeatable)");
  hw->add_option("--intent", hw_options->session.intent, "Intent once tared: close, open or idle")
      ->capture_default_str();
  hw->add_option("--duration", hw_options->session.duration_s,
                 "Stop cleanly after S seconds (0: until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  hw->add_option("--tare-frames", hw_options->session.tare_frames,
                 "Frames averaged for the tare baseline at start (default: readout.baseline_frames = 100)")
      ->check(CLI::PositiveNumber);
  hw->add_option("--log", hw_options->session.log, "CSV with one row per decoded frame");
  hw->add_flag("--json", hw_options->json, "Print a JSON summary at the end");
  hw->add_option("--realtime-priority", hw_options->session.realtime_priority,
                 "Run the loop and the serial threads under SCHED_FIFO at this priority (1-99), so a busy "
                 "machine cannot delay the answer to a frame; needs root, CAP_SYS_NICE or an rtprio limit")
      ->check(CLI::Range(1, 99));
  hw->add_flag("--latency-report", hw_options->session.latency_report,
               "Measure the loop latency, from each frame's decode to the write of the command that answers "
               "it, and print its p50, p99, p99.9 and max (JSON: \"latency\")");
  hw->callback([hw_options] { RunHw(*hw_options); });
}

void AddEmulateCommand(CLI::App& root) {
  auto emulate_options = std::make_shared<EmulateOptions>();
  CLI::App* emulate = root.add_subcommand(
      "emulate", "Serve the simulated hand as a serial device on a pseudo-terminal (symlinked at --link)");
  emulate->add_option("--link", emulate_options->session.link, "Path of the symlink to create")->required();
  emulate
      ->add_option("scenario", emulate_options->session.scenario, "Scenario YAML (wrist and object script)")
      ->check(CLI::ExistingFile);
  emulate
      ->add_option("--duration", emulate_options->session.duration_s,
                   "Simulated seconds after the host starts streaming (default: the scenario's; "
                   "without a scenario, until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  emulate->add_flag(
      "--json", emulate_options->json,
      "Print a JSON summary at the end: ground truth and run metrics as the host left the hand");
  emulate
      ->add_option("--protocol-version", emulate_options->session.protocol_version,
                   "Highest wire protocol version the device speaks: 2 sends the hand's proprioception "
                   "(HAND) once the host selects it; 1 is a device from before it (docs/protocol.md)")
      ->check(CLI::Range(1, 2))
      ->capture_default_str();
  emulate
      ->add_option("--soak-cycles", emulate_options->session.soak_cycles,
                   "Inject the soak's fault schedule for N cycles from the host's first stream start "
                   "(corrupted, dropped, reordered and truncated frames, garbage, a disconnect and "
                   "reconnect per cycle; docs/hardware.md, \"The soak\"), then pause the stream until the "
                   "host ends the session")
      ->check(CLI::PositiveNumber);
  emulate
      ->add_option("--soak-period", emulate_options->session.soak_period_s,
                   "Length of one soak cycle [s] (>= 5)")
      ->capture_default_str();
  emulate
      ->add_option("--soak-downtime", emulate_options->session.soak_downtime_s,
                   "How long the device stays away at each soak disconnect [s]")
      ->capture_default_str();
  emulate->callback([emulate_options] { RunEmulate(*emulate_options); });
}

void AddSoakCommand(CLI::App& root) {
  auto soak_options = std::make_shared<SoakOptions>();
  CLI::App* soak = root.add_subcommand(
      "soak",
      "Soak the serial path: `graspbed emulate` with the soak's fault schedule against `graspbed run "
      "--backend "
      "serial`; compares the host's counters with what the device injected, exactly, and checks the host's "
      "resident memory stays flat (exit 0 when both hold, 1 otherwise)");
  soak->add_option("scenario", soak_options->soak.scenario,
                   "Scenario YAML for both sides (close/open/idle script)")
      ->required()
      ->check(CLI::ExistingFile);
  soak->add_option("--duration", soak_options->soak.duration_s,
                   "Length of the fault schedule [s], a multiple of --period")
      ->capture_default_str();
  soak->add_option("--period", soak_options->soak.period_s,
                   "One cycle of faults and one disconnect per period [s]")
      ->capture_default_str();
  soak->add_option("--downtime", soak_options->soak.downtime_s,
                   "How long the device stays away each time [s]")
      ->capture_default_str();
  soak->add_option("--link", soak_options->soak.link, "Emulator link path (default /tmp/graspbed-soak-PID)");
  soak->add_option("--out", soak_options->soak.out_dir,
                   "Output directory: soak.json, both summaries and logs")
      ->capture_default_str();
  soak->add_option("--rss-interval", soak_options->soak.rss_interval_s, "Host RSS sampling interval [s]")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 60.0));
  soak->add_flag("--keep-signals", soak_options->soak.keep_signals,
                 "Keep the host's signals.csv (one row per control tick: about 2 GB for 10 minutes)");
  soak->add_flag("--json", soak_options->json, "Print the report (soak.json) on stdout instead of the table");
  soak->callback([soak_options] { RunSoak(*soak_options); });
}

void AddHwCommands(CLI::App& root) {
  AddHwCommand(root);
  AddEmulateCommand(root);
  AddSoakCommand(root);
}

const bool kRegistered = RegisterCommands(&AddHwCommands);

}  // namespace
}  // namespace graspbed::app
