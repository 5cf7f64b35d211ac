#include "controller/control_loop.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "common/config_error.h"

namespace graspbed::controller {

void ControlLoopConfig::Validate() const {
  common::Require(stale_timeout_s > 0.0 && std::isfinite(stale_timeout_s), "control_loop.stale_timeout_s",
                  stale_timeout_s, "must be > 0");
  readout.Validate();
  inversion.Validate();
}

ControlLoop::ControlLoop(sensor::TactileBackend& backend, GraspController& controller,
                         hand::HandActuator& actuator, const sensor::Layout& layout,
                         const sensor::Calibration& calibration, const ControlLoopConfig& config)
    : ControlLoop(backend, no_hand_sensor_, controller, actuator, layout, calibration, config) {}

ControlLoop::ControlLoop(sensor::TactileBackend& backend, hand::HandSensor& hand_sensor,
                         GraspController& controller, hand::HandActuator& actuator, const sensor::Layout& layout,
                         const sensor::Calibration& calibration, const ControlLoopConfig& config)
    : backend_(backend),
      hand_sensor_(hand_sensor),
      controller_(controller),
      actuator_(actuator),
      config_(config),
      readout_(config.readout, layout.unit_count(), backend.nominal_r0_ohm()),
      inversion_(layout, calibration, config.inversion),
      session_(backend.session()) {
  config_.Validate();
  if (backend.unit_count() != layout.unit_count()) {
    throw std::invalid_argument("backend '" + backend.name() + "' delivers " +
                                std::to_string(backend.unit_count()) + " units but the layout '" +
                                layout.name + "' has " + std::to_string(layout.unit_count()));
  }
  state_.unit_count = layout.unit_count();
  state_.stale = true;  // nothing measured yet: a controller must not act on an empty state
}

void ControlLoop::Retare() { readout_.Reset(); }

void ControlLoop::SetBaseline(std::span<const double> r1_ohm, std::span<const double> r2_ohm) {
  readout_.SetBaseline(r1_ohm, r2_ohm);
}

sensor::ReadStatus ControlLoop::Tick(double time_s) {
  ++counters_.ticks;
  const sensor::ReadStatus status = backend_.Read(&frame_);
  last_status_ = status;
  if (status == sensor::ReadStatus::kOk) {
    // A device that rebooted starts a new session: its baseline is no longer ours.
    if (backend_.session() != session_) {
      session_ = backend_.session();
      readout_.Reset();
      ++counters_.retares;
    }
    readout_.Process(frame_, &readout_frame_);
    inversion_.Invert(readout_frame_, &state_);
    last_frame_time_s_ = time_s;
    ++counters_.frames;
  } else if (status == sensor::ReadStatus::kDisconnected) {
    ++counters_.disconnected_ticks;
  }

  const bool stale = status == sensor::ReadStatus::kStale || status == sensor::ReadStatus::kDisconnected ||
                     last_frame_time_s_ < 0.0 || time_s - last_frame_time_s_ > config_.stale_timeout_s;
  state_.stale = stale;
  if (stale) ++counters_.stale_ticks;

  if (hand_sensor_.Read(time_s, &hand_state_)) ++counters_.hand_readings;
  if (hand_state_.digit_count > 0) {
    hand_state_.stale = hand_state_.time_s < 0.0 || time_s - hand_state_.time_s > config_.stale_timeout_s;
    if (hand_state_.stale) ++counters_.hand_stale_ticks;
  }

  command_ = controller_.Update(state_, hand_state_, time_s);
  if (actuator_.Write(command_) != hand::WriteStatus::kOk) ++counters_.actuator_failures;
  return status;
}

}  // namespace graspbed::controller
