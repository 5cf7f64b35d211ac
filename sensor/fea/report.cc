#include "sensor/fea/report.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "common/plot.h"

namespace graspbed::fea {
namespace {

constexpr double kMicrostrain = 1e6;  // plots show strain in microstrain

void WriteAtomically(const std::string& path, const std::string& text) {
  const std::string temp_path = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(temp_path, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temp_path, ignored);
      throw std::runtime_error("cannot write " + path);
    }
  }
  std::error_code error;
  std::filesystem::rename(temp_path, path, error);
  if (error) {
    std::filesystem::remove(temp_path, error);
    throw std::runtime_error("cannot write " + path + ": " + error.message());
  }
}

std::vector<double> Scaled(const std::vector<double>& values, double factor) {
  std::vector<double> scaled(values);
  for (double& value : scaled) value *= factor;
  return scaled;
}

std::string ProfileCsv(const StrainProfile& profile) {
  std::ostringstream out;
  out << std::setprecision(10);
  out << "x_mm,eps_normal,eps_shear,eps_both,eps_sum\n";
  for (size_t i = 0; i < profile.x_mm.size(); ++i) {
    out << profile.x_mm[i] << ',' << profile.normal[i] << ',' << profile.shear[i] << ',' << profile.both[i]
        << ',' << profile.sum[i] << '\n';
  }
  return out.str();
}

std::string SweepCsv(const FeaResults& results) {
  std::ostringstream out;
  out << std::setprecision(10);
  out << "force_n,normal_eps1,normal_eps2,normal_eps_n,shear_eps1,shear_eps2,shear_eps_t\n";
  const ResistorSweep& n = results.normal_sweep;
  const ResistorSweep& t = results.shear_sweep;
  for (size_t i = 0; i < n.force_n.size(); ++i) {
    out << n.force_n[i] << ',' << n.eps1[i] << ',' << n.eps2[i] << ',' << 0.5 * (n.eps1[i] + n.eps2[i]) << ','
        << t.eps1[i] << ',' << t.eps2[i] << ',' << 0.5 * (t.eps1[i] - t.eps2[i]) << '\n';
  }
  return out.str();
}

std::string Scientific(double value) {
  std::ostringstream out;
  out << std::scientific << std::setprecision(3) << value;
  return out.str();
}

std::string Fixed(double value, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

plot::Chart ProfileChart(const FeaResults& results, const FeaConfig& config) {
  const StrainProfile& p = results.profile;
  const std::string force = Fixed(config.load.max_force_n, 0) + " N";
  plot::Chart chart;
  chart.title = "Beam underside x-strain (paper Fig. 4)";
  chart.x_label = "x along the beam from its centre [mm]";
  chart.y_label = "eps_xx [microstrain]";
  chart.series = {{"normal " + force, p.x_mm, Scaled(p.normal, kMicrostrain)},
                  {"shear " + force, p.x_mm, Scaled(p.shear, kMicrostrain)},
                  {"both " + force, p.x_mm, Scaled(p.both, kMicrostrain)},
                  {"sum normal + shear", p.x_mm, Scaled(p.sum, kMicrostrain), true}};
  chart.bands = {{config.gauge.r1.start_mm, config.gauge.r1.end_mm, "R1"},
                 {config.gauge.r2.start_mm, config.gauge.r2.end_mm, "R2"}};
  const double half_mesa = 0.5 * config.geometry.mesa_length_mm;
  chart.markers = {{-half_mesa, "mesa"}, {half_mesa, ""}};
  chart.include_zero_y = true;
  return chart;
}

plot::Figure SweepFigure(const FeaResults& results) {
  const ResistorSweep& n = results.normal_sweep;
  const ResistorSweep& t = results.shear_sweep;
  plot::Chart normal;
  normal.title = "Normal force: k_n = " + Scientific(results.sensitivities.kn_per_n) +
                 " /N, R^2 = " + Fixed(results.normal_fit.r_squared, 6);
  normal.x_label = "Fn [N]";
  normal.y_label = "resistor-averaged strain [microstrain]";
  std::vector<double> mean_n, half_diff_t;
  for (size_t i = 0; i < n.force_n.size(); ++i) {
    mean_n.push_back(0.5 * (n.eps1[i] + n.eps2[i]));
    half_diff_t.push_back(0.5 * (t.eps1[i] - t.eps2[i]));
  }
  normal.series = {{"eps1 (R1)", n.force_n, Scaled(n.eps1, kMicrostrain), false, true},
                   {"eps2 (R2)", n.force_n, Scaled(n.eps2, kMicrostrain), true, true},
                   {"eps_n = (eps1 + eps2) / 2", n.force_n, Scaled(mean_n, kMicrostrain)}};
  normal.include_zero_y = true;
  plot::Chart shear;
  shear.title = "Shear force: k_t = " + Scientific(results.sensitivities.kt_per_n) +
                " /N, R^2 = " + Fixed(results.shear_fit.r_squared, 6);
  shear.x_label = "Ft [N]";
  shear.y_label = "resistor-averaged strain [microstrain]";
  shear.series = {{"eps1 (R1)", t.force_n, Scaled(t.eps1, kMicrostrain), false, true},
                  {"eps2 (R2)", t.force_n, Scaled(t.eps2, kMicrostrain), false, true},
                  {"eps_t = (eps1 - eps2) / 2", t.force_n, Scaled(half_diff_t, kMicrostrain)}};
  shear.include_zero_y = true;
  plot::Figure figure;
  figure.title = "Resistor strains over the load sweep (paper Fig. 5)";
  figure.panels = {normal, shear};
  figure.columns = 2;
  figure.panel_width_px = 640;
  figure.panel_height_px = 480;
  return figure;
}

}  // namespace

