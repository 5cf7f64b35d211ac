#pragma once
/// Synthetic TactileState streams for controller tests: a Gaussian contact patch on a row-major
/// grid of units with a checkerboard of beam orientations (the default layout), tangential load
/// spread like the pressure, seeded Gaussian noise, stick-slip vibration, invalid and saturated
/// units, stale frames. Plus a small closed-loop plant (a one-motor hand pinching an object with
/// Coulomb friction) so the controller's commands have consequences.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

#include "hand/hand_command.h"
#include "sensor/tactile_state.h"

namespace graspbed::controller::test_support {

/// What touches the sensor at one instant.
struct SyntheticContact {
  double grip_n = 0.0;                  ///< total normal force over the patch [N]
  double load_axial_n = 0.0;            ///< tangential load along the holder axis [N]
  double load_circumferential_n = 0.0;  ///< tangential load around the holder [N]
  double centre_row = 2.0;              ///< patch centre, row index space
  double centre_column = 1.5;           ///< patch centre, column index space
  double patch_sigma_units = 1.0;       ///< Gaussian spread of the patch [unit pitches]
  double vibration_n = 0.0;             ///< extra shear along the load direction, spread like the load [N]
};

/// Turns SyntheticContacts into TactileStates the way the readout would report them.
class SyntheticTactile {
 public:
  struct Options {
    int rows = 5;
    int columns = 4;
    bool even_units_axial = true;
    double noise_fn_n = 0.03;  ///< per-unit noise on the normal estimate [N], 1 sigma
    double noise_ft_n = 0.04;  ///< per-unit noise on the shear estimate [N], 1 sigma (k_n/k_t larger)
    double range_n = 10.0;     ///< units beyond this report kOutOfRange
    double contact_threshold_n = 0.25;
    uint32_t seed = 1;
    /// Report the noise in the state as a readout that measured it at its tare would
    /// (TactileState::noise_known, fn_noise_n, ft_noise_n); off: the state carries no noise figure.
    bool report_noise = false;
  };

  explicit SyntheticTactile(const Options& options) : options_(options), rng_(options.seed) {
    forced_validity_.fill(sensor::UnitValidity::kValid);
  }

  int unit_count() const { return options_.rows * options_.columns; }
  bool IsAxial(int unit) const {
    const int row = unit / options_.columns;
    const int column = unit % options_.columns;
    return ((row + column) % 2 == 0) == options_.even_units_axial;
  }
  /// Marks a unit permanently invalid (dead) or valid again.
  /// Multiplies the injected noise (a noise burst); the reported figure stays the tare's.
  void SetNoiseScale(double scale) { noise_scale_ = scale; }

  void SetUnitValidity(int unit, sensor::UnitValidity validity) {
    forced_validity_[static_cast<size_t>(unit)] = validity;
  }

  /// The next frame at `time_s` (sequence increments).
  sensor::TactileState Frame(const SyntheticContact& contact, double time_s) {
    sensor::TactileState state;
    state.sequence = ++sequence_;
    state.time_s = time_s;
    state.unit_count = unit_count();
    if (options_.report_noise) {
      state.noise_known = true;
      for (int i = 0; i < unit_count(); ++i) {
        state.fn_noise_n[static_cast<size_t>(i)] = options_.noise_fn_n;
        state.ft_noise_n[static_cast<size_t>(i)] = options_.noise_ft_n;
      }
    }
    std::array<double, sensor::kMaxUnits> weight{};
    double weight_sum = 0.0;
    for (int i = 0; i < unit_count(); ++i) {
      const double dr = i / options_.columns - contact.centre_row;
      const double dc = i % options_.columns - contact.centre_column;
      const double sigma = contact.patch_sigma_units;
      weight[static_cast<size_t>(i)] = std::exp(-(dr * dr + dc * dc) / (2.0 * sigma * sigma));
      weight_sum += weight[static_cast<size_t>(i)];
    }
    const double load = std::hypot(contact.load_axial_n, contact.load_circumferential_n);
    const double direction_axial = load > 0.0 ? contact.load_axial_n / load : 1.0;
    const double direction_circ = load > 0.0 ? contact.load_circumferential_n / load : 0.0;
    for (int i = 0; i < unit_count(); ++i) {
      const size_t u = static_cast<size_t>(i);
      const double share = weight_sum > 0.0 ? weight[u] / weight_sum : 0.0;
      const bool axial = IsAxial(i);
      const double shear_load = axial ? contact.load_axial_n : contact.load_circumferential_n;
      const double shear_vibration = contact.vibration_n * (axial ? direction_axial : direction_circ);
      state.fn_n[u] = contact.grip_n * share + noise_scale_ * options_.noise_fn_n * normal_(rng_);
      state.ft_n[u] =
          (shear_load + shear_vibration) * share + noise_scale_ * options_.noise_ft_n * normal_(rng_);
      sensor::UnitValidity validity = forced_validity_[u];
      if (validity == sensor::UnitValidity::kValid &&
          (std::abs(state.fn_n[u]) > options_.range_n || std::abs(state.ft_n[u]) > options_.range_n)) {
        validity = sensor::UnitValidity::kOutOfRange;
      }
      state.validity[u] = validity;
      if (validity != sensor::UnitValidity::kValid) continue;
      ++state.valid_count;
      state.total_fn_n += state.fn_n[u];
      (axial ? state.total_shear_axial_n : state.total_shear_circumferential_n) += state.ft_n[u];
      if (state.fn_n[u] > options_.contact_threshold_n) ++state.contact_count;
    }
    return state;
  }

