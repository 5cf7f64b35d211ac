#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "controller/grasp_controller.h"
#include "controller/grip_slip_controller.h"
#include "controller/open_loop_controller.h"

namespace graspbed::controller {
namespace {

/// One controller the factory can build.
struct ControllerEntry {
  std::string name;
  std::vector<ControllerParameter> (*parameters)();
  std::unique_ptr<GraspController> (*make)(const ControllerParams& resolved);
};

/// Every built-in controller; a user's own controller is added here with one line.
const std::vector<ControllerEntry>& Entries() {
  static const std::vector<ControllerEntry> entries = {
      {"open_loop", &OpenLoopController::Parameters,
       [](const ControllerParams& p) -> std::unique_ptr<GraspController> {
         return std::make_unique<OpenLoopController>(
             OpenLoopConfig{.close_effort = p.at("close_effort"), .open_effort = p.at("open_effort")});
       }},
      {"grip_slip", &GripSlipController::Parameters,
       [](const ControllerParams& p) -> std::unique_ptr<GraspController> {
         return std::make_unique<GripSlipController>(GripSlipController::ConfigFromParams(p));
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
  throw std::invalid_argument("unknown controller '" + name + "'; valid controllers: " + JoinNames());
}

}  // namespace

std::vector<std::string> ControllerNames() {
  std::vector<std::string> names;
  for (const ControllerEntry& entry : Entries()) names.push_back(entry.name);
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<ControllerParameter> ControllerParameters(const std::string& name) {
  return Find(name).parameters();
}

std::unique_ptr<GraspController> MakeController(const std::string& name, const ControllerParams& params) {
  const ControllerEntry& entry = Find(name);
  const std::vector<ControllerParameter> declared = entry.parameters();
  ControllerParams resolved;
  for (const ControllerParameter& parameter : declared) resolved[parameter.name] = parameter.default_value;
  for (const auto& [key, value] : params) {
    const auto match = std::find_if(declared.begin(), declared.end(),
                                    [&](const ControllerParameter& p) { return p.name == key; });
    if (match == declared.end()) {
      std::string valid;
      for (const ControllerParameter& p : declared) valid += (valid.empty() ? "" : ", ") + p.name;
      throw std::invalid_argument("controller '" + name + "' has no parameter '" + key +
                                  "'; valid parameters: " + valid);
    }
    if (!std::isfinite(value) || value < match->min || value > match->max) {
      std::ostringstream message;
      message << "controller '" << name << "' parameter " << key << " = " << value << ": must be in ["
              << match->min << ", " << match->max << "] " << match->unit;
      throw std::invalid_argument(message.str());
    }
    resolved[key] = value;
  }
  return entry.make(resolved);
}

}  // namespace graspbed::controller
