#include "sim/sim_backend.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace graspbed::sim {
namespace {

// Latency the ring is sized for at least [s]; SetLatency() may not exceed the ring.
constexpr double kMinRingLatencyS = 0.1;
// Sample times are k / rate; this fraction of a period absorbs floating-point sums of timesteps.
constexpr double kTimeSlackPeriods = 1e-6;

}  // namespace

const common::FieldTable<SimBackendConfig>& SimBackendConfigFields() {
  using Table = common::FieldTable<SimBackendConfig>;
  using C = SimBackendConfig;
  using common::NumberRule;
  static const Table table(
      "sim_backend",
      {
          Table::Number("sample_rate_hz", &C::sample_rate_hz, NumberRule::Between(1.0, 100000.0), "Hz",
                        "frames per second of simulated time"),
          Table::Number("latency_s", &C::latency_s, NumberRule::Between(0.0, 10.0), "s",
                        "sample -> available to Read()"),
          Table::Number("drop_probability", &C::drop_probability, NumberRule::Between(0.0, 1.0), "-",
                        "chance a sampled frame is lost (seeded)"),
          Table::Custom("strain_model", "", "ideal paper unit", "section", "the strain model's config"),
      },
      [](const C& c) {
        // Set by the runner from the script (add_latency), never read from a file.
        common::Require(c.max_latency_s >= 0.0 && c.max_latency_s <= 10.0, "max_latency_s", c.max_latency_s,
                        "must be in [0, 10]");
      });
  return table;
}

void SimBackendConfig::Validate() const {
  SimBackendConfigFields().Validate(*this);
  strain_model.Validate();
}

SimBackendConfig LoadSimBackendConfig(const common::YamlMap& map, int unit_count) {
  SimBackendConfig config;
  SimBackendConfigFields().Load(map, &config);
  if (auto strain = map.GetMap("strain_model"))
    config.strain_model = sensor::LoadStrainModelConfig(*strain, unit_count);
  return config;
}

SimBackend::SimBackend(Simulation& simulation, const SimBackendConfig& config, uint64_t seed)
    : simulation_(simulation),
      config_(config),
      strain_model_(simulation.layout(), config.strain_model, seed),
      drop_rng_(seed ^ 0x5eed'd20b'f4a3'e001ull) {
  config_.Validate();
  loads_.resize(static_cast<size_t>(simulation_.unit_count()));
  const double ring_latency_s = std::max({config_.latency_s, config_.max_latency_s, kMinRingLatencyS});
  ring_.resize(static_cast<size_t>(std::ceil(ring_latency_s * config_.sample_rate_hz)) + 8);
  newest_.unit_count = simulation_.unit_count();
}

int SimBackend::unit_count() const { return simulation_.unit_count(); }

double SimBackend::nominal_r0_ohm() const { return config_.strain_model.nominal.r0_ohm; }

void SimBackend::SetLatency(double latency_s) {
  const double capacity_s = static_cast<double>(ring_.size() - 8) / config_.sample_rate_hz;
  if (!(latency_s >= 0.0) || latency_s > capacity_s) {
    throw std::invalid_argument("sim backend latency = " + std::to_string(latency_s) + " s: must be in [0, " +
                                std::to_string(capacity_s) + "] (the ring was sized at construction)");
  }
  config_.latency_s = latency_s;
}

void SimBackend::Poll(double now) {
  const double period = 1.0 / config_.sample_rate_hz;
  const double slack = kTimeSlackPeriods * period;
  while (static_cast<double>(sample_index_) * period <= now + slack) {
    ++sample_index_;
    // One pass over the contacts per physics state, however many samples it serves.
    if (loads_time_s_ != simulation_.time_s()) {
      simulation_.ComputeUnitLoads(loads_);
      loads_time_s_ = simulation_.time_s();
    }
    Slot& slot = ring_[ring_head_];
    strain_model_.Sample(loads_, now, &slot.frame);
    bool drop = false;
    if (drop_next_ > 0) {
      --drop_next_;
      drop = true;
    } else if (config_.drop_probability > 0.0) {
      drop = std::uniform_real_distribution<double>(0.0, 1.0)(drop_rng_) < config_.drop_probability;
    }
    if (drop) {
      ++counters_.dropped;
      continue;
    }
    slot.release_time_s = now + config_.latency_s;
    ring_head_ = (ring_head_ + 1) % ring_.size();
    if (ring_size_ < ring_.size()) {
      ++ring_size_;
    }  // else the oldest queued frame was overwritten: the ring is sized so this cannot happen
  }
  // Release every queued frame whose latency has passed; the newest of them is what Read() gives.
  while (ring_size_ > 0) {
    const size_t oldest = (ring_head_ + ring_.size() - ring_size_) % ring_.size();
    if (ring_[oldest].release_time_s > now + slack) break;
    newest_ = ring_[oldest].frame;
    has_frame_ = true;
    --ring_size_;
  }
}

sensor::ReadStatus SimBackend::Read(sensor::RawFrame* frame) {
  if (!has_frame_) return sensor::ReadStatus::kNoNewFrame;
  *frame = newest_;
  has_frame_ = false;
  ++counters_.frames;
  return sensor::ReadStatus::kOk;
}

}  // namespace graspbed::sim
