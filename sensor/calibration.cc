#include "sensor/calibration.h"

#include <unistd.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "common/yaml_map.h"
#include "sensor/raw_frame.h"

namespace graspbed::sensor {
namespace {

using common::ConfigError;
using common::NumberRule;
using common::YamlMap;

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream stream(line);
  while (std::getline(stream, field, ',')) {
    const size_t first = field.find_first_not_of(" \t\r");
    const size_t last = field.find_last_not_of(" \t\r");
    fields.push_back(first == std::string::npos ? "" : field.substr(first, last - first + 1));
  }
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

}  // namespace

Calibration PaperCalibration(int unit_count) {
  if (unit_count < 1 || unit_count > kMaxUnits) {
    throw std::invalid_argument("calibration: unit count " + std::to_string(unit_count) + " outside 1.." +
                                std::to_string(kMaxUnits));
  }
  return Calibration{std::vector<UnitCalibration>(static_cast<size_t>(unit_count))};
}

Calibration NominalCalibration(const UnitConstants& nominal, int unit_count) {
  Calibration calibration = PaperCalibration(unit_count);
  for (UnitCalibration& unit : calibration.units) {
    unit.gauge_factor = nominal.gauge_factor;
    unit.kn_per_n = nominal.kn_per_n;
    unit.kt_per_n = nominal.kt_per_n;
  }
  return calibration;
}

Calibration LoadCalibration(const std::string& path, int expected_unit_count) {
  const YamlMap root = YamlMap::LoadFile(path);
  const std::vector<YamlMap> unit_maps = root.GetMapList("units");
  if (unit_maps.empty()) root.Fail("units", "missing required list of per-unit calibrations");
  if (static_cast<int>(unit_maps.size()) != expected_unit_count) {
    root.Fail("units", "file has " + std::to_string(unit_maps.size()) + " units, the layout has " +
                           std::to_string(expected_unit_count));
  }
  Calibration calibration;
  for (const YamlMap& map : unit_maps) {
    UnitCalibration unit;
    unit.gauge_factor = map.RequireNumber("gauge_factor", NumberRule::Positive());
    unit.kn_per_n = map.RequireNumber("kn_per_n", NumberRule::Positive());
    unit.kt_per_n = map.RequireNumber("kt_per_n", NumberRule::Positive());
    unit.fn_offset_n = map.GetNumber("fn_offset_n", 0.0);
    unit.ft_offset_n = map.GetNumber("ft_offset_n", 0.0);
    map.RejectUnknownKeys();
    calibration.units.push_back(unit);
  }
  root.RejectUnknownKeys({"comment"});
  return calibration;
}

void SaveCalibration(const Calibration& calibration, const std::string& path) {
  std::ostringstream text;
  text.precision(std::numeric_limits<double>::max_digits10);
  text << "# graspbed sensor calibration: per-unit constants of the inversion (paper eq. 4),\n"
       << "# Fn = (dR1/R1 + dR2/R2) / (2 G kn) - fn_offset_n, Ft = (dR1/R1 - dR2/R2) / (2 G kt) - "
          "ft_offset_n.\n"
       << "# Units in layout order. Format: docs/sensor.md.\n"
       << "units:\n";
  for (const UnitCalibration& unit : calibration.units) {
    text << "  - {gauge_factor: " << unit.gauge_factor << ", kn_per_n: " << unit.kn_per_n
         << ", kt_per_n: " << unit.kt_per_n << ", fn_offset_n: " << unit.fn_offset_n
         << ", ft_offset_n: " << unit.ft_offset_n << "}\n";
  }
  // Temp file in the same directory + rename: readers see the old file or the new one, never half.
  const std::string temporary = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(temporary, std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot write calibration (cannot create " + temporary + ")");
    out << text.str();
    out.flush();
    if (!out) {
      std::remove(temporary.c_str());
      throw std::runtime_error(path + ": cannot write calibration");
    }
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    std::remove(temporary.c_str());
    throw std::runtime_error(path + ": cannot write calibration (rename failed)");
  }
}

std::vector<CalibrationSample> LoadCalibrationLog(const std::string& path, int unit_count) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open file");
  std::vector<std::string> header;
  std::map<std::string, size_t> column;
  std::vector<CalibrationSample> samples;
  std::vector<std::pair<double, double>> resistances;  // r1, r2 per sample when given in Ohm
  bool in_ohm = false;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    const std::vector<std::string> fields = SplitCsv(line);
    const std::string where = path + ":" + std::to_string(line_number) + ": ";
    if (header.empty()) {
      header = fields;
      for (size_t i = 0; i < header.size(); ++i) {
        const std::string& name = header[i];
        if (name != "unit" && name != "fn_n" && name != "ft_n" && name != "dr1_rel" && name != "dr2_rel" &&
            name != "r1_ohm" && name != "r2_ohm") {
          throw ConfigError(where + "header column '" + name +
                            "': unknown column; valid: unit, fn_n, ft_n, dr1_rel, dr2_rel, r1_ohm, r2_ohm");
        }
        if (!column.emplace(name, i).second)
          throw ConfigError(where + "header column '" + name + "' given twice");
      }
      for (const char* name : {"unit", "fn_n", "ft_n"}) {
        if (!column.count(name))
          throw ConfigError(where + "header: missing column '" + std::string(name) + "'");
      }
      const bool relative = column.count("dr1_rel") && column.count("dr2_rel");
      in_ohm = column.count("r1_ohm") && column.count("r2_ohm");
      if (relative == in_ohm) {
        throw ConfigError(where + "header: give either dr1_rel, dr2_rel or r1_ohm, r2_ohm");
      }
      continue;
    }
    if (fields.size() != header.size()) {
      throw ConfigError(where + "expected " + std::to_string(header.size()) + " columns, got " +
                        std::to_string(fields.size()));
    }
    const auto number = [&](const char* name) {
      const std::string& text = fields[column.at(name)];
      char* end = nullptr;
      const double value = std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size()) {
        throw ConfigError(where + name + " = " + text + ": expected a number");
      }
      if (!std::isfinite(value)) throw ConfigError(where + name + " = " + text + ": must be finite");
      return value;
    };
    CalibrationSample sample;
    sample.line = line_number;
    const double unit = number("unit");
    if (unit != std::floor(unit) || unit < 0 || unit >= unit_count) {
      throw ConfigError(where + "unit = " + fields[column.at("unit")] + ": must be a unit index 0.." +
                        std::to_string(unit_count - 1));
    }
    sample.unit = static_cast<int>(unit);
    sample.fn_n = number("fn_n");
    sample.ft_n = number("ft_n");
    if (in_ohm) {
      const double r1 = number("r1_ohm");
      const double r2 = number("r2_ohm");
      if (!(r1 > 0)) throw ConfigError(where + "r1_ohm = " + fields[column.at("r1_ohm")] + ": must be > 0");
      if (!(r2 > 0)) throw ConfigError(where + "r2_ohm = " + fields[column.at("r2_ohm")] + ": must be > 0");
      resistances.emplace_back(r1, r2);
    } else {
      sample.dr1_rel = number("dr1_rel");
      sample.dr2_rel = number("dr2_rel");
    }
    samples.push_back(sample);
  }
  if (header.empty()) throw ConfigError(path + ": empty calibration log (no header)");
  if (in_ohm) {
    // Each unit's reference is the mean of its zero-load readings.
    std::vector<double> sum1(static_cast<size_t>(unit_count), 0.0),
        sum2(static_cast<size_t>(unit_count), 0.0);
    std::vector<int> zeros(static_cast<size_t>(unit_count), 0);
    for (size_t i = 0; i < samples.size(); ++i) {
      if (samples[i].fn_n == 0.0 && samples[i].ft_n == 0.0) {
        const size_t unit = static_cast<size_t>(samples[i].unit);
        sum1[unit] += resistances[i].first;
        sum2[unit] += resistances[i].second;
        ++zeros[unit];
      }
    }
    for (size_t i = 0; i < samples.size(); ++i) {
      const size_t unit = static_cast<size_t>(samples[i].unit);
      if (zeros[unit] == 0) {
        throw ConfigError(path + ":" + std::to_string(samples[i].line) + ": unit = " + std::to_string(unit) +
                          ": no zero-load row (fn_n = ft_n = 0) to refer r1_ohm, r2_ohm to");
      }
      samples[i].dr1_rel = resistances[i].first / (sum1[unit] / zeros[unit]) - 1.0;
      samples[i].dr2_rel = resistances[i].second / (sum2[unit] / zeros[unit]) - 1.0;
    }
  }
  return samples;
}

