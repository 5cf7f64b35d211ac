#pragma once
/// GraspController: the pluggable decision maker. It sees only TactileState, the hand's own state
/// (HandState: joint positions, motor currents), time and the user's intent (close / open), never
/// MuJoCo, serial ports or ground truth, so the same controller runs in simulation and on the hand. Part of the controller API (controller/controller_api.h: its
/// version, GRASPBED_CONTROLLER_API_VERSION, and how a plugin exports a controller).

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hand/hand_command.h"
#include "hand/hand_state.h"
#include "sensor/tactile_state.h"

namespace graspbed::controller {

/// The controller's output. It is defined below controller/ (hand/hand_command.h) so that sim/ and
/// hardware/ carry it without linking the controller library; this name keeps the controller API's
/// spelling (plugins, the Python module) unchanged.
using HandCommand = hand::HandCommand;

/// What the user (EMG, a button, a scenario script) currently asks the hand to do.
enum class GraspIntent { kIdle, kClose, kOpen };

/// The intent's name in scripts, logs, the terminal and the Python API: "idle", "close" or "open".
inline const char* ToString(GraspIntent intent) {
  switch (intent) {
    case GraspIntent::kClose:
      return "close";
    case GraspIntent::kOpen:
      return "open";
    case GraspIntent::kIdle:
      break;
  }
  return "idle";
}

/// The intent named `name` ("idle", "close", "open"); nullopt for any other text.
inline std::optional<GraspIntent> IntentFromName(std::string_view name) {
  for (const GraspIntent intent : {GraspIntent::kIdle, GraspIntent::kClose, GraspIntent::kOpen}) {
    if (name == ToString(intent)) return intent;
  }
  return std::nullopt;
}

/// Controller state exposed for logging and plots; fixed size, filled every update.
struct ControllerTelemetry {
  const char* phase = "idle";      ///< static string naming the current phase
  double grip_target_n = 0.0;      ///< grip force the controller aims for [N]
  double friction_estimate = 0.0;  ///< current estimate of the contact friction coefficient
  bool slip_detected = false;      ///< slip detected at this update
  /// Static string naming the cues behind slip_detected ("ratio", "vibration+centroid", ...;
  /// "" when none fired or the controller does not say).
  const char* slip_cues = "";
  int slip_events = 0;     ///< slip events since Reset()
  bool safe_hold = false;  ///< holding because data are stale or too few units are valid
};

/// One internal signal a controller logs beside its telemetry (a cue's statistic, its threshold):
/// column "ctl_<name>" of signals.csv on every backend, so a flag can be traced to what raised it.
struct DiagnosticChannel {
  /// Static; lower-case letters, digits and '_', ending in its unit ("vibration_rms_n", "load_ratio").
  const char* name;
  const char* doc;  ///< static; what it is, with its unit
};

/// Most diagnostic channels a controller may declare (their columns are reserved with the run's).
inline constexpr size_t kMaxDiagnosticChannels = 32;

/// One tunable parameter of a controller: its name, default, unit and meaning (for docs and
/// validation of scenario files).
struct ControllerParameter {
  std::string name;
  double default_value = 0.0;
  double min = 0.0;
  double max = 0.0;
  std::string unit;
  std::string doc;
};

/// Parameter values by name, as given in a scenario's controller.params (validated by the factory).
using ControllerParams = std::map<std::string, double>;

class GraspController {
 public:
  virtual ~GraspController() = default;

  /// Back to the initial state (hand considered open, no contact, estimates reset).
  virtual void Reset() = 0;
  /// Sets the user's intent; takes effect at the next Update().
  virtual void SetIntent(GraspIntent intent) = 0;
  /// One control tick at `time_s` [s] with the newest tactile state and the newest hand state
  /// (check its `known` flags: a backend without proprioception leaves them false); returns the
  /// motor command. Must not allocate.
  virtual hand::HandCommand Update(const sensor::TactileState& state, const hand::HandState& hand,
                                   double time_s) = 0;
  /// Grip force ceiling for this task [N] (fragile objects); never exceeded on purpose.
  virtual void SetGripCeiling(double ceiling_n) = 0;
  virtual ControllerTelemetry telemetry() const = 0;
  virtual std::string name() const = 0;
  /// The internal signals this controller logs (none by default); the same for its lifetime, at most
  /// kMaxDiagnosticChannels, names unique.
  virtual std::span<const DiagnosticChannel> diagnostic_channels() const { return {}; }
  /// Their values after the latest Update() into `values`, in the order of diagnostic_channels()
  /// (values.size() is their count). Must not allocate.
  virtual void ReadDiagnostics(std::span<double> values) const { (void)values; }
};

/// Names of the built-in controllers, sorted. Any "plugin:LIBRARY" name is valid besides them
/// (controller/plugin_loader.h). These three functions are graspbed's side, not part of the plugin API.
std::vector<std::string> ControllerNames();
/// The parameters (with defaults) of controller `name` (built-in or "plugin:..."); throws
/// std::invalid_argument on an unknown name, listing the valid ones, or a plugin that does not load.
std::vector<ControllerParameter> ControllerParameters(const std::string& name);
/// Builds controller `name` with `params` (unknown or out-of-range parameters throw
/// std::invalid_argument naming the parameter, value and range).
std::unique_ptr<GraspController> MakeController(const std::string& name, const ControllerParams& params);

}  // namespace graspbed::controller
