#include "sim/sim_rig.h"

#include <algorithm>
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
  proprioception.Validate();
  loop.Validate();
  common::Require(control_rate_hz > 0.0 && std::isfinite(control_rate_hz), "control_rate_hz", control_rate_hz,
                  "must be > 0");
}

SimRig::SimRig(const sensor::Layout& layout, const sensor::Calibration& calibration,
               const SimRigConfig& config, std::unique_ptr<controller::GraspController> controller)
    : config_((config.Validate(), config)),
      simulation_(layout, config_.scene),
      backend_(simulation_, config_.backend, config_.seed),
      hand_sensor_(simulation_, config_.proprioception, config_.seed),
      actuator_(simulation_),
      controller_(controller ? std::move(controller)
                             : throw std::invalid_argument("SimRig needs a controller")),
      loop_(backend_, hand_sensor_, *controller_, actuator_, layout, calibration, config_.loop) {
  // Bodies that start inside each other make a result out of bad input (a pinch of hundreds of N).
  CheckInitialPenetration(simulation_);
}

bool SimRig::Step() {
  const double period = 1.0 / config_.control_rate_hz;
  // Absorbs floating-point sums of timesteps, so a 1 kHz loop sees each 1 kHz frame at once.
  const double slack = 1e-6 * period;
  const double next_tick_s = static_cast<double>(control_index_) * period;
  const double physics_s = simulation_.time_s();
  if (next_tick_s > physics_s + slack && next_tick_s < physics_s + simulation_.timestep_s() - slack) {
    clock_s_ = next_tick_s;
  } else {
    simulation_.Step();
    clock_s_ = simulation_.time_s();
  }
  backend_.Poll(clock_s_);
  hand_sensor_.Poll(clock_s_);
  if (next_tick_s > clock_s_ + slack) return false;
  while (static_cast<double>(control_index_) * period <= clock_s_ + slack) ++control_index_;
  loop_.Tick(clock_s_);
  return true;
}

void SimRig::AdvanceTo(double time_s) {
  // A fault ends the run; Simulation::Step() advances the clock regardless, so this always ends.
  const double half_step_s = 0.5 * std::min(simulation_.timestep_s(), 1.0 / config_.control_rate_hz);
  while (!simulation_.fault().occurred && clock_s_ < time_s - half_step_s) Step();
}

}  // namespace graspbed::sim
