// `graspbed fea`: the sensing unit's plane-stress finite-element analysis (paper section 3).
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "app/command_registry.h"
#include "sensor/calibration.h"
#include "sensor/fea/fea_config.h"
#include "sensor/fea/report.h"
#include "sensor/fea/unit_analysis.h"

namespace graspbed::app {
namespace {

struct FeaOptions {
  std::string config_path = fea::DefaultFeaConfigPath();
  std::string out_dir;
  bool json = false;
  std::string calibration_path;
  int units = 20;
};

void PrintTable(const fea::FeaResults& r, const fea::FeaConfig& config) {
  std::printf("unit FEA: %d elements (9-node), %d free dofs, %d load cases\n", r.stats.elements,
              r.stats.free_dofs, r.stats.load_cases);
  std::printf("  time: mesh %.3f s, assemble+factorise %.3f s, solve+recover %.3f s\n", r.stats.mesh_s,
              r.stats.assemble_factor_s, r.stats.solve_s);
  std::printf("  %-24s %12s %12s %8s\n", "", "graspbed", "paper", "ratio");
  std::printf("  %-24s %12.4e %12.4e %8.3f\n", "k_n [1/N]", r.sensitivities.kn_per_n,
              config.reference.kn_per_n, r.kn_ratio);
  std::printf("  %-24s %12.4e %12.4e %8.3f\n", "k_t [1/N]", r.sensitivities.kt_per_n,
              config.reference.kt_per_n, r.kt_ratio);
  std::printf("  linearity R^2: normal %.9f, shear %.9f\n", r.normal_fit.r_squared, r.shear_fit.r_squared);
  std::printf("  superposition error: %.3e\n", r.superposition_error);
  std::printf("  peak underside strain at %.0f N: normal %.4e, shear %.4e\n", config.load.max_force_n,
              r.peak_normal_strain, r.peak_shear_strain);
}

void RunFea(const FeaOptions& options) {
  const fea::FeaConfig config = fea::LoadFeaConfigFile(options.config_path);
  const fea::FeaResults results = fea::RunUnitAnalysis(config);
  if (options.json) {
    std::cout << fea::SummaryJson(results, config);
  } else {
    PrintTable(results, config);
  }
  if (!options.out_dir.empty()) {
    const std::vector<std::string> written = fea::WriteReport(results, config, options.out_dir);
    if (!options.json) {
      for (const std::string& path : written) std::printf("  wrote %s\n", path.c_str());
    }
  }
  if (!options.calibration_path.empty()) {
    // Paper constants everywhere, except the sensitivities, which come from this analysis.
    sensor::Calibration calibration = sensor::PaperCalibration(options.units);
    for (sensor::UnitCalibration& unit : calibration.units) {
      unit.kn_per_n = results.sensitivities.kn_per_n;
      unit.kt_per_n = results.sensitivities.kt_per_n;
    }
    sensor::SaveCalibration(calibration, options.calibration_path);
    if (!options.json)
      std::printf("  wrote %s (%d unit%s)\n", options.calibration_path.c_str(), options.units, options.units == 1 ? "" : "s");
  }
}

void AddFeaCommand(CLI::App& root) {
  auto options = std::make_shared<FeaOptions>();
  CLI::App* command = root.add_subcommand(
      "fea",
      "Plane-stress finite-element analysis of one sensing unit: underside strain profiles, "
      "resistor strains over 0..10 N, k_n and k_t against the paper's");
  command->add_option("--config", options->config_path, "FEA config YAML (default sensor/fea/unit_fea.yaml)")
      ->check(CLI::ExistingFile);
  command->add_option("--out", options->out_dir,
                      "write CSV curves, PNG plots, summary JSON and the config used here");
  command->add_flag("--json", options->json, "print the summary as JSON instead of a table");
  command->add_option("--write-calibration", options->calibration_path,
                      "write a calibration YAML with the paper's constants but k_n, k_t from this analysis");
  command->add_option("--units", options->units, "number of units in the written calibration")
      ->check(CLI::Range(1, 1000));
  command->callback([options] { RunFea(*options); });
}

const bool kRegistered = RegisterCommands(&AddFeaCommand);

}  // namespace
}  // namespace graspbed::app