CalibrationFit FitCalibration(const std::vector<CalibrationSample>& samples, int unit_count,
                              double gauge_factor) {
  if (unit_count < 1 || unit_count > kMaxUnits) {
    throw std::invalid_argument("calibration fit: unit count " + std::to_string(unit_count) + " outside 1.." +
                                std::to_string(kMaxUnits));
  }
  if (!(gauge_factor > 0.0) || !std::isfinite(gauge_factor)) {
    throw std::invalid_argument("calibration fit: gauge factor must be > 0");
  }
  std::vector<std::vector<const CalibrationSample*>> by_unit(static_cast<size_t>(unit_count));
  for (const CalibrationSample& sample : samples) {
    if (sample.unit < 0 || sample.unit >= unit_count) {
      throw std::invalid_argument("calibration fit: sample for unit " + std::to_string(sample.unit) +
                                  " outside 0.." + std::to_string(unit_count - 1));
    }
    by_unit[static_cast<size_t>(sample.unit)].push_back(&sample);
  }
  CalibrationFit fit;
  for (int unit = 0; unit < unit_count; ++unit) {
    const auto& rows = by_unit[static_cast<size_t>(unit)];
    const Eigen::Index count = static_cast<Eigen::Index>(rows.size());
    Eigen::MatrixXd design(count, 3);
    Eigen::VectorXd mean(count), difference(count);
    for (Eigen::Index i = 0; i < count; ++i) {
      const CalibrationSample& row = *rows[static_cast<size_t>(i)];
      design.row(i) << row.fn_n, row.ft_n, 1.0;
      mean(i) = 0.5 * (row.dr1_rel + row.dr2_rel);
      difference(i) = 0.5 * (row.dr1_rel - row.dr2_rel);
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
    if (count < 3 || qr.rank() < 3) {
      throw std::invalid_argument("calibration fit: unit " + std::to_string(unit) + " has " +
                                  std::to_string(count) +
                                  " samples without independent Fn, Ft and zero-load variation; need at "
                                  "least 3 with both loads varied");
    }
    const Eigen::Vector3d normal = qr.solve(mean);       // [G kn, coupling, G kn fn_offset]
    const Eigen::Vector3d shear = qr.solve(difference);  // [coupling, G kt, G kt ft_offset]
    if (!(normal(0) > 0.0) || !(shear(1) > 0.0)) {
      throw std::invalid_argument("calibration fit: unit " + std::to_string(unit) +
                                  " has a non-positive sensitivity (check the sign of the loads and which "
                                  "column is R1)");
    }
    UnitCalibration result;
    result.gauge_factor = gauge_factor;
    result.kn_per_n = normal(0) / gauge_factor;
    result.kt_per_n = shear(1) / gauge_factor;
    result.fn_offset_n = normal(2) / normal(0);
    result.ft_offset_n = shear(2) / shear(1);
    UnitFitReport report;
    report.samples = static_cast<int>(count);
    report.fn_from_ft_coupling = normal(1) / normal(0);
    report.ft_from_fn_coupling = shear(0) / shear(1);
    double sum_fn = 0.0, sum_ft = 0.0;
    for (Eigen::Index i = 0; i < count; ++i) {
      const double fn = mean(i) / (gauge_factor * result.kn_per_n) - result.fn_offset_n;
      const double ft = difference(i) / (gauge_factor * result.kt_per_n) - result.ft_offset_n;
      sum_fn += std::pow(fn - design(i, 0), 2);
      sum_ft += std::pow(ft - design(i, 1), 2);
    }
    report.rms_fn_residual_n = std::sqrt(sum_fn / static_cast<double>(count));
    report.rms_ft_residual_n = std::sqrt(sum_ft / static_cast<double>(count));
    fit.calibration.units.push_back(result);
    fit.reports.push_back(report);
  }
  return fit;
}

}  // namespace graspbed::sensor
