// What a plugin compiled against graspbed's controller API version 2 (before Update took the
// HandState) exports: its descriptor's first field says 2. graspbed refuses it before reading
// anything past api_version (parameters and make are deliberately null).
#include "controller/controller_api.h"

static_assert(GRASPBED_CONTROLLER_API_VERSION > 2, "this library stands for a plugin of an older API");

extern "C" __attribute__((visibility("default"))) const GraspbedControllerPlugin*
graspbed_controller_plugin() {
  static const GraspbedControllerPlugin plugin{2, "from_api_2", nullptr, nullptr};
  return &plugin;
}
