#pragma once
/// The simulated hand's proprioception: joint encoders and motor current sensing, read from the
/// physics through a profile of the electronics as the tactile readout has its sensor profile
/// (docs/simulation.md, "Proprioception"). SimHandSensor samples Simulation::ReadDigits() at the
/// profile's rate, quantises the joint positions to the encoder's resolution, differentiates and
/// low-pass filters them into velocities, turns the motor's torque share into a winding current
/// with a gain error, an offset and white noise behind a first-order filter, marks the end stops,
/// and releases each sample after the profile's latency through a ring allocated once.
///
/// Profiles: `ideal` (exact values, no delay) and `realistic` (the default): a 12-bit absolute
/// magnetic encoder on each driven joint (2 pi / 4096 = 1.53 mrad; 0.01 mm on the jaw's slides), a
/// shunt amplifier on the motor (2 % gain error, 10 mA offset, 5 mA rms noise, 500 Hz filter),
/// a 1 kHz sample and 1 ms from sample to the controller: figures of the class of parts a
/// prosthetic hand's motor board uses, not of one part (docs/simulation.md gives the reasoning).

#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "common/field_table.h"
#include "common/yaml_map.h"
#include "hand/hand_state.h"
#include "sim/simulation.h"

namespace graspbed::sim {

/// The proprioception electronics of the simulated hand (scenario key `proprioception:`).
struct ProprioceptionConfig {
  std::string profile = "realistic";  ///< "ideal" or "realistic": the values the keys below start from
  bool enabled = true;                ///< false: the hand reports nothing (every field unknown)
  double sample_rate_hz = 1000.0;     ///< readings per second [Hz]
  double latency_s = 0.001;           ///< sample -> available to the controller [s]
  /// One encoder count on a hinge [rad] and on a slide [m]; 0 = exact.
  double encoder_resolution_rad = 2.0 * 3.14159265358979323846 / 4096.0;
  double encoder_resolution_m = 1e-5;
  double velocity_filter_hz = 50.0;  ///< first-order low-pass on the differentiated encoder [Hz]; 0 = none
  /// The motor's winding current at stall with full effort [A] (the scale of motor_current_a).
  double stall_current_a = 1.0;
  double current_gain = 1.02;       ///< measured / true current [-] (the shunt amplifier's gain error)
  double current_offset_a = 0.01;   ///< added to every current reading [A]
  double current_noise_a = 0.005;   ///< white noise on the current, standard deviation [A]
  double current_filter_hz = 500.0;  ///< first-order low-pass on the current [Hz]; 0 = none
  /// The driven joint within this of an end stop counts as at it [rad] / [m].
  double stop_tolerance_rad = 0.02;
  double stop_tolerance_m = 0.5e-3;
  /// An encoder whose reading stands still this long while its motor's back-EMF says it turns at
  /// >= 20 % of its no-load speed is flagged (DigitState::encoder_fault, position unknown) [s].
  double stuck_encoder_timeout_s = 0.05;

  /// @throws common::ConfigError naming the field and value.
  void Validate() const;
};

/// The fields of ProprioceptionConfig (loader, emitter, Validate and the reference table).
const common::FieldTable<ProprioceptionConfig>& ProprioceptionConfigFields();
/// Names of the shipped profiles ("ideal", "realistic").
std::vector<std::string> ProprioceptionProfileNames();
/// The profile called `name` (every field at the profile's value); std::invalid_argument listing
/// the names for another.
ProprioceptionConfig ProprioceptionProfile(const std::string& name);
/// Reads a `proprioception:` section: `profile` first, then any key given overrides it.
/// @throws common::ConfigError naming file, line, key and value.
ProprioceptionConfig LoadProprioceptionConfig(const common::YamlMap& map);

/// The simulated hand's proprioception behind hand::HandSensor. Holds a reference to the
/// Simulation, which must outlive it. Driven like SimBackend: Poll(now) whenever the rig's clock
/// moves; the control loop's Read() takes the newest released sample.
class SimHandSensor final : public hand::HandSensor {
 public:
  /// `seed` seeds the current noise (same seed = identical readings).
  SimHandSensor(const Simulation& simulation, const ProprioceptionConfig& config, uint64_t seed);

  /// Samples if `now` [s] (the rig's clock) has reached the next sample time. Allocates nothing.
  void Poll(double now);
  bool Read(double time_s, hand::HandState* state) override;
  std::string name() const override { return "sim"; }

  /// Fault injection: freezes digit `digit`'s encoder at its current reading (true) or frees it.
  void SetEncoderStuck(int digit, bool stuck);
  /// Ticks at which some digit's encoder was flagged faulty (a stuck encoder seen).
  uint64_t encoder_fault_samples() const { return encoder_fault_samples_; }
  const ProprioceptionConfig& config() const { return config_; }

 private:
  struct DigitMemory {
    double current_filtered_a = 0.0;
    std::array<double, hand::kMaxDigitJoints> last_reading{};
    std::array<double, hand::kMaxDigitJoints> velocity_filtered{};
    bool stuck = false;
    std::array<double, hand::kMaxDigitJoints> stuck_reading{};
    double unchanged_since_s = 0.0;  ///< sample time since which the reading has not changed
  };
  struct Slot {
    double release_time_s = 0.0;
    hand::HandState state;
  };

  void Sample(double time_s);
  void SampleDigit(const DigitTruth& truth, double time_s, double dt_s, DigitMemory& memory,
                   hand::DigitState& digit);

  const Simulation& simulation_;
  ProprioceptionConfig config_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  std::array<DigitMemory, hand::kMaxDigits> memory_{};
  std::vector<Slot> ring_;  ///< fixed capacity, allocated at construction
  size_t ring_head_ = 0;
  size_t ring_size_ = 0;
  int64_t sample_index_ = 0;
  bool first_sample_ = true;
  uint64_t encoder_fault_samples_ = 0;
};

}  // namespace graspbed::sim
