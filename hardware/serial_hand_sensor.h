#pragma once
/// SerialHandSensor: the hand's proprioception as the serial link receives it (HAND packets, protocol
/// version 2; docs/protocol.md), behind hand::HandSensor. Read() takes the newest HAND the link has
/// published and dates it on the loop's clock by its arrival. A device that speaks only version 1
/// never sends HAND: the state then stays empty (digit_count 0, every field unknown, never a zero),
/// and the loop's stale check marks a hand whose HANDs stop.

#include <cstdint>
#include <memory>
#include <string>

#include "hand/hand_state.h"
#include "hardware/serial_link.h"

namespace graspbed::hardware {

class SerialHandSensor final : public hand::HandSensor {
 public:
  /// Reads the HANDs of `link` (the sensor's link: the port that streams), which must outlive it.
  explicit SerialHandSensor(std::shared_ptr<SerialLink> link);

  /// The newest HAND newer than the last call's, its time_s = loop time `time_s` less its age since
  /// it was decoded [s]. False when none arrived since (also on a version-1 connection). Never
  /// blocks, never allocates. (Times before the loop began count as 0.)
  bool Read(double time_s, hand::HandState* state) override;
  std::string name() const override { return "serial"; }

 private:
  std::shared_ptr<SerialLink> link_;
  hand::HandState scratch_;
  uint64_t last_id_ = 0;
};

}  // namespace graspbed::hardware
