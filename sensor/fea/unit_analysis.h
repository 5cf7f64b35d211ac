#pragma once
/// The paper's FEA of one sensing unit (section 3, Figs. 4-5), done by graspbed's own plane-stress
/// model: x-strain along the beam's underside for the maximum normal, shear and combined loads, the
/// resistor-averaged strains over 0..max in both directions, linearity, k_n, k_t, superposition.
///
/// Sign conventions (unit frame, see fea_config.h): Fn > 0 presses the mesa down (-y); Ft > 0 pushes
/// the mesa top towards +x along the beam. Tensile strain is positive.

#include <Eigen/Core>

#include <vector>

#include "sensor/fea/fea_config.h"
#include "sensor/fea/plane_stress.h"

namespace graspbed::fea {

/// Strain eps_xx sampled along a surface at the element nodes, ascending x.
struct StrainLine {
  std::vector<double> x_mm;  ///< positions [mm]
  std::vector<double> eps;   ///< eps_xx at those positions [-]
};

/// The x-strain along the beam underside (paper Fig. 4), at the nodes of the free span.
struct StrainProfile {
  std::vector<double> x_mm;    ///< [mm] from the beam centre
  std::vector<double> normal;  ///< under Fn = max, Ft = 0 [-]
  std::vector<double> shear;   ///< under Fn = 0, Ft = max [-]
  std::vector<double> both;    ///< under Fn = Ft = max, solved as one load case [-]
  std::vector<double> sum;     ///< normal + shear, added afterwards [-]
};

/// Resistor-averaged strains over a force sweep in one direction (paper Fig. 5).
struct ResistorSweep {
  std::vector<double> force_n;  ///< applied force [N]
  std::vector<double> eps1;     ///< mean eps_xx over R1's extent [-]
  std::vector<double> eps2;     ///< mean eps_xx over R2's extent [-]
};

/// Least-squares line y = slope * x + intercept and its coefficient of determination.
struct LineFit {
  double slope = 0.0;
  double intercept = 0.0;
  double r_squared = 0.0;  ///< 1 for a perfect line; 1 when the data have no variance at all
};

/// Size and cost of one analysis.
struct FeaStats {
  int nodes = 0;
  int elements = 0;
  int free_dofs = 0;
  long stiffness_non_zeros = 0;
  int load_cases = 0;
  double mesh_s = 0.0;             ///< meshing [s]
  double assemble_factor_s = 0.0;  ///< stiffness assembly + LDLT factorisation [s]
  double solve_s = 0.0;            ///< load assembly + all load cases' solves + strain recovery [s]
};

/// The sensitivities of one unit, as the sensor model uses them.
struct Sensitivities {
  double kn_per_n = 0.0;  ///< eps_n per N of normal force, eps_n = (eps1 + eps2) / 2 [1/N]
  double kt_per_n = 0.0;  ///< eps_t per N of shear along the beam, eps_t = (eps1 - eps2) / 2 [1/N]
};

/// Everything the analysis reports.
struct FeaResults {
  StrainProfile profile;
  ResistorSweep normal_sweep;   ///< Ft = 0, Fn = 0..max
  ResistorSweep shear_sweep;    ///< Fn = 0, Ft = 0..max
  LineFit normal_fit;           ///< (eps1 + eps2) / 2 against Fn
  LineFit shear_fit;            ///< (eps1 - eps2) / 2 against Ft
  Sensitivities sensitivities;  ///< slopes of the two fits
  double kn_ratio = 0.0;        ///< k_n / paper's k_n
  double kt_ratio = 0.0;        ///< k_t / paper's k_t
  /// max |both - (normal + shear)| / max |both| along the underside, and over the two resistors.
  double superposition_error = 0.0;
  /// Cross-talk of the ideal unit: |eps1 - eps2| / |eps1 + eps2| under Fn alone, and
  /// |eps1 + eps2| / |eps1 - eps2| under Ft alone (0 for a perfectly symmetric model).
  double normal_to_shear_cross_talk = 0.0;
  double shear_to_normal_cross_talk = 0.0;
  double peak_normal_strain = 0.0;  ///< largest |eps_xx| on the underside under Fn = max [-]
  double peak_shear_strain = 0.0;   ///< largest |eps_xx| on the underside under Ft = max [-]
  FeaStats stats;
};

/// Least-squares fit of y against x (same length, at least 2 points).
LineFit FitLine(const std::vector<double>& x, const std::vector<double>& y);

/// eps_xx along the free bottom faces of grid row `row` of a MeshRectangles mesh (faces with no
/// element below), at the element nodes; values at nodes shared by two elements are averaged.
StrainLine BottomSurfaceStrain(const PlaneStressModel& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                               int row);

/// Mean of eps_xx over x in [x_start, x_end] along the free bottom faces of grid row `row`
/// (exact Gauss integration along each face, divided by the covered length).
double AverageBottomStrain(const PlaneStressModel& model, const Eigen::Ref<const Eigen::VectorXd>& u, int row,
                           double x_start_mm, double x_end_mm);

/// The meshed, constrained and factorised unit (inverted-U frame + mesa, brace feet fixed).
class UnitModel {
 public:
  /// Validates `config` (std::invalid_argument on a bad value), meshes and factorises.
  explicit UnitModel(const FeaConfig& config);

  /// The config the unit was built from.
  const FeaConfig& config() const { return config_; }
  /// The assembled, factorised plane-stress model.
  const PlaneStressModel& model() const { return model_; }
  /// Grid row whose bottom faces are the beam underside.
  int UndersideRow() const { return underside_row_; }
  /// Nodal forces [N] of a uniform traction on the mesa top whose resultant is Fn down and Ft along +x.
  Eigen::VectorXd LoadVector(double fn_n, double ft_n) const;
  /// eps_xx along the beam underside (free span only) for displacements `u`.
  StrainLine Underside(const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// Mean eps_xx over R1 and R2 for displacements `u`.
  Eigen::Vector2d ResistorStrains(const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// Time spent meshing [s].
  double mesh_s() const { return mesh_s_; }
  /// Time spent assembling and factorising the stiffness [s].
  double assemble_factor_s() const { return assemble_factor_s_; }

 private:
  // Meshes and factorises, recording the two times (members are initialised in declaration order).
  static PlaneStressModel BuildModel(const FeaConfig& config, double* mesh_s, double* assemble_factor_s);

  FeaConfig config_;
  double mesh_s_ = 0.0;
  double assemble_factor_s_ = 0.0;
  PlaneStressModel model_;
  int underside_row_ = 0;
  std::vector<int> mesa_top_elements_;
  std::vector<int> underside_elements_;  // free-span elements along the underside, ascending x
};

/// Runs the whole analysis: one factorisation, all load cases solved together.
FeaResults RunUnitAnalysis(const FeaConfig& config);

/// k_n and k_t of the unit described by `config` (runs the analysis); for the sensor model to take
/// its sensitivities from geometry instead of the paper's constants.
Sensitivities ComputeSensitivities(const FeaConfig& config);

}  // namespace graspbed::fea
