#pragma once
/// Linear-elastic plane-stress finite elements: 9-node Lagrange quadrilaterals (biquadratic, 3x3
/// Gauss integration), which bend without shear locking even with a few elements through a thin
/// beam. The stiffness is assembled and factorised once (Eigen SimplicialLDLT); any number of load
/// cases are then solved together. Units: mm, N, MPa; strains are dimensionless.

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <memory>
#include <vector>

#include "sensor/fea/mesh.h"

namespace graspbed::fea {

/// Isotropic material and the out-of-plane thickness of the plane-stress model.
struct PlaneStressMaterial {
  double youngs_modulus_mpa = 197000.0;  ///< E [MPa]
  double poisson_ratio = 0.3;            ///< nu [-]
  double thickness_mm = 2.0;             ///< out-of-plane width of the part [mm]
};

/// A prescribed displacement of one degree of freedom: dof = 2 * node + (0 for x, 1 for y).
struct PrescribedDof {
  int dof = 0;
  double value_mm = 0.0;  ///< prescribed displacement [mm]
};

/// Element sides in the element's natural coordinates.
enum class Side { kBottom, kRight, kTop, kLeft };  ///< eta = -1, xi = +1, eta = +1, xi = -1

/// Shape functions of the 9-node element at natural coordinates (xi, eta) in [-1, 1]^2, tensor order.
Eigen::Matrix<double, 9, 1> ShapeFunctions(double xi, double eta);

/// An assembled and factorised plane-stress model. Immutable after construction.
class PlaneStressModel {
 public:
  /// Assembles K over `mesh`, removes the prescribed dofs and factorises. Throws std::invalid_argument
  /// for a bad material, an out-of-range dof or an element with a non-positive Jacobian, and
  /// std::runtime_error when the stiffness is singular (e.g. too few constraints).
  PlaneStressModel(Mesh mesh, PlaneStressMaterial material, std::vector<PrescribedDof> prescribed);

  /// The mesh the model was built on.
  const Mesh& mesh() const { return mesh_; }
  /// Material and thickness.
  const PlaneStressMaterial& material() const { return material_; }
  /// Degrees of freedom of the whole mesh (free + prescribed).
  int DofCount() const { return mesh_.DofCount(); }
  /// Degrees of freedom left after removing the prescribed ones (size of the factorised system).
  int FreeDofCount() const { return static_cast<int>(free_dofs_.size()); }
  /// Non-zeros of the factorised stiffness (upper triangle included twice) -- a size statistic.
  long StiffnessNonZeros() const { return stiffness_non_zeros_; }

  /// Solves K u = f for every column of `loads` (DofCount() x cases, nodal forces [N]); returns the
  /// displacements (DofCount() x cases [mm]) with the prescribed values in place.
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& loads) const;

  /// Strain (eps_xx, eps_yy, gamma_xy) in `element` at natural coordinates (xi, eta) for the
  /// displacement vector `u` (DofCount() entries [mm]).
  Eigen::Vector3d StrainAt(int element, double xi, double eta,
                           const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// Stress (sigma_xx, sigma_yy, tau_xy) [MPa] at the same place.
  Eigen::Vector3d StressAt(int element, double xi, double eta,
                           const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// Position [mm] of natural coordinates (xi, eta) in `element`.
  Eigen::Vector2d PositionAt(int element, double xi, double eta) const;

  /// Adds the consistent nodal forces of a uniform traction `traction_mpa` (force per area of the
  /// side, global x/y components [MPa]) on `side` of `element` to the load vector `loads` (column).
  void AddEdgeTraction(int element, Side side, const Eigen::Vector2d& traction_mpa,
                       Eigen::Ref<Eigen::VectorXd> loads) const;

 private:
  Eigen::Matrix<double, 3, 18> StrainMatrix(int element, double xi, double eta) const;
  Eigen::Matrix<double, 18, 1> ElementDisplacements(int element,
                                                    const Eigen::Ref<const Eigen::VectorXd>& u) const;

  Mesh mesh_;
  PlaneStressMaterial material_;
  Eigen::Matrix3d elasticity_;           // plane-stress D [MPa]
  std::vector<int> free_dofs_;           // free index -> global dof
  std::vector<int> free_index_;          // global dof -> free index, or -1 when prescribed
  Eigen::VectorXd prescribed_values_;    // global vector, prescribed values else 0
  Eigen::VectorXd prescribed_reaction_;  // K_fp * u_p, per free dof
  // Held by pointer: Eigen solvers are not movable, the model is.
  std::unique_ptr<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>> solver_;
  long stiffness_non_zeros_ = 0;
};

}  // namespace graspbed::fea
