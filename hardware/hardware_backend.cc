#include "hardware/hardware_backend.h"

namespace graspbed::hardware {

HardwareBackend::HardwareBackend(const HardwareConfig& config, int unit_count, std::string layout_name)
    : link_(std::make_shared<SerialLink>(
          config.port, config, config.motor_port.empty() ? LinkRole::kSensorAndMotor : LinkRole::kSensor,
          unit_count, std::move(layout_name))),
      unit_count_(unit_count) {}

HardwareBackend::~HardwareBackend() { Stop(); }

void HardwareBackend::Start() { link_->Start(); }

void HardwareBackend::Stop() { link_->Stop(); }

sensor::ReadStatus HardwareBackend::Read(sensor::RawFrame* frame) {
  if (link_->TryTakeFrame(frame, &last_id_, &frame_session_)) return sensor::ReadStatus::kOk;
  if (!link_->connected()) return sensor::ReadStatus::kDisconnected;
  const double since_s = link_->SecondsSinceLastFrame();
  if (since_s > link_->config().disconnect_timeout_s) return sensor::ReadStatus::kDisconnected;
  if (since_s > link_->config().stale_timeout_s) return sensor::ReadStatus::kStale;
  return sensor::ReadStatus::kNoNewFrame;
}

double HardwareBackend::nominal_r0_ohm() const {
  const uint32_t r0 = link_->hello().nominal_r0_milliohm;
  return r0 == 0 ? 3400.0 : MilliohmToOhm(r0);
}

HardwareActuator::HardwareActuator(HardwareBackend& backend, const HardwareConfig& config)
    : sensor_link_(backend.link()), owns_link_(!config.motor_port.empty()) {
  link_ = owns_link_ ? std::make_shared<SerialLink>(config.motor_port, config, LinkRole::kMotor, 0, "")
                     : backend.link();
}

HardwareActuator::~HardwareActuator() { Stop(); }

void HardwareActuator::Start() {
  if (owns_link_) link_->Start();
}

hand::WriteStatus HardwareActuator::Write(const hand::HandCommand& command) {
  return link_->SendMotor(command, sensor_link_->taken_frame_arrival_ns());
}

void HardwareActuator::Stop() {
  link_->MotorOff(0.1);
  if (owns_link_) link_->Stop();
}

}  // namespace graspbed::hardware
