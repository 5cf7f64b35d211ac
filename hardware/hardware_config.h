#pragma once
/// Configuration of the serial hardware link: ports, baud, and the timeouts of the handshake, stale
/// detection and reconnection. Plain struct with defaults; YAML loader below (docs/hardware.md).

#include <string>

#include "common/field_table.h"
#include "common/yaml_map.h"

namespace graspbed::hardware {

struct HardwareConfig {
  /// Serial device of the tactile readout (and of the motor, unless motor_port is set), e.g.
  /// /dev/ttyACM0 or the emulator's link.
  std::string port;
  /// Separate serial device for the hand electronics' motor link; "" = the same port as the sensor.
  std::string motor_port;
  int baud = 2000000;                    ///< [bit/s]; 1 kHz x 20 units needs >= 2 Mbaud on a UART
  double hello_timeout_s = 3.0;          ///< Start() gives up when no HELLO came within this [s]
  double stale_timeout_s = 0.05;         ///< no valid frame for this long: ReadStatus::kStale [s]
  double disconnect_timeout_s = 0.5;     ///< no valid frame for this long: kDisconnected [s]
  double reconnect_backoff_s = 0.05;     ///< first wait before reopening a vanished port [s]
  double reconnect_backoff_max_s = 1.0;  ///< the wait doubles up to this [s]
  double poll_interval_s = 0.002;        ///< I/O thread's longest sleep in poll() [s]
  double write_timeout_s = 0.02;         ///< longest wait for room in the output queue [s]

  /// Checks every field against HardwareConfigFields().
  /// @throws common::ConfigError "serial.KEY = VALUE: reason".
  void Validate() const;
};

/// The fields of HardwareConfig (loader, Validate(), emitter and reference table derive from it).
const common::FieldTable<HardwareConfig>& HardwareConfigFields();

/// Reads a hardware config from `map` (keys as the field names; the `serial:` section of a
/// `graspbed hw --config` file, docs/hardware.md "Configuration"); unknown keys are refused.
/// @throws common::ConfigError naming file, line, key and value.
HardwareConfig LoadHardwareConfig(const common::YamlMap& map);

}  // namespace graspbed::hardware