std::string SummaryJson(const FeaResults& results, const FeaConfig& config) {
  nlohmann::ordered_json json;
  json["kn"] = results.sensitivities.kn_per_n;
  json["kt"] = results.sensitivities.kt_per_n;
  json["kn_paper"] = config.reference.kn_per_n;
  json["kt_paper"] = config.reference.kt_per_n;
  json["kn_ratio"] = results.kn_ratio;
  json["kt_ratio"] = results.kt_ratio;
  json["linearity"] = {{"normal_r2", results.normal_fit.r_squared},
                       {"shear_r2", results.shear_fit.r_squared},
                       {"normal_intercept", results.normal_fit.intercept},
                       {"shear_intercept", results.shear_fit.intercept}};
  json["superposition_error"] = results.superposition_error;
  json["cross_talk"] = {{"normal_to_shear", results.normal_to_shear_cross_talk},
                        {"shear_to_normal", results.shear_to_normal_cross_talk}};
  json["peak_strain"] = {{"normal", results.peak_normal_strain}, {"shear", results.peak_shear_strain}};
  const size_t last = results.normal_sweep.force_n.size() - 1;
  json["at_max_force"] = {{"force_n", results.normal_sweep.force_n[last]},
                          {"normal_eps1", results.normal_sweep.eps1[last]},
                          {"normal_eps2", results.normal_sweep.eps2[last]},
                          {"shear_eps1", results.shear_sweep.eps1[last]},
                          {"shear_eps2", results.shear_sweep.eps2[last]}};
  const FeaStats& s = results.stats;
  json["mesh"] = {{"element_size_mm", config.mesh.element_size_mm},
                  {"nodes", s.nodes},
                  {"elements", s.elements},
                  {"free_dofs", s.free_dofs},
                  {"stiffness_non_zeros", s.stiffness_non_zeros},
                  {"load_cases", s.load_cases}};
  json["time_s"] = {{"mesh", s.mesh_s}, {"assemble_factor", s.assemble_factor_s}, {"solve", s.solve_s}};
  return json.dump(2) + "\n";
}

std::string ConfigYaml(const FeaConfig& config) { return FeaConfigFields().EmitYaml(config); }

std::vector<std::string> WriteReport(const FeaResults& results, const FeaConfig& config,
                                     const std::string& directory) {
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) throw std::runtime_error("cannot create output directory " + directory + ": " + error.message());
  const std::filesystem::path dir(directory);
  std::vector<std::string> written;
  auto path = [&](const char* name) {
    written.push_back((dir / name).string());
    return written.back();
  };
  WriteAtomically(path("fea_profile.csv"), ProfileCsv(results.profile));
  WriteAtomically(path("fea_sweep.csv"), SweepCsv(results));
  plot::WritePng(ProfileChart(results, config), path("fea_profile.png"), 900, 540);
  plot::WritePng(SweepFigure(results), path("fea_sweep.png"));
  WriteAtomically(path("fea_summary.json"), SummaryJson(results, config));
  WriteAtomically(path("fea_config_used.yaml"), ConfigYaml(config));
  return written;
}

}  // namespace graspbed::fea
