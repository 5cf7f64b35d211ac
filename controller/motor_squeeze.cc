#include "controller/motor_squeeze.h"

#include <algorithm>
#include <cmath>

namespace graspbed::controller {
namespace {

/// Weight of a new sample in a first-order low-pass of time constant `tau_s` after `dt_s`.
double Weight(double tau_s, double dt_s) { return tau_s > 0.0 ? 1.0 - std::exp(-dt_s / tau_s) : 1.0; }

/// Every known joint of the hand turns slower than `max_speed` [rad/s] (slides: x 1 rad/m).
bool Still(const hand::HandState& hand, double max_speed) {
  for (int d = 0; d < hand.digit_count; ++d) {
    const hand::DigitState& digit = hand.digits[d];
    if (!digit.velocity_known) continue;
    for (int j = 0; j < digit.joint_count; ++j) {
      if (std::abs(digit.joint_velocity[j]) > max_speed) return false;
    }
  }
  return true;
}

}  // namespace

void MotorSqueeze::Reset() {
  offset_share_ = 0.0;
  known_ = false;
  squeeze_n_ = 0.0;
  closed_on_nothing_ = false;
  RestartShare();
}

void MotorSqueeze::RestartShare() {
  share_ = 1.0;
  share_measured_ = false;
}

void MotorSqueeze::Update(const hand::HandState& hand, double last_effort, double sensed_grip_n, bool calm,
                          double dt_s) {
  const hand::DigitState& index = hand.digits[0];
  closed_on_nothing_ = hand.digit_count > 0 && !hand.stale && index.stops_known && index.at_closed_stop;
  // The index's own motor: the units are on its pad, and the thumb's current also carries what its
  // joint's creep under the load back-drives.
  known_ = hand.digit_count > 0 && !hand.stale && index.current_known && index.stall_current_a > 0.0;
  if (!known_) {
    squeeze_n_ = 0.0;
    return;
  }
  const double share = index.motor_current_a / index.stall_current_a;
  const bool still = Still(hand, config_.max_joint_speed_rad_s);
  // Motor off and digits still: whatever current flows is the sensing chain's offset.
  if (last_effort == 0.0 && still) offset_share_ += Weight(config_.offset_filter_s, dt_s) * (share - offset_share_);
  squeeze_n_ = std::max(0.0, share - offset_share_) * config_.stall_pinch_n;
  if (!calm || !still || squeeze_n_ < config_.min_squeeze_n || last_effort <= 0.0) return;
  const double seen = std::clamp(sensed_grip_n / squeeze_n_, config_.min_sensed_share, 1.0);
  share_ = share_measured_ ? share_ + Weight(config_.share_filter_s, dt_s) * (seen - share_) : seen;
  share_measured_ = true;
}

}  // namespace graspbed::controller
