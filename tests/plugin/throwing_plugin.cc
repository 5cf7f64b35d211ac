// A plugin whose make() throws something other than std::invalid_argument (a controller that cannot
// be built, e.g. a model file it needs is missing): graspbed reports it as bad input, never crashes.
#include <stdexcept>

#include "controller/controller_api.h"

namespace {

std::vector<graspbed::controller::ControllerParameter> Parameters() {
  return {{"gain", 1.0, 0.0, 2.0, "", "unused"}};
}

std::unique_ptr<graspbed::controller::GraspController> Make(const graspbed::controller::ControllerParams&) {
  throw std::runtime_error("cannot open weights.bin");
}

}  // namespace

GRASPBED_CONTROLLER_PLUGIN("throws_when_built", &Parameters, &Make)
