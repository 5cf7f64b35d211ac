#pragma once
/// HardwareBackend (sensor::TactileBackend) and HardwareActuator (hand::HandActuator) on the
/// serial link to the real readout and hand electronics: one port for both, or a second port for
/// the motor (HardwareConfig::motor_port). All port I/O happens on the links' own threads; Read()
/// and Write() only exchange data with them and never block.

#include <memory>
#include <string>

#include "hand/hand_command.h"
#include "sensor/tactile_backend.h"
#include "hardware/hardware_config.h"
#include "hardware/serial_link.h"

namespace graspbed::hardware {

class HardwareBackend : public sensor::TactileBackend {
 public:
  /// `unit_count` and `layout_name` describe the configured layout the device must match.
  HardwareBackend(const HardwareConfig& config, int unit_count, std::string layout_name);
  ~HardwareBackend() override;

  /// Opens the port and completes the handshake (HELLO, unit check, stream start). Throws
  /// PortError (missing, permission, busy) or std::runtime_error (no HELLO, unit-count mismatch).
  void Start() override;
  /// Stream stop, motor off (when the motor shares the port), restore and close the port.
  void Stop() override;
  /// kOk with the newest frame; kNoNewFrame; kStale after stale_timeout_s without a valid frame;
  /// kDisconnected when the port is gone, the device was refused, or after disconnect_timeout_s.
  sensor::ReadStatus Read(sensor::RawFrame* frame) override;
  int unit_count() const override { return unit_count_; }
  /// From the device's HELLO (3400 Ohm until one arrived or when it reports 0).
  double nominal_r0_ohm() const override;
  /// The device session of the newest frame Read() returned (the link's current one before any):
  /// a frame still in the slot from before a reboot does not count as the new session's.
  uint64_t session() const override { return frame_session_ != 0 ? frame_session_ : link_->session(); }
  sensor::BackendCounters counters() const override { return link_->counters(); }
  std::string name() const override { return "serial"; }

  /// The link underneath (for the actuator when it shares the port, taps and diagnostics).
  const std::shared_ptr<SerialLink>& link() const { return link_; }

 private:
  std::shared_ptr<SerialLink> link_;
  int unit_count_;
  uint64_t last_id_ = 0;
  uint64_t frame_session_ = 0;
};

class HardwareActuator : public hand::HandActuator {
 public:
  /// Shares `backend`'s port when config.motor_port is empty, else uses a link of its own on
  /// motor_port (opened by Start()).
  HardwareActuator(HardwareBackend& backend, const HardwareConfig& config);
  ~HardwareActuator() override;

  /// Opens the motor port when it is separate (same errors as HardwareBackend::Start); no-op when
  /// the port is shared.
  void Start();
  /// Queues a MOTOR_COMMAND; kDisconnected while the device has not said HELLO on this connection.
  hand::WriteStatus Write(const hand::HandCommand& command) override;
  /// Motor off (waits up to 0.1 s for it to be written); closes a separate motor port.
  void Stop() override;
  std::string name() const override { return "serial"; }

  const std::shared_ptr<SerialLink>& link() const { return link_; }

 private:
  std::shared_ptr<SerialLink> link_;
  std::shared_ptr<SerialLink> sensor_link_;  // the backend's: when the frame a command answers arrived
  bool owns_link_;
};

}  // namespace graspbed::hardware
