#pragma once
/// Writing the unit analysis out: CSV curves, PNG plots (paper Figs. 4 and 5), a JSON summary and
/// the resolved config, all written atomically (temp file + rename).

#include <string>
#include <vector>

#include "sensor/fea/fea_config.h"
#include "sensor/fea/unit_analysis.h"

namespace graspbed::fea {

/// The summary as pretty JSON: kn, kt [1/N], their ratios to the paper's, linearity (R^2 of each
/// sweep), superposition_error, cross-talk, peak strains, mesh size and timings.
std::string SummaryJson(const FeaResults& results, const FeaConfig& config);

/// The config as YAML in the layout of sensor/fea/unit_fea.yaml (every value spelled out, from
/// FeaConfigFields(); LoadFeaConfigFile reads it back to the same config).
std::string ConfigYaml(const FeaConfig& config);

/// Writes into `directory` (created if missing): fea_profile.csv, fea_sweep.csv, fea_profile.png,
/// fea_sweep.png, fea_summary.json and fea_config_used.yaml. Returns the paths written.
/// Throws std::runtime_error naming the path when a file cannot be written.
std::vector<std::string> WriteReport(const FeaResults& results, const FeaConfig& config,
                                     const std::string& directory);

}  // namespace graspbed::fea
