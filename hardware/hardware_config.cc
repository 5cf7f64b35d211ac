#include "hardware/hardware_config.h"

#include "hardware/serial_port.h"

namespace graspbed::hardware {

const common::FieldTable<HardwareConfig>& HardwareConfigFields() {
  using Table = common::FieldTable<HardwareConfig>;
  using C = HardwareConfig;
  using common::NumberRule;
  const NumberRule positive = NumberRule::Positive();
  static const Table table(
      "serial",
      {
          Table::Text("port", &C::port, {},
                      "the device of the tactile readout (and of the motor unless `motor_port` is set); "
                      "`--port` wins"),
          Table::Text("motor_port", &C::motor_port, {},
                      "a separate device for the hand electronics (\"\" = the sensor's port); it gets its "
                      "own link and I/O thread, waits for its own HELLO, is never asked to stream, and "
                      "its unit count is not checked"),
          Table::Integer("baud", &C::baud, 1, 4000000, "bit/s",
                         "a standard termios rate; 1 kHz x 20 units is about 175 kB/s, so a UART needs >= 2 "
                         "Mbaud (USB CDC ignores it)")
              .Note("a standard rate from 9600"),
          Table::Number("hello_timeout_s", &C::hello_timeout_s, positive, "s",
                        "`hw` gives up when no HELLO arrives this long after opening the port (the device "
                        "sends one every second)"),
          Table::Number("stale_timeout_s", &C::stale_timeout_s, positive, "s",
                        "no valid frame for this long: `Read()` says `kStale`, and one stale period is "
                        "counted"),
          Table::Number("disconnect_timeout_s", &C::disconnect_timeout_s, positive, "s",
                        "no valid frame for this long: `Read()` says `kDisconnected`")
              .Note("> `stale_timeout_s`"),
          Table::Number("reconnect_backoff_s", &C::reconnect_backoff_s, positive, "s",
                        "first wait before reopening a port that vanished"),
          Table::Number("reconnect_backoff_max_s", &C::reconnect_backoff_max_s, positive, "s",
                        "the wait doubles after every failed reopen up to this")
              .Note(">= `reconnect_backoff_s`"),
          Table::Number("poll_interval_s", &C::poll_interval_s, {0.0, 0.1, true}, "s",
                        "longest sleep of the I/O thread in poll() (it also wakes on bytes and on motor "
                        "commands)"),
          Table::Number("write_timeout_s", &C::write_timeout_s, positive, "s",
                        "longest wait for room in the output queue for one packet"),
      },
      [](const C& c) {
        if (!IsSupportedBaud(c.baud))
          common::FieldError("baud", c.baud, "not a supported rate (9600 .. 4000000)");
        if (!(c.disconnect_timeout_s > c.stale_timeout_s)) {
          common::FieldError("disconnect_timeout_s", c.disconnect_timeout_s, "must be > stale_timeout_s");
        }
        if (!(c.reconnect_backoff_max_s >= c.reconnect_backoff_s)) {
          common::FieldError("reconnect_backoff_max_s", c.reconnect_backoff_max_s,
                             "must be >= reconnect_backoff_s");
        }
      });
  return table;
}

void HardwareConfig::Validate() const { HardwareConfigFields().Validate(*this); }

HardwareConfig LoadHardwareConfig(const common::YamlMap& map) {
  HardwareConfig config;
  HardwareConfigFields().Load(map, &config);
  return config;
}

}  // namespace graspbed::hardware
