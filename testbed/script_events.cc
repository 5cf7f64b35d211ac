#include "testbed/script_events.h"

#include <algorithm>
#include <cmath>

namespace graspbed::testbed {
namespace {

// Ticks are compared in floating-point time; this absorbs the rounding of n * period.
constexpr double kTimeEpsS = 1e-9;

}  // namespace

ScriptEventMonitor::ScriptEventMonitor(const MetricsConfig& metrics, double control_rate_hz)
    : grasp_force_n_(metrics.grasp_force_n),
      stable_band_(metrics.stable_force_band),
      stable_window_s_(metrics.stable_window_s),
      window_fn_(
          static_cast<size_t>(std::max(1.0, std::round(metrics.stable_window_s * control_rate_hz))) + 1,
          0.0) {}

uint32_t ScriptEventMonitor::Update(double time_s, controller::GraspIntent intent,
                                    const sensor::TactileState& state, bool slip_flag) {
  uint32_t events = 0;
  if (slip_flag) {
    events |= EventBit(ScriptEvent::kSlipFlagged);
    last_slip_flag_s_ = time_s;
  }

  // Stale data say nothing about now: both streaks break.
  const bool fresh = !state.stale;
  const bool in_grasp = fresh && state.contact_count >= 1 && state.total_fn_n >= grasp_force_n_;
  const bool free =
      fresh && state.valid_count >= 1 && state.contact_count == 0 && state.total_fn_n < grasp_force_n_;

  if (in_grasp) {
    if (grasp_since_s_ < 0.0) {
      grasp_since_s_ = time_s;
      window_count_ = 0;
    }
    window_fn_[window_next_] = state.total_fn_n;
    window_next_ = (window_next_ + 1) % window_fn_.size();
    window_count_ = std::min(window_count_ + 1, window_fn_.size());
  } else {
    grasp_since_s_ = -1.0;
    window_count_ = 0;
  }
  free_since_s_ = free ? (free_since_s_ < 0.0 ? time_s : free_since_s_) : -1.0;

  const bool grasped = intent == controller::GraspIntent::kClose && grasp_since_s_ >= 0.0 &&
                       time_s - grasp_since_s_ >= kEventConfirmS - kTimeEpsS;
  if (grasped) events |= EventBit(ScriptEvent::kGrasped);

  // Stable: the whole window inside the grasp streak, steady, and no slip flag in it.
  if (grasped && window_count_ == window_fn_.size() &&
      time_s - last_slip_flag_s_ > stable_window_s_ + kTimeEpsS) {
    double sum = 0.0;
    double low = window_fn_[0];
    double high = window_fn_[0];
    for (double fn : window_fn_) {
      sum += fn;
      low = std::min(low, fn);
      high = std::max(high, fn);
    }
    const double mean = sum / static_cast<double>(window_fn_.size());
    if (high <= mean * (1.0 + stable_band_) && low >= mean * (1.0 - stable_band_)) {
      events |= EventBit(ScriptEvent::kStable);
    }
  }

  if (intent == controller::GraspIntent::kOpen && free_since_s_ >= 0.0 &&
      time_s - free_since_s_ >= kEventConfirmS - kTimeEpsS) {
    events |= EventBit(ScriptEvent::kReleased);
  }
  return events;
}

}  // namespace graspbed::testbed
