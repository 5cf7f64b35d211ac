#include "hardware/serial_hand_sensor.h"

#include <algorithm>
#include <chrono>
#include <utility>

namespace graspbed::hardware {

SerialHandSensor::SerialHandSensor(std::shared_ptr<SerialLink> link) : link_(std::move(link)) {}

bool SerialHandSensor::Read(double time_s, hand::HandState* state) {
  int64_t arrival_ns = 0;
  if (!link_->TryTakeHand(&scratch_, &last_id_, &arrival_ns)) return false;
  const int64_t now_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                             std::chrono::steady_clock::now().time_since_epoch())
                             .count();
  *state = scratch_;
  // The device's clock is not the loop's: the sample is dated by when its last byte was read.
  // (Not before the loop's clock began: a HAND read before the session's first tick counts from 0.)
  state->time_s =
      std::max(0.0, time_s - static_cast<double>(std::max<int64_t>(0, now_ns - arrival_ns)) * 1e-9);
  state->stale = false;
  return true;
}

}  // namespace graspbed::hardware
