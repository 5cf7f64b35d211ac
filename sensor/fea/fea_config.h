#pragma once
/// Configuration of the sensing unit's finite-element analysis (paper section 3): geometry,
/// material, mesh, where the two resistors sit and the load sweep. Defaults are the paper's numbers;
/// what the paper leaves open is chosen here and stated in sensor/fea/unit_fea.yaml and docs/fea.md.
///
/// Model frame: x along the beam (0 at the beam centre, + towards the right brace), y up (0 at the
/// brace feet). The frame is an inverted U: two braces standing on fixed feet carry the beam, whose
/// underside holds the gauge; the mesa sits on top of the beam centre and takes the load.

#include <string>

#include "common/field_table.h"
#include "common/yaml_map.h"

namespace graspbed::fea {

/// Elastic constants of the frame (spring steel 65Mn).
struct MaterialConfig {
  double youngs_modulus_gpa = 197.0;  ///< E [GPa]
  double poisson_ratio = 0.3;         ///< nu [-]
};

/// Frame geometry [mm].
struct GeometryConfig {
  double beam_length_mm = 3.0;      ///< overall length of the beam, outer face to outer face of the braces
  double beam_thickness_mm = 0.2;   ///< beam thickness (y)
  double width_mm = 2.0;            ///< out-of-plane width of the frame = plane-stress thickness
  double brace_thickness_mm = 0.5;  ///< brace thickness along x; braces sit under the beam's ends
  double brace_height_mm = 3.0;     ///< brace height, foot to beam underside
  double mesa_length_mm = 0.5;      ///< mesa length along the beam, centred (paper: not given)
  double mesa_height_mm = 0.5;      ///< mesa thickness above the beam (paper: 0.5 mm)
  /// Free span of the beam between the braces' inner faces [mm].
  double SpanMm() const { return beam_length_mm - 2.0 * brace_thickness_mm; }
};

/// Finite-element mesh.
struct MeshConfig {
  double element_size_mm = 0.05;  ///< largest element edge [mm] (paper: 0.05 mm)
};

/// Extent of one resistor along the beam underside, x from the beam centre [mm].
struct ResistorExtent {
  double start_mm = 0.0;
  double end_mm = 0.0;
};

/// The silicon gauge's two resistors on the beam underside. R1 is the half where a positive shear
/// (mesa pushed towards +x) adds tensile strain, so eps1 = eps_n + eps_t as in paper eq. 3.
struct GaugeConfig {
  ResistorExtent r1{0.0, 0.75};   ///< [mm]
  ResistorExtent r2{-0.75, 0.0};  ///< [mm]
};

/// Loads: a uniform traction on the mesa top; the sweep runs 0..max_force_n in `steps` steps.
struct LoadConfig {
  double max_force_n = 10.0;  ///< largest normal and shear force, and the Fig. 4 load [N]
  int steps = 10;             ///< sweep intervals (steps + 1 load levels per direction)
};

/// The paper's sensitivities, for the ratios in the report.
struct ReferenceConfig {
  double kn_per_n = 5.5e-4;  ///< paper's k_n [1/N]
  double kt_per_n = 4.1e-4;  ///< paper's k_t [1/N]
};

/// Everything the analysis needs. Plain values; Validate() checks them.
struct FeaConfig {
  MaterialConfig material;
  GeometryConfig geometry;
  MeshConfig mesh;
  GaugeConfig gauge;
  LoadConfig load;
  ReferenceConfig reference;

  /// Checks every field against FeaConfigFields() and the geometry and mesh cross-checks
  /// (braces that leave no span, a mesa or resistor outside the span, a mesh too coarse to put one
  /// element through the beam's thickness or so fine it would not fit in memory).
  /// @throws common::ConfigError "key = value: reason" (key from the file's top, e.g.
  ///   "mesh.element_size_mm") for the first problem.
  void Validate() const;
};

/// The fields of FeaConfig, its sections and cross-checks: the loader, Validate() and the report's
/// fea_config_used.yaml derive from it.
const common::FieldTable<FeaConfig>& FeaConfigFields();

/// Reads a config from YAML (every key optional, defaults as above, unknown keys refused).
/// @throws common::ConfigError naming the file, line, key and value, the cross-checks included
///   (a check on a key the file leaves at its default names no line and marks the value "(default)").
FeaConfig LoadFeaConfig(const common::YamlMap& root);
/// Loads and validates the YAML file at `path`.
/// @throws common::ConfigError as LoadFeaConfig, or when the file cannot be read.
FeaConfig LoadFeaConfigFile(const std::string& path);
/// Path of the shipped default config, sensor/fea/unit_fea.yaml under common::DataDir().
std::string DefaultFeaConfigPath();

}  // namespace graspbed::fea
