/// A built-in controller's declared parameters bound to the fields of its config struct: one table
/// per controller gives its Parameters() (names, defaults, ranges, units, docs), fills its config
/// from a scenario's controller.params and checks the config's ranges.
#pragma once

#include <cmath>
#include <span>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "common/config_error.h"
#include "controller/grasp_controller.h"

namespace graspbed::controller {

/// One declared parameter bound to a field of `Config` (GRASPBED_BIND_PARAMETER writes one).
template <typename Config>
struct ParameterBinding {
  const char* name;
  const char* member;  ///< the Config member it sets, as written ("slip.settle_s")
  double min;
  double max;
  const char* unit;
  const char* doc;
  bool integer;  ///< the field is an int or a bool: the value must be a whole number
  double (*get)(const Config&);
  void (*set)(Config&, double);
};

/// Binds parameter `name` to `Config`'s `field` in one line; ints and bools take whole numbers.
#define GRASPBED_BIND_PARAMETER(Config, name, field, min, max, unit, doc)                        \
  ::graspbed::controller::ParameterBinding<Config> {                                             \
    name, #field, min, max, unit, doc, std::is_integral_v<decltype(Config{}.field)>,             \
        [](const Config& c) { return static_cast<double>(c.field); }, [](Config& c, double v) { \
          using Field = decltype(Config{}.field);                                                \
          if constexpr (std::is_same_v<Field, bool>) {                                           \
            c.field = v != 0.0;                                                                  \
          } else if constexpr (std::is_integral_v<Field>) {                                      \
            c.field = static_cast<Field>(std::lround(v));                                        \
          } else {                                                                               \
            c.field = v;                                                                         \
          }                                                                                      \
        }                                                                                        \
  }

/// The declared parameters with `Config{}`'s values as their defaults.
template <typename Config>
std::vector<ControllerParameter> DescribeParameters(std::span<const ParameterBinding<Config>> bindings) {
  const Config defaults;
  std::vector<ControllerParameter> parameters;
  for (const ParameterBinding<Config>& b : bindings)
    parameters.push_back({b.name, b.get(defaults), b.min, b.max, b.unit, b.doc});
  return parameters;
}

/// Sets the fields of `config` that `params` names.
/// @throws common::ConfigError (key: the parameter) for a fraction given to an integer field.
template <typename Config>
void ApplyParameters(std::span<const ParameterBinding<Config>> bindings, const ControllerParams& params,
                     Config* config) {
  for (const ParameterBinding<Config>& b : bindings) {
    const auto found = params.find(b.name);
    if (found == params.end()) continue;
    const double value = found->second;
    if (b.integer && !(std::isfinite(value) && value == std::round(value)))
      throw common::ConfigError("", 0, b.name, common::ReadableNumber(value), "must be a whole number");
    b.set(*config, value);
  }
}

/// Checks every bound field of `config` against its declared range.
/// @throws common::ConfigError (key: the parameter) "must be in [min, max] unit".
template <typename Config>
void RequireParametersInRange(std::span<const ParameterBinding<Config>> bindings, const Config& config) {
  for (const ParameterBinding<Config>& b : bindings) {
    const double value = b.get(config);
    std::ostringstream range;
    range << "must be in [" << b.min << ", " << b.max << "] " << b.unit;
    common::Require(std::isfinite(value) && value >= b.min && value <= b.max, b.name, value, range.str());
  }
}

}  // namespace graspbed::controller
