#include "sim/sim_rig.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/config_error.h"
#include "sim/scene_check.h"

namespace graspbed::sim {

void SimRigConfig::Validate() const {
  scene.Validate();
  backend.Validate();
  loop.Validate();
  common::Require(control_rate_hz > 0.0 && std::isfinite(control_rate_hz), "control_rate_hz", control_rate_hz,
                  "must be > 0");
}

SimRig::SimRig(const sensor::Layout& layout, const sensor::Calibration& calibration,
               const SimRigConfig& config, std::unique_ptr<controller::GraspController> controller)
    : config_((config.Validate(), config)),
      simulation_(layout, config_.scene),
      backend_(simulation_, config_.backend, config_.seed),
      actuator_(simulation_),
      controller_(controller ? std::move(controller)
                             : throw std::invalid_argument("SimRig needs a controller")),
      loop_(backend_, *controller_, actuator_, layout, calibration, config_.loop) {
  // Bodies that start inside each other make a result out of bad input (a pinch of hundreds of N).
  CheckInitialPenetration(simulation_);
}

bool SimRig::Step() {
  simulation_.Step();
  backend_.Poll();
  const double period = 1.0 / config_.control_rate_hz;
  // Same slack as the backend's sampling, so a 1 kHz loop sees each 1 kHz frame at once.
  if (static_cast<double>(control_index_) * period > simulation_.time_s() + 1e-6 * period) return false;
  while (static_cast<double>(control_index_) * period <= simulation_.time_s() + 1e-6 * period)
    ++control_index_;
  loop_.Tick(simulation_.time_s());
  return true;
}

void SimRig::AdvanceTo(double time_s) {
  // A fault ends the run; Simulation::Step() advances the clock regardless, so this always ends.
  while (!simulation_.fault().occurred && simulation_.time_s() < time_s - 0.5 * simulation_.timestep_s())
    Step();
}

}  // namespace graspbed::sim
