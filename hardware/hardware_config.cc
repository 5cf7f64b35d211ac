#include "hardware/hardware_config.h"

#include <sstream>

#include "hardware/serial_port.h"

namespace graspbed::hardware {
namespace {

void Require(bool ok, const std::string& field, double value, const std::string& reason) {
  if (ok) return;
  std::ostringstream message;
  message << "hardware config: " << field << " = " << value << ": " << reason;
  throw common::ConfigError(message.str());
}

}  // namespace

void HardwareConfig::Validate() const {
  Require(IsSupportedBaud(baud), "baud", baud, "not a supported rate (9600 .. 4000000)");
  Require(hello_timeout_s > 0, "hello_timeout_s", hello_timeout_s, "must be > 0");
  Require(stale_timeout_s > 0, "stale_timeout_s", stale_timeout_s, "must be > 0");
  Require(disconnect_timeout_s > stale_timeout_s, "disconnect_timeout_s", disconnect_timeout_s,
          "must be > stale_timeout_s");
  Require(reconnect_backoff_s > 0, "reconnect_backoff_s", reconnect_backoff_s, "must be > 0");
  Require(reconnect_backoff_max_s >= reconnect_backoff_s, "reconnect_backoff_max_s", reconnect_backoff_max_s,
          "must be >= reconnect_backoff_s");
  Require(poll_interval_s > 0 && poll_interval_s <= 0.1, "poll_interval_s", poll_interval_s,
          "must be in (0, 0.1]");
  Require(write_timeout_s > 0, "write_timeout_s", write_timeout_s, "must be > 0");
}

HardwareConfig HardwareConfigFromYaml(const common::YamlMap& map) {
  HardwareConfig config;
  const auto positive = common::NumberRule::Positive();
  config.port = map.GetString("port", config.port);
  config.motor_port = map.GetString("motor_port", config.motor_port);
  config.baud = map.GetInt("baud", config.baud, 1);
  if (!IsSupportedBaud(config.baud)) map.Fail("baud", "not a supported rate (9600 .. 4000000)");
  config.hello_timeout_s = map.GetNumber("hello_timeout_s", config.hello_timeout_s, positive);
  config.stale_timeout_s = map.GetNumber("stale_timeout_s", config.stale_timeout_s, positive);
  config.disconnect_timeout_s = map.GetNumber("disconnect_timeout_s", config.disconnect_timeout_s, positive);
  if (config.disconnect_timeout_s <= config.stale_timeout_s) {
    map.Fail("disconnect_timeout_s", "must be > stale_timeout_s");
  }
  config.reconnect_backoff_s = map.GetNumber("reconnect_backoff_s", config.reconnect_backoff_s, positive);
  config.reconnect_backoff_max_s =
      map.GetNumber("reconnect_backoff_max_s", config.reconnect_backoff_max_s, positive);
  if (config.reconnect_backoff_max_s < config.reconnect_backoff_s) {
    map.Fail("reconnect_backoff_max_s", "must be >= reconnect_backoff_s");
  }
  config.poll_interval_s = map.GetNumber("poll_interval_s", config.poll_interval_s, {0.0, 0.1, true});
  config.write_timeout_s = map.GetNumber("write_timeout_s", config.write_timeout_s, positive);
  map.RejectUnknownKeys();
  config.Validate();
  return config;
}

}  // namespace graspbed::hardware