 private:
  double noise_scale_ = 1.0;
  Options options_;
  std::mt19937 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::array<sensor::UnitValidity, sensor::kMaxUnits> forced_validity_{};
  uint32_t sequence_ = 0;
};

/// A one-motor hand pinching an object against the sensorised finger, with Coulomb friction at the
/// finger. Before contact the effort moves the finger; in contact it builds grip force through a
/// first-order lag towards effort x stall force. The object's tangential load (weight, inertia,
/// pulls) is scripted; when it exceeds friction the object accelerates (Coulomb sliding of a
/// mass), the shear stays on the friction cone with stick-slip vibration, and the contact patch
/// travels along the holder axis.
class HandPlant {
 public:
  struct Options {
    double stall_force_n = 17.0;  ///< grip force at effort 1 at stall [N]
    double force_time_constant_s = 0.02;
    double closing_speed_per_s = 4.0;  ///< fraction of the closing stroke per second at effort 1
    double start_gap = 0.3;            ///< fraction of the stroke between finger and object at start
    double friction = 0.8;             ///< true friction coefficient at the finger
    double slip_mass_kg = 0.1;         ///< mass the finger's friction accelerates when sliding [kg]
    double stick_slip_hz = 120.0;      ///< stick-slip vibration frequency while sliding [Hz]
    double stick_slip_fraction = 0.3;  ///< peak stick-slip shear, fraction of the friction force
    double pitch_m = 5e-3;             ///< unit pitch the patch travels over [m]
    double drop_distance_m = 20e-3;    ///< after sliding this far the object is gone [m]
  };

  explicit HandPlant(const Options& options) : options_(options), gap_(options.start_gap) {}

  /// Advances the plant by `dt_s` under `command` with tangential load `load_n` (axial) [N].
  void Step(const hand::HandCommand& command, double load_n, double dt_s) {
    time_s_ += dt_s;
    load_n_ = load_n;
    const double effort = std::clamp(command.grip_effort, -1.0, 1.0);
    if (dropped()) {
      // Nothing between the fingers: the hand closes on air, the sensor reads nothing.
      grip_n_ = 0.0;
      speed_m_per_s_ = 0.0;
      sliding_ = false;
      return;
    }
    if (gap_ > 0.0 || (grip_n_ <= 0.0 && effort < 0.0)) {
      gap_ = std::clamp(gap_ - effort * options_.closing_speed_per_s * dt_s, 0.0, 1.0);
      grip_n_ = 0.0;
    } else {
      const double target = std::max(effort, 0.0) * options_.stall_force_n;
      grip_n_ += (target - grip_n_) * (1.0 - std::exp(-dt_s / options_.force_time_constant_s));
      if (effort < 0.0) grip_n_ = std::max(0.0, grip_n_ + effort * options_.stall_force_n * dt_s / 0.05);
    }
    // Coulomb friction on a sliding mass: the excess load accelerates it, friction brakes it once
    // the load falls back inside the cone, and it sticks again when it stops.
    const double friction_force = options_.friction * grip_n_;
    const double excess_n = std::abs(load_n) - friction_force;
    if (grip_n_ > 0.0 && (speed_m_per_s_ > 0.0 || excess_n > 0.0)) {
      speed_m_per_s_ = std::max(0.0, speed_m_per_s_ + excess_n / options_.slip_mass_kg * dt_s);
      if (grip_n_ <= 0.0) speed_m_per_s_ = 0.0;
    } else {
      speed_m_per_s_ = 0.0;
    }
    sliding_ = speed_m_per_s_ > 0.0;
    if (sliding_) {
      if (slip_onset_s_ < 0.0) slip_onset_s_ = time_s_;
      slip_distance_m_ += speed_m_per_s_ * dt_s;
      total_slip_m_ += speed_m_per_s_ * dt_s;
      centre_row_ += std::copysign(speed_m_per_s_ * dt_s / options_.pitch_m, load_n);
    }
  }

  /// What the sensor sees now.
  SyntheticContact Contact() const {
    SyntheticContact contact;
    contact.grip_n = grip_n_;
    contact.centre_row = centre_row_;
    if (sliding_) {
      const double friction_force = options_.friction * grip_n_;
      contact.load_axial_n = std::copysign(friction_force, load_n_);
      const double phase = std::fmod(time_s_ * options_.stick_slip_hz, 1.0);
      // Sawtooth: shear builds while sticking, drops at each micro-slip.
      contact.vibration_n =
          std::copysign(options_.stick_slip_fraction * friction_force * (phase - 0.5), load_n_);
    } else {
      contact.load_axial_n = grip_n_ > 0.0 ? load_n_ : 0.0;
    }
    return contact;
  }

  double grip_n() const { return grip_n_; }
  /// The object slid out of the grasp.
  bool dropped() const { return total_slip_m_ >= options_.drop_distance_m; }
  double gap() const { return gap_; }
  bool sliding() const { return sliding_; }
  /// First time the object slid since construction or ClearSlip() [s], < 0 if never.
  double slip_onset_s() const { return slip_onset_s_; }
  /// Forgets slip onset and distance (ground truth restarts from here).
  void ClearSlip() {
    slip_onset_s_ = -1.0;
    slip_distance_m_ = 0.0;
  }
  double slip_distance_m() const { return slip_distance_m_; }
  void set_friction(double friction) { options_.friction = friction; }

 private:
  Options options_;
  double gap_;
  double grip_n_ = 0.0;
  double load_n_ = 0.0;
  double time_s_ = 0.0;
  bool sliding_ = false;
  double slip_onset_s_ = -1.0;
  double slip_distance_m_ = 0.0;
  double speed_m_per_s_ = 0.0;
  double total_slip_m_ = 0.0;  ///< never cleared: decides the drop
  double centre_row_ = 2.0;
};

}  // namespace graspbed::controller::test_support
