#pragma once
/// ScriptEventMonitor: decides once per control tick which script events (ScriptEvent) hold, from
/// what a run can know without ground truth: the script's intent, the sensor estimate and the
/// controller's slip flag. The same definitions hold on hardware, where there is no truth to ask.
/// Allocates only in the constructor.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "controller/grasp_controller.h"
#include "sensor/tactile_state.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {

/// Bit of `event` in a ScriptEventMonitor::Update result (0 for kNone).
constexpr uint32_t EventBit(ScriptEvent event) {
  return event == ScriptEvent::kNone ? 0u : 1u << static_cast<unsigned>(event);
}

class ScriptEventMonitor {
 public:
  /// Thresholds from `metrics` (grasp_force_n, stable_window_s, stable_force_band); `control_rate_hz`
  /// sizes the stable window's history.
  ScriptEventMonitor(const MetricsConfig& metrics, double control_rate_hz);

  /// One control tick at `time_s` [s]: returns the EventBit()s of the events that hold now.
  /// Allocates nothing.
  uint32_t Update(double time_s, controller::GraspIntent intent, const sensor::TactileState& state,
                  bool slip_flag);

 private:
  double grasp_force_n_;
  double stable_band_;
  double stable_window_s_;
  double grasp_since_s_ = -1.0;  ///< start of the current in-grasp streak (< 0: none)
  double free_since_s_ = -1.0;   ///< start of the current no-load streak (< 0: none)
  double last_slip_flag_s_ = -1e9;
  std::vector<double> window_fn_;  ///< estimated total Fn of the last ticks, a ring [N]
  size_t window_next_ = 0;
  size_t window_count_ = 0;  ///< ticks of the current in-grasp streak held in the ring
};

}  // namespace graspbed::testbed
