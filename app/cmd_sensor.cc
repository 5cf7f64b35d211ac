// `graspbed sensor`: the paper's forward model and inversion for one unit (for the bench with a
// multimeter as much as for scripts), the layout's unit poses, and the calibration fit.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "app/command_registry.h"
#include "common/plot.h"
#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/layout.h"
#include "sensor/layout_drawing.h"
#include "sensor/strain_model.h"

namespace graspbed::app {
namespace {

// What sign a command-line quantity may have.
enum class Sign { kAny, kNonNegative, kPositive };

// Parses a command-line number; refuses text, NaN, infinities, and values of the wrong sign,
// naming the option and the value.
double ParseQuantity(const std::string& option, const std::string& text, Sign sign, const char* hint = "") {
  const auto fail = [&](const std::string& reason) {
    throw std::invalid_argument(option + " = " + text + ": " + reason + hint);
  };
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size()) fail("expected a number");
  if (!std::isfinite(value)) fail("must be a finite number");
  if (sign == Sign::kPositive && !(value > 0.0)) fail("must be > 0");
  if (sign == Sign::kNonNegative && value < 0.0) fail("must be >= 0");
  return value;
}

struct ForwardOptions {
  std::string fn = "0";
  std::string ft = "0";
  std::string r0;
  bool json = false;
};

struct InvertOptions {
  std::string r1;
  std::string r2;
  std::string r0;
  bool json = false;
};

struct LayoutOptions {
  std::string layout_path = sensor::DefaultLayoutPath();
  bool json = false;
  std::string picture_path;  ///< "" or where to write the labelled picture (PNG)
};

struct CalibrateOptions {
  std::string log_path;
  std::string out_path;
  std::string layout_path = sensor::DefaultLayoutPath();
  double gauge_factor = 100.0;
  bool json = false;
};

void WarnBeyondRange(const char* name, double force_n, double rated_n) {
  if (std::abs(force_n) > rated_n) {
    std::fprintf(stderr, "graspbed: note: %s = %g N is beyond the rated %g N range\n", name, force_n,
                 rated_n);
  }
}

void RunForward(const ForwardOptions& options) {
  sensor::UnitConstants constants;
  // Fn presses the mesa (the unit cannot pull it); Ft is shear along the beam either way: negative
  // shear stretches R2's half and compresses R1's (paper eq. 3 with eps_t < 0), so R1 < R2.
  const double fn_n = ParseQuantity("--fn", options.fn, Sign::kNonNegative);
  const double ft_n = ParseQuantity("--ft", options.ft, Sign::kAny);
  if (!options.r0.empty()) constants.r0_ohm = ParseQuantity("--r0", options.r0, Sign::kPositive);
  const sensor::GaugeResistances r = sensor::IdealGaugeResistances(constants, fn_n, ft_n);
  // Far beyond the rated range the linear gauge model would give a resistance <= 0: no reading.
  if (!(r.r1_ohm > 0.0) || !(r.r2_ohm > 0.0)) {
    char message[200];
    std::snprintf(
        message, sizeof(message),
        "--fn = %s, --ft = %s: the gauge model gives R1 = %.0f Ohm, R2 = %.0f Ohm (<= 0: far beyond "
        "the rated %g N)",
        options.fn.c_str(), options.ft.c_str(), r.r1_ohm, r.r2_ohm, constants.rated_force_n);
    throw std::invalid_argument(message);
  }
  const double dr1 = r.r1_ohm / constants.r0_ohm - 1.0;
  const double dr2 = r.r2_ohm / constants.r0_ohm - 1.0;
  if (options.json) {
    const nlohmann::json out = {{"fn", fn_n},
                                {"ft", ft_n},
                                {"r0", constants.r0_ohm},
                                {"r1", r.r1_ohm},
                                {"r2", r.r2_ohm},
                                {"dr1_rel", dr1},
                                {"dr2_rel", dr2},
                                {"gauge_factor", constants.gauge_factor},
                                {"kn_per_n", constants.kn_per_n},
                                {"kt_per_n", constants.kt_per_n}};
    std::cout << out.dump() << '\n';
    return;
  }
  WarnBeyondRange("Fn", fn_n, constants.rated_force_n);
  WarnBeyondRange("Ft", ft_n, constants.rated_force_n);
  std::printf("unit: R0 = %g Ohm, G = %g, kn = %g /N, kt = %g /N (paper eqs. 1-3)\n", constants.r0_ohm,
              constants.gauge_factor, constants.kn_per_n, constants.kt_per_n);
  std::printf("load: Fn = %g N, Ft = %g N\n", fn_n, ft_n);
  std::printf("R1 = %.1f Ohm   dR1/R1 = %+.4f\n", r.r1_ohm, dr1);
  std::printf("R2 = %.1f Ohm   dR2/R2 = %+.4f\n", r.r2_ohm, dr2);
}

void RunInvert(const InvertOptions& options) {
  const char* hint_short = " (0 Ohm reads as a short circuit)";
  const double r1 = ParseQuantity("--r1", options.r1, Sign::kPositive, hint_short);
  const double r2 = ParseQuantity("--r2", options.r2, Sign::kPositive, hint_short);
  sensor::UnitConstants constants;
  if (!options.r0.empty()) constants.r0_ohm = ParseQuantity("--r0", options.r0, Sign::kPositive);
  const sensor::UnitCalibration calibration;  // paper constants
  const double dr1 = r1 / constants.r0_ohm - 1.0;
  const double dr2 = r2 / constants.r0_ohm - 1.0;
  const sensor::UnitForces forces = sensor::InvertUnit(calibration, dr1, dr2);
  if (options.json) {
    const nlohmann::json out = {{"r1", r1},         {"r2", r2},       {"r0", constants.r0_ohm},
                                {"dr1_rel", dr1},   {"dr2_rel", dr2}, {"fn", forces.fn_n},
                                {"ft", forces.ft_n}};
    std::cout << out.dump() << '\n';
    return;
  }
  WarnBeyondRange("Fn", forces.fn_n, constants.rated_force_n);
  WarnBeyondRange("Ft", forces.ft_n, constants.rated_force_n);
  std::printf("R1 = %g Ohm, R2 = %g Ohm, R0 = %g Ohm: dR1/R1 = %+.4f, dR2/R2 = %+.4f\n", r1, r2,
              constants.r0_ohm, dr1, dr2);
  std::printf("Fn = %.3f N\nFt = %.3f N\n", forces.fn_n, forces.ft_n);
}

void RunLayout(const LayoutOptions& options) {
  const sensor::Layout layout = sensor::LoadLayout(options.layout_path);
  if (!options.picture_path.empty()) {
    plot::WritePng(sensor::LayoutDrawing(layout), options.picture_path);
    std::printf("wrote %s (layout %s, %d unit%s)\n", options.picture_path.c_str(), layout.name.c_str(),
                layout.unit_count(), layout.unit_count() == 1 ? "" : "s");
    return;
  }
  if (options.json) {
    nlohmann::json units = nlohmann::json::array();
    for (const sensor::UnitPose& pose : layout.units) {
      const auto vector = [](const Eigen::Vector3d& v) {
        return nlohmann::json::array({v.x(), v.y(), v.z()});
      };
      units.push_back({{"row", pose.row},
                       {"column", pose.column},
                       {"orientation", sensor::ToString(pose.orientation)},
                       {"axial_position_m", pose.axial_position_m},
                       {"arc_position_m", pose.arc_position_m},
                       {"position_m", vector(pose.position_m)},
                       {"inward_normal", vector(pose.inward_normal)},
                       {"beam_axis", vector(pose.beam_axis)}});
    }
    const nlohmann::json out = {{"name", layout.name},
                                {"file", layout.source_file},
                                {"holder_major_axis_m", layout.holder.major_axis_m},
                                {"holder_minor_axis_m", layout.holder.minor_axis_m},
                                {"holder_length_m", layout.holder.length_m},
                                {"units", units}};
    std::cout << out.dump(2) << '\n';
    return;
  }
  std::printf("layout %s (%s): %d units on a %.1f x %.1f mm elliptic holder, %.1f mm long\n",
              layout.name.c_str(), layout.source_file.c_str(), layout.unit_count(),
              layout.holder.major_axis_m * 1e3, layout.holder.minor_axis_m * 1e3,
              layout.holder.length_m * 1e3);
  std::printf("holder frame: x along the axis (distal +), y lateral, z dorsal; positions in mm\n");
  std::printf("%4s %3s %3s %-15s %7s %7s   %-26s %-24s %s\n", "unit", "row", "col", "beam", "x", "arc",
              "position (x, y, z)", "inward normal", "beam axis");
  for (int i = 0; i < layout.unit_count(); ++i) {
    const sensor::UnitPose& u = layout.units[static_cast<size_t>(i)];
    std::printf(
        "%4d %3d %3d %-15s %7.2f %7.2f   (%6.2f, %6.3f, %6.3f)   (%5.3f, %6.3f, %5.3f)   (%5.3f, %6.3f, "
        "%6.3f)\n",
        i, u.row, u.column, sensor::ToString(u.orientation), u.axial_position_m * 1e3, u.arc_position_m * 1e3,
        u.position_m.x() * 1e3, u.position_m.y() * 1e3, u.position_m.z() * 1e3, u.inward_normal.x(),
        u.inward_normal.y(), u.inward_normal.z(), u.beam_axis.x(), u.beam_axis.y(), u.beam_axis.z());
  }
}

void RunCalibrate(const CalibrateOptions& options) {
  const sensor::Layout layout = sensor::LoadLayout(options.layout_path);
  const std::vector<sensor::CalibrationSample> samples =
      sensor::LoadCalibrationLog(options.log_path, layout.unit_count());
  const sensor::CalibrationFit fit =
      sensor::FitCalibration(samples, layout.unit_count(), options.gauge_factor);
  sensor::SaveCalibration(fit.calibration, options.out_path);
  if (options.json) {
    nlohmann::json units = nlohmann::json::array();
    for (size_t i = 0; i < fit.reports.size(); ++i) {
      const sensor::UnitCalibration& c = fit.calibration.units[i];
      const sensor::UnitFitReport& r = fit.reports[i];
      units.push_back({{"unit", i},
                       {"samples", r.samples},
                       {"kn_per_n", c.kn_per_n},
                       {"kt_per_n", c.kt_per_n},
                       {"fn_offset_n", c.fn_offset_n},
                       {"ft_offset_n", c.ft_offset_n},
                       {"rms_fn_residual_n", r.rms_fn_residual_n},
                       {"rms_ft_residual_n", r.rms_ft_residual_n},
                       {"fn_from_ft_coupling", r.fn_from_ft_coupling},
                       {"ft_from_fn_coupling", r.ft_from_fn_coupling}});
    }
    std::cout << nlohmann::json{{"out", options.out_path}, {"units", units}}.dump() << '\n';
    return;
  }
  std::printf("fitted %zu samples for %d units (G = %g); wrote %s\n", samples.size(), layout.unit_count(),
              options.gauge_factor, options.out_path.c_str());
  std::printf("%4s %7s %11s %11s %9s %9s %9s %9s %9s %9s\n", "unit", "samples", "kn [1/N]", "kt [1/N]",
              "Fn0 [N]", "Ft0 [N]", "rmsFn[N]", "rmsFt[N]", "Fn<-Ft", "Ft<-Fn");
  for (size_t i = 0; i < fit.reports.size(); ++i) {
    const sensor::UnitCalibration& c = fit.calibration.units[i];
    const sensor::UnitFitReport& r = fit.reports[i];
    std::printf("%4zu %7d %11.4e %11.4e %9.4f %9.4f %9.4f %9.4f %9.4f %9.4f\n", i, r.samples, c.kn_per_n,
                c.kt_per_n, c.fn_offset_n, c.ft_offset_n, r.rms_fn_residual_n, r.rms_ft_residual_n,
                r.fn_from_ft_coupling, r.ft_from_fn_coupling);
  }
}

void AddSensorCommands(CLI::App& root) {
  CLI::App* sensor = root.add_subcommand(
      "sensor", "The tactile unit of the paper: forward model, inversion, layout and calibration");
  sensor->require_subcommand(1);

  auto forward = std::make_shared<ForwardOptions>();
  CLI::App* forward_command = sensor->add_subcommand(
      "forward", "R1, R2 and dR/R of one unit (paper constants) for a normal and a shear force");
  forward_command->add_option("--fn", forward->fn, "normal force on the mesa [N], >= 0 (default 0)");
  forward_command->add_option(
      "--ft", forward->ft,
      "shear force along the beam [N], either sign: rated -10..10, negative gives R1 < R2 "
      "(default 0)");
  forward_command->add_option("--r0", forward->r0, "unstrained resistance of R1 and R2 [Ohm] (default 3400)");
  forward_command->add_flag("--json", forward->json,
                            "print one JSON object: fn, ft [N], r0, r1, r2 [Ohm], dr1_rel, dr2_rel");
  forward_command->callback([forward] { RunForward(*forward); });

  auto invert = std::make_shared<InvertOptions>();
  CLI::App* invert_command = sensor->add_subcommand(
      "invert", "Fn and Ft of one unit from measured R1, R2 (paper eq. 4, paper constants)");
  invert_command->add_option("--r1", invert->r1, "measured R1 [Ohm], > 0")->required();
  invert_command->add_option("--r2", invert->r2, "measured R2 [Ohm], > 0")->required();
  invert_command->add_option("--r0", invert->r0,
                             "unloaded resistance (tare) of R1 and R2 [Ohm] (default 3400)");
  invert_command->add_flag("--json", invert->json, "print one JSON object: r1, r2, r0 [Ohm], fn, ft [N]");
  invert_command->callback([invert] { RunInvert(*invert); });

  auto layout = std::make_shared<LayoutOptions>();
  CLI::App* layout_command =
      sensor->add_subcommand("layout", "Unit poses of a layout file: position, inward normal, beam axis");
  layout_command->add_option("--layout", layout->layout_path,
                             "layout YAML (default sensor/layouts/default_20.yaml)");
  layout_command->add_flag("--json", layout->json, "print the poses as JSON");
  layout_command->add_option("--picture", layout->picture_path,
                             "write a labelled picture of the layout (PNG: the palmar surface unrolled, units "
                             "numbered, beams and +Ft senses, rows and columns) instead of the table");
  layout_command->callback([layout] { RunLayout(*layout); });

  auto calibrate = std::make_shared<CalibrateOptions>();
  CLI::App* calibrate_command = sensor->add_subcommand(
      "calibrate",
      "Least-squares fit of per-unit kn, kt and offsets from a CSV log of known loads and "
      "readings (docs/sensor.md); writes a calibration YAML");
  calibrate_command->add_option("--log", calibrate->log_path, "calibration log CSV")->required();
  calibrate_command->add_option("--out", calibrate->out_path, "calibration YAML to write")->required();
  calibrate_command->add_option("--layout", calibrate->layout_path,
                                "layout YAML giving the unit count (default sensor/layouts/default_20.yaml)");
  calibrate_command->add_option("--gauge-factor", calibrate->gauge_factor, "gauge factor G (default 100)")
      ->check(CLI::PositiveNumber);
  calibrate_command->add_flag("--json", calibrate->json, "print the fit as JSON");
  calibrate_command->callback([calibrate] { RunCalibrate(*calibrate); });
}

const bool kRegistered = RegisterCommands(&AddSensorCommands);

}  // namespace
}  // namespace graspbed::app
