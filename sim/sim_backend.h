#pragma once
/// SimBackend: the simulated tactile array behind the TactileBackend interface. It samples the unit
/// loads of a Simulation at the sensor rate, runs them through the StrainModel into RawFrames and
/// releases each frame after a configurable latency, through a ring buffer allocated once. The
/// readout downstream sees RawFrames only, exactly as from hardware; ground truth stays in
/// Simulation::truth().
///
/// Driving it (the sim-only call controllers never see, like gz_ros2_control's initSim): whenever the
/// clock moves (a physics step, or a control instant between steps, SimRig::Step) call Poll(now); it
/// samples when a sample time has been reached. Read() then hands out the newest frame whose release
/// time (sample time + latency) has passed.

#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "common/field_table.h"
#include "common/yaml_map.h"
#include "sensor/raw_frame.h"
#include "sensor/strain_model.h"
#include "sensor/tactile_backend.h"
#include "sim/simulation.h"

namespace graspbed::sim {

/// Timing and transport of the simulated sensor.
struct SimBackendConfig {
  double sample_rate_hz = 1000.0;  ///< frames per second of simulated time
  double latency_s = 0.0;          ///< sample -> available to Read() [s]; >= 0
  /// Largest latency SetLatency() will be given during the run [s] (the frame ring is sized for
  /// it); values below latency_s count as latency_s.
  double max_latency_s = 0.0;
  /// Probability that a sampled frame is lost (seeded); its sequence number is skipped, so the
  /// readout sees a gap exactly as with a lost serial packet [0..1].
  double drop_probability = 0.0;
  sensor::StrainModelConfig strain_model;

  /// Checks the fields against SimBackendConfigFields() and the strain model.
  /// @throws common::ConfigError naming the field and value.
  void Validate() const;
};

/// The fields of SimBackendConfig (loader and Validate() derive from it; max_latency_s is set by
/// the runner and only validated).
const common::FieldTable<SimBackendConfig>& SimBackendConfigFields();

/// Reads a SimBackendConfig (keys sample_rate_hz, latency_s, drop_probability, strain_model).
/// @throws common::ConfigError naming file, line, key and value.
SimBackendConfig LoadSimBackendConfig(const common::YamlMap& map, int unit_count);

/// The simulated tactile backend. Holds a reference to the Simulation, which must outlive it.
class SimBackend : public sensor::TactileBackend {
 public:
  /// `seed` seeds the strain model and the frame-drop draw (same seed = identical frames).
  SimBackend(Simulation& simulation, const SimBackendConfig& config, uint64_t seed);

  /// Samples if `now` (the rig's clock [s], never behind the simulation's) has reached the next
  /// sample time (possibly several samples if Poll() was not called for a while), every sample from
  /// the current physics state: between physics steps the sensor sees the last step's contact forces
  /// (zero-order hold), as a sensor sampling faster than the physics steps would. Frames carry
  /// `now`. Allocates nothing.
  void Poll(double now);

  /// Newest released frame newer than the last one read. Never blocks, never allocates.
  sensor::ReadStatus Read(sensor::RawFrame* frame) override;
  int unit_count() const override;
  double nominal_r0_ohm() const override;
  sensor::BackendCounters counters() const override { return counters_; }
  std::string name() const override { return "sim"; }

  /// The strain model, for fault injection (dead / shorted unit, bias, noise burst, temperature).
  sensor::StrainModel& strain_model() { return strain_model_; }
  const sensor::StrainModel& strain_model() const { return strain_model_; }
  /// Drops the next `count` sampled frames (sequence numbers are still used up).
  void DropNextFrames(int count) { drop_next_ += count; }
  /// Changes the release latency from now on [s] (>= 0; frames already queued keep theirs).
  void SetLatency(double latency_s);
  /// The unit loads used for the most recent sample (ground truth of what the sensor saw).
  std::span<const sensor::UnitLoad> last_loads() const { return loads_; }
  /// Simulated time of the physics state last_loads() were computed from [s] (the simulation's time
  /// then, not the sample's); -1 before the first sample.
  double last_loads_time_s() const { return loads_time_s_; }
  const SimBackendConfig& config() const { return config_; }

 private:
  struct Slot {
    double release_time_s = 0.0;
    sensor::RawFrame frame;
  };

  Simulation& simulation_;
  SimBackendConfig config_;
  sensor::StrainModel strain_model_;
  std::mt19937_64 drop_rng_;
  std::vector<sensor::UnitLoad> loads_;
  double loads_time_s_ = -1.0;
  std::vector<Slot> ring_;    ///< fixed capacity, allocated at construction
  size_t ring_head_ = 0;      ///< next slot to write
  size_t ring_size_ = 0;      ///< frames queued and not yet released
  int64_t sample_index_ = 0;  ///< next sample: time = sample_index_ / sample_rate_hz
  int drop_next_ = 0;
  bool has_frame_ = false;  ///< newest_ holds a released frame not yet read
  sensor::RawFrame newest_;
  sensor::BackendCounters counters_;
};

}  // namespace graspbed::sim
