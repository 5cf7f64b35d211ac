#pragma once
/// SimRig: one simulated run wired up: Simulation -> SimBackend -> ControlLoop (readout, inversion,
/// controller) -> SimActuator -> Simulation, with the simulated clock driving it. Scenario runs,
/// tests and the benchmark use it; scripts reach the pieces through the accessors.

#include <cstdint>
#include <memory>

#include "controller/control_loop.h"
#include "controller/grasp_controller.h"
#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "sim/proprioception.h"
#include "sim/scene_config.h"
#include "sim/sim_actuator.h"
#include "sim/sim_backend.h"
#include "sim/simulation.h"

namespace graspbed::sim {

/// Rates and settings of a rig.
struct SimRigConfig {
  SceneConfig scene;
  SimBackendConfig backend;
  ProprioceptionConfig proprioception;  ///< the hand's encoders and current sensing
  controller::ControlLoopConfig loop;
  double control_rate_hz = 1000.0;  ///< ControlLoop::Tick() rate on the simulated clock [Hz]
  uint64_t seed = 1;                ///< seeds the sensor model and frame drops

  /// @throws common::ConfigError naming the field (key path) and value.
  void Validate() const;
};

/// Owns the simulation, backend, actuator and loop of one run. Not copyable, not movable.
class SimRig {
 public:
  /// `controller` is taken over; `layout` and `calibration` are copied where needed and must match.
  /// Throws std::invalid_argument for a bad config or a scene whose bodies start inside each other
  /// (CheckInitialPenetration).
  SimRig(const sensor::Layout& layout, const sensor::Calibration& calibration, const SimRigConfig& config,
         std::unique_ptr<controller::GraspController> controller);
  SimRig(const SimRig&) = delete;
  SimRig& operator=(const SimRig&) = delete;

  /// Steps until time_s() >= `time_s` [s], polling the sensor and ticking the control loop at the
  /// control rate; returns early at a physics fault (simulation().fault()). Allocates nothing.
  void AdvanceTo(double time_s);
  /// Advances the rig's clock to the next physics step's end or, when a control instant falls before
  /// it (a physics step longer than the control period), to that instant without stepping the
  /// physics: there the sensor samples the last step's contact forces (zero-order hold) and the
  /// loop ticks, as the real loop does between the hand's physical changes. Polls the sensor and
  /// ticks the control loop when due; returns true when it ticked.
  bool Step();
  /// The rig's clock [s]: the control loop's and the sensor's time. The physics may be one step
  /// behind it (simulation().time_s()) between physics steps.
  double time_s() const { return clock_s_; }
  Simulation& simulation() { return simulation_; }
  SimBackend& backend() { return backend_; }
  /// The hand's simulated proprioception (fault injection: SetEncoderStuck).
  SimHandSensor& hand_sensor() { return hand_sensor_; }
  SimActuator& actuator() { return actuator_; }
  controller::GraspController& controller() { return *controller_; }
  controller::ControlLoop& loop() { return loop_; }
  const SimRigConfig& config() const { return config_; }

 private:
  SimRigConfig config_;
  Simulation simulation_;
  SimBackend backend_;
  SimHandSensor hand_sensor_;
  SimActuator actuator_;
  std::unique_ptr<controller::GraspController> controller_;
  controller::ControlLoop loop_;
  int64_t control_index_ = 0;  ///< next control tick: time = control_index_ / control_rate_hz
  double clock_s_ = 0.0;       ///< time_s()
};

}  // namespace graspbed::sim
