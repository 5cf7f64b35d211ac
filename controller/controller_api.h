#pragma once
/// The controller API version and the C++ plugin entry point: what a controller built outside
/// graspbed (its own CMake project, find_package(graspbed), target graspbed::controller_api)
/// exports so that `controller: {plugin: libmine.so}` or `--controller plugin:libmine.so` loads it.
///
/// Stability: the headers a controller sees (this one, controller/grasp_controller.h,
/// hand/hand_command.h, hand/hand_state.h, sensor/tactile_state.h, sensor/raw_frame.h) form the
/// controller API.
/// Any change a compiled plugin could notice (a virtual added to GraspController, a field added to
/// TactileState, HandState, HandCommand or ControllerTelemetry, a change to GraspbedControllerPlugin after its
/// first field) raises GRASPBED_CONTROLLER_API_VERSION, and graspbed refuses a plugin built against
/// another version instead of calling into it. `api_version` stays the first field of the
/// descriptor in every version, so that check is always safe. A plugin must be built with the same
/// compiler family and C++ standard library as graspbed (the interface passes std::string,
/// std::vector and std::unique_ptr).
///
/// A plugin, in full (examples/cpp_controller/ is a complete project):
///
///     #include "controller/controller_api.h"
///     class MyController : public graspbed::controller::GraspController { ... };
///     std::vector<graspbed::controller::ControllerParameter> MyParameters() {
///       return {{"target_n", 2.0, 0.1, 10.0, "N", "grip force held"}};
///     }
///     std::unique_ptr<graspbed::controller::GraspController> MakeMy(
///         const graspbed::controller::ControllerParams& params) {  // every declared key, validated
///       return std::make_unique<MyController>(params.at("target_n"));
///     }
///     GRASPBED_CONTROLLER_PLUGIN("my_controller", &MyParameters, &MakeMy)

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "controller/grasp_controller.h"

namespace graspbed::controller {

/// What a plugin's make() throws for a parameter it refuses (a combination its ranges cannot say,
/// e.g. a contact threshold above the grip target): graspbed reports it at that parameter in the
/// scenario file, `file:line: controller.params.<parameter> = <value>: <reason>`, and exits 2, as it
/// does for a value out of its declared range. (Any other std::exception from make() is reported
/// too, naming the plugin but no parameter.) Header-only, so a plugin links nothing for it.
class ParameterError : public std::invalid_argument {
 public:
  /// `parameter` a declared name, `value` the value refused, `reason` why ("must be below
  /// target_grip_n = 3").
  ParameterError(std::string parameter, double value, std::string reason)
      : std::invalid_argument(parameter + " = " + std::to_string(value) + ": " + reason),
        parameter_(std::move(parameter)),
        value_(value),
        reason_(std::move(reason)) {}
  const std::string& parameter() const { return parameter_; }
  double value() const { return value_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string parameter_;
  double value_;
  std::string reason_;
};

}  // namespace graspbed::controller

/// Version of the controller API these headers describe (an integer, raised on every change a
/// compiled plugin could notice; see above). Version 1: graspbed 0.1; 2: GraspController's
/// diagnostic_channels() and ReadDiagnostics(); 3: Update() takes the hand's HandState
/// (proprioception) beside the TactileState.
#define GRASPBED_CONTROLLER_API_VERSION 3

/// Name of the symbol every plugin exports (extern "C", returns const GraspbedControllerPlugin*).
#define GRASPBED_CONTROLLER_PLUGIN_SYMBOL "graspbed_controller_plugin"

/// What a plugin library describes itself with. Lives as long as the library (a static object).
struct GraspbedControllerPlugin {
  /// GRASPBED_CONTROLLER_API_VERSION the plugin was compiled against; always the first field.
  int api_version;
  /// Controller name for messages and reports (e.g. "threshold_grip"); a static string.
  const char* name;
  /// The parameters the controller takes, with defaults, ranges and units; graspbed validates a
  /// scenario's controller.params against them exactly as for the built-in controllers. May throw.
  std::vector<graspbed::controller::ControllerParameter> (*parameters)();
  /// Builds a controller from `params`, which holds every declared parameter (defaults filled in,
  /// each in its range). Throws graspbed::controller::ParameterError for a parameter it refuses
  /// (graspbed reports it at that parameter and exits 2); must not return nullptr.
  std::unique_ptr<graspbed::controller::GraspController> (*make)(
      const graspbed::controller::ControllerParams& params);
};

/// Signature of the entry point.
using GraspbedControllerPluginEntry = const GraspbedControllerPlugin* (*)();

/// Defines the plugin's entry point: a controller named `name_literal` whose parameters come from
/// `parameters_function` and which `make_function` builds. Use once per library, at namespace scope.
#define GRASPBED_CONTROLLER_PLUGIN(name_literal, parameters_function, make_function)            \
  extern "C" __attribute__((visibility("default"))) const GraspbedControllerPlugin*             \
  graspbed_controller_plugin() {                                                                \
    static const GraspbedControllerPlugin plugin{GRASPBED_CONTROLLER_API_VERSION, name_literal, \
                                                 parameters_function, make_function};           \
    return &plugin;                                                                             \
  }
