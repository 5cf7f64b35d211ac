#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "common/config_error.h"
#include "controller/constant_grip_controller.h"
#include "controller/grasp_controller.h"
#include "controller/grip_slip_controller.h"
#include "controller/learned_slip_controller.h"
#include "controller/open_loop_controller.h"
#include "controller/plugin_loader.h"

namespace graspbed::controller {
namespace {

/// One controller the factory can build.
struct ControllerEntry {
  std::string name;
  std::vector<ControllerParameter> (*parameters)();
  std::unique_ptr<GraspController> (*make)(const ControllerParams& resolved);
};

/// Every built-in controller. A user's own controller is a plugin (controller/plugin_loader.h).
const std::vector<ControllerEntry>& Entries() {
  static const std::vector<ControllerEntry> entries = {
      {"open_loop", &OpenLoopController::Parameters,
       [](const ControllerParams& p) -> std::unique_ptr<GraspController> {
         return std::make_unique<OpenLoopController>(
             OpenLoopConfig{.close_effort = p.at("close_effort"), .open_effort = p.at("open_effort")});
       }},
      {"constant_grip", &ConstantGripController::Parameters,
       [](const ControllerParams& p) -> std::unique_ptr<GraspController> {
         return std::make_unique<ConstantGripController>(ConstantGripController::ConfigFromParams(p));
       }},
      {"grip_slip", &GripSlipController::Parameters,
       [](const ControllerParams& p) -> std::unique_ptr<GraspController> {
         return std::make_unique<GripSlipController>(GripSlipController::ConfigFromParams(p));
       }},
      {"learned_slip", &LearnedSlipController::Parameters,
       [](const ControllerParams& p) -> std::unique_ptr<GraspController> {
         return std::make_unique<LearnedSlipController>(LearnedSlipController::ConfigFromParams(p));
       }},
  };
  return entries;
}

std::string JoinNames() {
  std::string joined;
  for (const std::string& name : ControllerNames()) joined += (joined.empty() ? "" : ", ") + name;
  return joined;
}

const ControllerEntry& Find(const std::string& name) {
  for (const ControllerEntry& entry : Entries()) {
    if (entry.name == name) return entry;
  }
  throw std::invalid_argument("unknown controller '" + name + "'; valid controllers: " + JoinNames() +
                              ", or plugin:LIBRARY for a controller plugin");
}

}  // namespace

std::vector<std::string> ControllerNames() {
  std::vector<std::string> names;
  for (const ControllerEntry& entry : Entries()) names.push_back(entry.name);
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<ControllerParameter> ControllerParameters(const std::string& name) {
  if (IsPluginName(name)) return LoadPlugin(name).parameters;
  return Find(name).parameters();
}

std::unique_ptr<GraspController> MakeController(const std::string& name, const ControllerParams& params) {
  // A plugin is checked exactly like a built-in: its declared parameters, then its own make().
  const LoadedPlugin* plugin = IsPluginName(name) ? &LoadPlugin(name) : nullptr;
  const ControllerEntry* entry = plugin == nullptr ? &Find(name) : nullptr;
  const std::vector<ControllerParameter> declared =
      plugin != nullptr ? plugin->parameters : entry->parameters();
  ControllerParams resolved;
  for (const ControllerParameter& parameter : declared) resolved[parameter.name] = parameter.default_value;
  for (const auto& [key, value] : params) {
    const auto match = std::find_if(declared.begin(), declared.end(),
                                    // Captured by name: clang 14 (the fuzz tree's) refuses a structured binding in a lambda.
                                    [&key = key](const ControllerParameter& p) { return p.name == key; });
    if (match == declared.end()) {
      std::string valid;
      for (const ControllerParameter& p : declared) valid += (valid.empty() ? "" : ", ") + p.name;
      throw common::ConfigError("", 0, key, std::nullopt, "no such parameter; valid parameters: " + valid)
          .WithContext("controller '" + name + "'");
    }
    if (!std::isfinite(value) || value < match->min || value > match->max) {
      std::ostringstream range;
      range << "must be in [" << match->min << ", " << match->max << "] " << match->unit;
      throw common::ConfigError("", 0, key, common::ReadableNumber(value), range.str())
          .WithContext("controller '" + name + "'");
    }
    resolved[key] = value;
  }
  return plugin != nullptr ? MakePluginController(*plugin, resolved) : entry->make(resolved);
}

}  // namespace graspbed::controller
