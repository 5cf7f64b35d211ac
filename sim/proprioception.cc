#include "sim/proprioception.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "common/config_error.h"

namespace graspbed::sim {
namespace {

/// A motor whose back-EMF term (effort - torque share) is at least this share of its no-load
/// speed turns: a still encoder then is stuck.
constexpr double kTurningShare = 0.2;
/// Slack on comparisons of sample times, which are quotients index / rate: half a microsecond, as
/// Poll's, so that a span of exactly the timeout is not lost to rounding.
constexpr double kTimeSlackS = 5e-7;

/// Weight of the new input in a first-order low-pass with cutoff `cutoff_hz` sampled every `dt_s`
/// (1 when the cutoff is 0: no filter).
double LowPassWeight(double cutoff_hz, double dt_s) {
  if (cutoff_hz <= 0.0 || dt_s <= 0.0) return 1.0;
  return 1.0 - std::exp(-2.0 * std::numbers::pi * cutoff_hz * dt_s);
}

double Quantise(double value, double step) { return step > 0.0 ? step * std::round(value / step) : value; }

}  // namespace

const common::FieldTable<ProprioceptionConfig>& ProprioceptionConfigFields() {
  using Table = common::FieldTable<ProprioceptionConfig>;
  using C = ProprioceptionConfig;
  using common::NumberRule;
  static const Table table(
      "proprioception",
      {
          Table::Text("profile", &C::profile, ProprioceptionProfileNames(),
                      "the electronics the keys below start from (`ideal`: exact, no delay)"),
          Table::Bool("enabled", &C::enabled, "false: the hand reports no proprioception (all fields unknown)"),
          Table::Number("sample_rate_hz", &C::sample_rate_hz, NumberRule::Between(1.0, 100000.0), "Hz",
                        "readings per second"),
          Table::Number("latency_s", &C::latency_s, NumberRule::Between(0.0, 1.0), "s",
                        "sample -> available to the controller"),
          Table::Number("encoder_resolution_rad", &C::encoder_resolution_rad, NumberRule::Between(0.0, 0.1),
                        "rad", "one encoder count on a hinge (0: exact; the default: 12 bits, 2 pi / 4096)"),
          Table::Number("encoder_resolution_m", &C::encoder_resolution_m, NumberRule::Between(0.0, 1e-3), "m",
                        "one encoder count on a slide (jaw fixture; 0: exact)"),
          Table::Number("velocity_filter_hz", &C::velocity_filter_hz, NumberRule::Between(0.0, 10000.0), "Hz",
                        "low-pass on the differentiated encoder (0: none)"),
          Table::Number("stall_current_a", &C::stall_current_a, NumberRule::Between(0.01, 100.0), "A",
                        "motor current at stall with full effort"),
          Table::Number("current_gain", &C::current_gain, NumberRule::Between(0.5, 2.0), "-",
                        "measured / true current"),
          Table::Number("current_offset_a", &C::current_offset_a, NumberRule::Between(-1.0, 1.0), "A",
                        "added to every current reading"),
          Table::Number("current_noise_a", &C::current_noise_a, NumberRule::Between(0.0, 1.0), "A",
                        "white noise on the current (standard deviation)"),
          Table::Number("current_filter_hz", &C::current_filter_hz, NumberRule::Between(0.0, 100000.0), "Hz",
                        "low-pass on the current (0: none)"),
          Table::Number("stop_tolerance_rad", &C::stop_tolerance_rad, NumberRule::Between(0.0, 0.5), "rad",
                        "a hinge this close to an end stop is at it"),
          Table::Number("stop_tolerance_m", &C::stop_tolerance_m, NumberRule::Between(0.0, 0.01), "m",
                        "a slide this close to an end stop is at it"),
          Table::Number("stuck_encoder_timeout_s", &C::stuck_encoder_timeout_s, NumberRule::Between(0.001, 10.0),
                        "s", "a reading still this long while the motor turns flags the encoder"),
      });
  return table;
}

void ProprioceptionConfig::Validate() const { ProprioceptionConfigFields().Validate(*this); }

std::vector<std::string> ProprioceptionProfileNames() { return {"ideal", "realistic"}; }

ProprioceptionConfig ProprioceptionProfile(const std::string& name) {
  ProprioceptionConfig config;  // the in-class defaults are the realistic profile
  if (name == "realistic") return config;
  if (name != "ideal") throw std::invalid_argument("unknown proprioception profile '" + name +
                                                   "' (valid: ideal, realistic)");
  config.profile = "ideal";
  config.latency_s = 0.0;
  config.encoder_resolution_rad = 0.0;
  config.encoder_resolution_m = 0.0;
  config.velocity_filter_hz = 0.0;
  config.current_gain = 1.0;
  config.current_offset_a = 0.0;
  config.current_noise_a = 0.0;
  config.current_filter_hz = 0.0;
  return config;
}

ProprioceptionConfig LoadProprioceptionConfig(const common::YamlMap& map) {
  const std::string name = map.GetString("profile", "realistic", ProprioceptionProfileNames());
  ProprioceptionConfig config = ProprioceptionProfile(name);
  ProprioceptionConfigFields().Load(map, &config);
  return config;
}

SimHandSensor::SimHandSensor(const Simulation& simulation, const ProprioceptionConfig& config, uint64_t seed)
    : simulation_(simulation), config_(config), rng_(seed ^ 0x9e37'79b9'7f4a'7c15ull) {
  config_.Validate();
  ring_.resize(static_cast<size_t>(std::ceil(config_.latency_s * config_.sample_rate_hz)) + 4);
}

void SimHandSensor::SetEncoderStuck(int digit, bool stuck) {
  if (digit < 0 || digit >= hand::kMaxDigits) throw std::invalid_argument("no digit " + std::to_string(digit));
  DigitMemory& memory = memory_[digit];
  memory.stuck = stuck;
  memory.stuck_reading = memory.last_reading;
}

void SimHandSensor::Poll(double now) {
  if (!config_.enabled) return;
  // Half a microsecond of slack so that a sample due at `now` is not lost to rounding.
  while (static_cast<double>(sample_index_) / config_.sample_rate_hz <= now + 5e-7) {
    Sample(static_cast<double>(sample_index_) / config_.sample_rate_hz);
    ++sample_index_;
  }
}

void SimHandSensor::Sample(double time_s) {
  const std::array<DigitTruth, 2> truth = simulation_.ReadDigits();
  const double dt_s = first_sample_ ? 0.0 : 1.0 / config_.sample_rate_hz;
  Slot& slot = ring_[ring_head_];
  slot.release_time_s = time_s + config_.latency_s;
  hand::HandState& state = slot.state;
  state.time_s = time_s;
  state.stale = false;
  state.digit_count = hand::kMaxDigits;
  for (int k = 0; k < hand::kMaxDigits; ++k) SampleDigit(truth[k], time_s, dt_s, memory_[k], state.digits[k]);
  first_sample_ = false;
  ring_head_ = (ring_head_ + 1) % ring_.size();
  ring_size_ = std::min(ring_size_ + 1, ring_.size());
}

void SimHandSensor::SampleDigit(const DigitTruth& truth, double time_s, double dt_s, DigitMemory& memory,
                                hand::DigitState& digit) {
  const double resolution = truth.linear ? config_.encoder_resolution_m : config_.encoder_resolution_rad;
  const double velocity_weight = LowPassWeight(config_.velocity_filter_hz, dt_s);
  bool changed = false;
  digit.joint_count = truth.joint_count;
  digit.linear = truth.linear;
  for (int j = 0; j < truth.joint_count; ++j) {
    const double reading = memory.stuck ? memory.stuck_reading[j] : Quantise(truth.position[j], resolution);
    const double raw_velocity = dt_s > 0.0 ? (reading - memory.last_reading[j]) / dt_s : 0.0;
    // An ideal encoder reports the physics' own velocity; a real one differentiates its counts.
    const double velocity = resolution == 0.0 && !memory.stuck && velocity_weight == 1.0 ? truth.velocity[j]
                                                                                         : raw_velocity;
    changed = changed || reading != memory.last_reading[j] || dt_s == 0.0;
    memory.velocity_filtered[j] += velocity_weight * (velocity - memory.velocity_filtered[j]);
    memory.last_reading[j] = reading;
    digit.joint_position[j] = reading;
    digit.joint_velocity[j] = memory.velocity_filtered[j];
  }
  if (changed) memory.unchanged_since_s = time_s;

  digit.current_known = truth.has_motor;
  digit.stall_current_a = truth.has_motor ? config_.stall_current_a : 0.0;
  if (truth.has_motor) {
    const double measured = config_.current_gain * config_.stall_current_a * truth.motor_torque_share +
                            config_.current_offset_a + config_.current_noise_a * noise_(rng_);
    const double weight = first_sample_ ? 1.0 : LowPassWeight(config_.current_filter_hz, dt_s);
    memory.current_filtered_a += weight * (measured - memory.current_filtered_a);
    digit.motor_current_a = memory.current_filtered_a;
  }

  // The firmware's check: the motor's back-EMF (effort - torque share) says it turns, the encoder
  // does not move.
  const double effort = simulation_.grip_brake() ? 0.0 : simulation_.grip_effort();
  const bool turning = truth.has_motor && std::abs(effort - truth.motor_torque_share) >= kTurningShare;
  digit.encoder_fault =
      turning && time_s - memory.unchanged_since_s >= config_.stuck_encoder_timeout_s - kTimeSlackS;
  if (digit.encoder_fault) ++encoder_fault_samples_;
  digit.position_known = truth.joint_count > 0 && !digit.encoder_fault;
  digit.velocity_known = digit.position_known;

  const double tolerance = truth.linear ? config_.stop_tolerance_m : config_.stop_tolerance_rad;
  digit.stops_known = digit.position_known && std::isfinite(truth.open_stop);
  digit.at_open_stop = digit.stops_known && digit.joint_position[0] <= truth.open_stop + tolerance;
  digit.at_closed_stop = digit.stops_known && digit.joint_position[0] >= truth.closed_stop - tolerance;
}

bool SimHandSensor::Read(double time_s, hand::HandState* state) {
  // The newest queued sample released by `time_s`; older ones are dropped with it.
  bool found = false;
  while (ring_size_ > 0) {
    const size_t oldest = (ring_head_ + ring_.size() - ring_size_) % ring_.size();
    if (ring_[oldest].release_time_s > time_s + 5e-7) break;
    *state = ring_[oldest].state;
    --ring_size_;
    found = true;
  }
  return found;
}

}  // namespace graspbed::sim
