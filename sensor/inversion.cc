#include "sensor/inversion.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace graspbed::sensor {
namespace {

using common::NumberRule;

using common::Require;

}  // namespace

const common::FieldTable<InversionConfig>& InversionConfigFields() {
  using Table = common::FieldTable<InversionConfig>;
  using C = InversionConfig;
  static const Table table(
      "inversion",
      {
          Table::Number("contact_threshold_n", &C::contact_threshold_n, NumberRule::Between(0.0, 1000.0), "N",
                        "a valid unit with Fn above this counts as in contact"),
          Table::Number("rated_force_n", &C::rated_force_n, {0.0, 1000.0, true}, "N",
                        "rated range of Fn and abs(Ft) (paper: 10 N)"),
          Table::Number("out_of_range_margin_fraction", &C::out_of_range_margin_fraction,
                        NumberRule::Between(0.0, 100.0), "-",
                        "estimates beyond rated_force_n x (1 + this) are `out_of_range`; they keep their "
                        "value, count as "
                        "contacts, and stay out of the totals"),
      });
  return table;
}

void InversionConfig::Validate() const { InversionConfigFields().Validate(*this); }

InversionConfig LoadInversionConfig(const common::YamlMap& map) {
  InversionConfig config;
  InversionConfigFields().Load(map, &config);
  return config;
}

UnitForces InvertUnit(const UnitCalibration& calibration, double dr1_rel, double dr2_rel) {
  return {
      (dr1_rel + dr2_rel) / (2.0 * calibration.gauge_factor * calibration.kn_per_n) - calibration.fn_offset_n,
      (dr1_rel - dr2_rel) / (2.0 * calibration.gauge_factor * calibration.kt_per_n) -
          calibration.ft_offset_n};
}

Inversion::Inversion(const Layout& layout, const Calibration& calibration, const InversionConfig& config)
    : config_(config), unit_count_(layout.unit_count()) {
  config_.Validate();
  if (unit_count_ < 1 || unit_count_ > kMaxUnits) {
    throw std::invalid_argument("inversion: layout has " + std::to_string(unit_count_) +
                                " units; expected 1.." + std::to_string(kMaxUnits));
  }
  if (calibration.unit_count() != unit_count_) {
    throw std::invalid_argument("inversion: calibration has " + std::to_string(calibration.unit_count()) +
                                " units, layout '" + layout.name + "' has " + std::to_string(unit_count_));
  }
  for (int unit = 0; unit < unit_count_; ++unit) {
    const UnitCalibration& constants = calibration.units[static_cast<size_t>(unit)];
    const std::string prefix = "calibration.units[" + std::to_string(unit) + "].";
    Require(constants.gauge_factor > 0.0 && std::isfinite(constants.gauge_factor), prefix + "gauge_factor",
            constants.gauge_factor, "must be > 0");
    Require(constants.kn_per_n > 0.0 && std::isfinite(constants.kn_per_n), prefix + "kn_per_n",
            constants.kn_per_n, "must be > 0");
    Require(constants.kt_per_n > 0.0 && std::isfinite(constants.kt_per_n), prefix + "kt_per_n",
            constants.kt_per_n, "must be > 0");
    Require(std::isfinite(constants.fn_offset_n), prefix + "fn_offset_n", constants.fn_offset_n,
            "must be finite");
    Require(std::isfinite(constants.ft_offset_n), prefix + "ft_offset_n", constants.ft_offset_n,
            "must be finite");
    calibration_[unit] = constants;
    const UnitPose& pose = layout.units[static_cast<size_t>(unit)];
    orientation_[unit] = pose.orientation;
    const double component =
        pose.orientation == BeamOrientation::kAxial ? pose.beam_axis.x() : pose.beam_axis.y();
    total_sign_[unit] = component < 0.0 ? -1.0 : 1.0;
  }
}

void Inversion::Invert(const ReadoutFrame& frame, TactileState* state) const {
  state->sequence = frame.sequence;
  state->time_s = frame.time_s;
  const bool units_changed = state->unit_count != unit_count_;
  state->unit_count = unit_count_;
  state->valid_count = 0;
  state->total_fn_n = 0.0;
  state->total_shear_axial_n = 0.0;
  state->total_shear_circumferential_n = 0.0;
  state->contact_count = 0;
  state->noise_known = frame.noise_known;
  const double limit_n = config_.rated_force_n * (1.0 + config_.out_of_range_margin_fraction);
  // A frame for another unit count carries nothing usable for this layout.
  const bool size_ok = frame.unit_count == unit_count_;
  // The noise figures change only when the readout tares again.
  if (state->noise_generation != frame.noise_generation || units_changed) {
    for (int unit = 0; unit < unit_count_; ++unit) {
      const UnitCalibration& calibration = calibration_[unit];
      state->r1_noise_ohm[unit] = frame.r1_noise_ohm[unit];
      state->r2_noise_ohm[unit] = frame.r2_noise_ohm[unit];
      state->fn_noise_n[unit] = frame.sum_noise_rel[unit] / (calibration.gauge_factor * calibration.kn_per_n);
      state->ft_noise_n[unit] =
          frame.diff_noise_rel[unit] / (calibration.gauge_factor * calibration.kt_per_n);
    }
    state->noise_generation = frame.noise_generation;
  }
  for (int unit = 0; unit < unit_count_; ++unit) {
    const UnitCalibration& calibration = calibration_[unit];
    UnitValidity validity = size_ok ? frame.validity[unit] : UnitValidity::kImplausible;
    if (validity != UnitValidity::kValid && validity != UnitValidity::kOutOfRange) {
      state->fn_n[unit] = 0.0;
      state->ft_n[unit] = 0.0;
      state->validity[unit] = validity;
      continue;
    }
    const UnitForces forces = InvertUnit(calibration, frame.dr1_rel[unit], frame.dr2_rel[unit]);
    state->fn_n[unit] = forces.fn_n;
    state->ft_n[unit] = forces.ft_n;
    if (std::abs(forces.fn_n) > limit_n || std::abs(forces.ft_n) > limit_n)
      validity = UnitValidity::kOutOfRange;
    state->validity[unit] = validity;
    // An overloaded unit is certainly touching; it just is not counted in the totals.
    if (forces.fn_n > config_.contact_threshold_n) ++state->contact_count;
    if (validity != UnitValidity::kValid) continue;
    ++state->valid_count;
    state->total_fn_n += forces.fn_n;
    if (orientation_[unit] == BeamOrientation::kAxial) {
      state->total_shear_axial_n += total_sign_[unit] * forces.ft_n;
    } else {
      state->total_shear_circumferential_n += total_sign_[unit] * forces.ft_n;
    }
  }
}

}  // namespace graspbed::sensor
