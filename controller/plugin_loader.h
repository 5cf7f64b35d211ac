#pragma once
/// Controllers from shared libraries (C++ plugins, controller/controller_api.h). A controller name
/// "plugin:LIBRARY" names one: MakeController, ControllerParameters and everything built on them
/// (scenario files, run, suite, sweep, score, hw) take it like a built-in name.
///
/// LIBRARY is a path (it contains a '/': absolute, or relative to the scenario file that names it,
/// or to the working directory on the command line; see ResolvePluginName) or a bare name looked
/// up as NAME and libNAME.so in each directory of $GRASPBED_PLUGIN_PATH (':'-separated), then in
/// <prefix>/lib/graspbed/plugins of the running graspbed. A library is loaded once per process and
/// never unloaded (controllers built from it may outlive any one run).

#include <string>
#include <string_view>
#include <vector>

#include "controller/controller_api.h"
#include "controller/grasp_controller.h"

namespace graspbed::controller {

/// Prefix of a controller name that names a plugin library.
inline constexpr std::string_view kPluginPrefix = "plugin:";

/// True for "plugin:...".
bool IsPluginName(const std::string& name);

/// For a plugin name whose library is a relative path, the same name with the path made absolute
/// against `base_dir`; any other name unchanged (bare library names are searched for at load).
std::string ResolvePluginName(const std::string& name, const std::string& base_dir);

/// Directories searched for a bare library name, in order.
std::vector<std::string> PluginSearchPath();

/// A loaded, checked plugin.
struct LoadedPlugin {
  std::string path;                             ///< absolute path of the library
  std::string name;                             ///< the controller name it declares
  std::vector<ControllerParameter> parameters;  ///< as declared (checked: min <= default <= max)
  const GraspbedControllerPlugin* descriptor = nullptr;
};

/// Loads (once) and checks the library of `plugin_name` ("plugin:..."). Throws std::invalid_argument
/// naming the library when it is missing, cannot be loaded, exports no
/// GRASPBED_CONTROLLER_PLUGIN_SYMBOL, was built against another GRASPBED_CONTROLLER_API_VERSION,
/// describes itself incompletely, or its parameters() throws. Thread-safe.
const LoadedPlugin& LoadPlugin(const std::string& plugin_name);

/// Builds the plugin's controller from fully resolved, validated `params`. Anything the plugin's
/// make() throws, or a null controller, becomes std::invalid_argument naming the plugin.
std::unique_ptr<GraspController> MakePluginController(const LoadedPlugin& plugin,
                                                      const ControllerParams& params);

}  // namespace graspbed::controller
