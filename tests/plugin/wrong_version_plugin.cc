// A plugin built against a controller API version graspbed does not have: refused before anything
// past api_version is read (parameters and make are deliberately null).
#include "controller/controller_api.h"

extern "C" __attribute__((visibility("default"))) const GraspbedControllerPlugin*
graspbed_controller_plugin() {
  static const GraspbedControllerPlugin plugin{GRASPBED_CONTROLLER_API_VERSION + 1, "from_the_future",
                                               nullptr, nullptr};
  return &plugin;
}
