#include "sensor/fea/plane_stress.h"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace graspbed::fea {
namespace {

// 3-point Gauss-Legendre rule on [-1, 1]: exact for the biquadratic element's stiffness on
// parallelograms and enough for the 9-node element to stay free of spurious modes.
constexpr std::array<double, 3> kGaussPoints{-0.7745966692414834, 0.0, 0.7745966692414834};
constexpr std::array<double, 3> kGaussWeights{5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};

// 1D quadratic Lagrange polynomials on nodes -1, 0, 1 and their derivatives.
Eigen::Vector3d Lagrange(double s) { return {0.5 * s * (s - 1.0), 1.0 - s * s, 0.5 * s * (s + 1.0)}; }
Eigen::Vector3d LagrangeDerivative(double s) { return {s - 0.5, -2.0 * s, s + 0.5}; }

// Derivatives of the 9 shape functions with respect to (xi, eta): row 0 d/dxi, row 1 d/deta.
Eigen::Matrix<double, 2, 9> ShapeDerivatives(double xi, double eta) {
  const Eigen::Vector3d lx = Lagrange(xi), ly = Lagrange(eta);
  const Eigen::Vector3d dx = LagrangeDerivative(xi), dy = LagrangeDerivative(eta);
  Eigen::Matrix<double, 2, 9> derivatives;
  for (int b = 0; b < 3; ++b) {
    for (int a = 0; a < 3; ++a) {
      derivatives(0, 3 * b + a) = dx[a] * ly[b];
      derivatives(1, 3 * b + a) = lx[a] * dy[b];
    }
  }
  return derivatives;
}

// The three local nodes on each side, in order of increasing natural coordinate along the side.
std::array<int, 3> SideNodes(Side side) {
  switch (side) {
    case Side::kBottom:
      return {0, 1, 2};
    case Side::kRight:
      return {2, 5, 8};
    case Side::kTop:
      return {6, 7, 8};
    case Side::kLeft:
      return {0, 3, 6};
  }
  return {0, 1, 2};
}

}  // namespace

Eigen::Matrix<double, 9, 1> ShapeFunctions(double xi, double eta) {
  const Eigen::Vector3d lx = Lagrange(xi), ly = Lagrange(eta);
  Eigen::Matrix<double, 9, 1> shape;
  for (int b = 0; b < 3; ++b) {
    for (int a = 0; a < 3; ++a) shape[3 * b + a] = lx[a] * ly[b];
  }
  return shape;
}

PlaneStressModel::PlaneStressModel(Mesh mesh, PlaneStressMaterial material,
                                   std::vector<PrescribedDof> prescribed)
    : mesh_(std::move(mesh)), material_(material) {
  const double e = material_.youngs_modulus_mpa;
  const double nu = material_.poisson_ratio;
  if (!(e > 0.0) || !(nu > -1.0 && nu < 0.5) || !(material_.thickness_mm > 0.0)) {
    throw std::invalid_argument("PlaneStressModel: material E = " + std::to_string(e) +
                                " MPa, nu = " + std::to_string(nu) +
                                ", thickness = " + std::to_string(material_.thickness_mm) +
                                " mm: need E > 0, -1 < nu < 0.5, thickness > 0");
  }
  if (mesh_.elements.empty()) throw std::invalid_argument("PlaneStressModel: the mesh has no elements");
  elasticity_ << 1.0, nu, 0.0, nu, 1.0, 0.0, 0.0, 0.0, 0.5 * (1.0 - nu);
  elasticity_ *= e / (1.0 - nu * nu);

  const int dof_count = mesh_.DofCount();
  prescribed_values_ = Eigen::VectorXd::Zero(dof_count);
  std::vector<bool> is_prescribed(dof_count, false);
  for (const PrescribedDof& p : prescribed) {
    if (p.dof < 0 || p.dof >= dof_count) {
      throw std::invalid_argument("PlaneStressModel: prescribed dof " + std::to_string(p.dof) +
                                  " outside 0.." + std::to_string(dof_count - 1));
    }
    is_prescribed[p.dof] = true;
    prescribed_values_[p.dof] = p.value_mm;
  }
  free_index_.assign(dof_count, -1);
  for (int dof = 0; dof < dof_count; ++dof) {
    if (is_prescribed[dof]) continue;
    free_index_[dof] = static_cast<int>(free_dofs_.size());
    free_dofs_.push_back(dof);
  }
  const int free_count = FreeDofCount();
  prescribed_reaction_ = Eigen::VectorXd::Zero(free_count);

  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(mesh_.elements.size() * 18 * 18);
  for (int element = 0; element < static_cast<int>(mesh_.elements.size()); ++element) {
    Eigen::Matrix<double, 18, 18> k = Eigen::Matrix<double, 18, 18>::Zero();
    for (int gy = 0; gy < 3; ++gy) {
      for (int gx = 0; gx < 3; ++gx) {
        const double xi = kGaussPoints[gx], eta = kGaussPoints[gy];
        const Eigen::Matrix<double, 2, 9> dn = ShapeDerivatives(xi, eta);
        Eigen::Matrix2d jacobian = Eigen::Matrix2d::Zero();
        for (int n = 0; n < 9; ++n)
          jacobian += dn.col(n) * mesh_.nodes[mesh_.elements[element][n]].transpose();
        const double det = jacobian.determinant();
        if (!(det > 0.0)) {
          throw std::invalid_argument("PlaneStressModel: element " + std::to_string(element) +
                                      " is inverted or degenerate (Jacobian determinant " +
                                      std::to_string(det) + ")");
        }
        const Eigen::Matrix<double, 3, 18> b = StrainMatrix(element, xi, eta);
        k += b.transpose() * elasticity_ * b *
             (det * kGaussWeights[gx] * kGaussWeights[gy] * material_.thickness_mm);
      }
    }
    std::array<int, 18> dofs{};
    for (int n = 0; n < 9; ++n) {
      dofs[2 * n] = 2 * mesh_.elements[element][n];
      dofs[2 * n + 1] = 2 * mesh_.elements[element][n] + 1;
    }
    for (int r = 0; r < 18; ++r) {
      const int row = free_index_[dofs[r]];
      if (row < 0) continue;
      for (int c = 0; c < 18; ++c) {
        const int column = free_index_[dofs[c]];
        if (column >= 0) {
          triplets.emplace_back(row, column, k(r, c));
        } else {
          prescribed_reaction_[row] += k(r, c) * prescribed_values_[dofs[c]];
        }
      }
    }
  }
  Eigen::SparseMatrix<double> stiffness(free_count, free_count);
  stiffness.setFromTriplets(triplets.begin(), triplets.end());
  stiffness_non_zeros_ = stiffness.nonZeros();
  solver_ = std::make_unique<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>>(stiffness);
  if (solver_->info() != Eigen::Success) {
    throw std::runtime_error("PlaneStressModel: the stiffness matrix could not be factorised (" +
                             std::to_string(free_count) + " free dofs); the part is not fully constrained");
  }
  // LDLT of a singular matrix can "succeed" with a zero pivot: check the pivots.
  const Eigen::VectorXd pivots = solver_->vectorD();
  const double largest = pivots.cwiseAbs().maxCoeff();
  if (!(pivots.minCoeff() > 1e-12 * largest)) {
    throw std::runtime_error("PlaneStressModel: the stiffness matrix is singular (" +
                             std::to_string(free_count) + " free dofs); the part is not fully constrained");
  }
}

Eigen::Matrix<double, 3, 18> PlaneStressModel::StrainMatrix(int element, double xi, double eta) const {
  const Eigen::Matrix<double, 2, 9> dn = ShapeDerivatives(xi, eta);
  Eigen::Matrix2d jacobian = Eigen::Matrix2d::Zero();
  for (int n = 0; n < 9; ++n) jacobian += dn.col(n) * mesh_.nodes[mesh_.elements[element][n]].transpose();
  // Rows of dn_dx: dN/dx, dN/dy.
  const Eigen::Matrix<double, 2, 9> dn_dx = jacobian.inverse() * dn;
  Eigen::Matrix<double, 3, 18> b = Eigen::Matrix<double, 3, 18>::Zero();
  for (int n = 0; n < 9; ++n) {
    b(0, 2 * n) = dn_dx(0, n);
    b(1, 2 * n + 1) = dn_dx(1, n);
    b(2, 2 * n) = dn_dx(1, n);
    b(2, 2 * n + 1) = dn_dx(0, n);
  }
  return b;
}

Eigen::Matrix<double, 18, 1> PlaneStressModel::ElementDisplacements(
    int element, const Eigen::Ref<const Eigen::VectorXd>& u) const {
  Eigen::Matrix<double, 18, 1> ue;
  for (int n = 0; n < 9; ++n) {
    ue[2 * n] = u[2 * mesh_.elements[element][n]];
    ue[2 * n + 1] = u[2 * mesh_.elements[element][n] + 1];
  }
  return ue;
}

Eigen::MatrixXd PlaneStressModel::Solve(const Eigen::MatrixXd& loads) const {
  if (loads.rows() != DofCount()) {
    throw std::invalid_argument("PlaneStressModel::Solve: load matrix has " + std::to_string(loads.rows()) +
                                " rows, expected " + std::to_string(DofCount()));
  }
  const int free_count = FreeDofCount();
  Eigen::MatrixXd rhs(free_count, loads.cols());
  for (int i = 0; i < free_count; ++i) rhs.row(i) = loads.row(free_dofs_[i]);
  rhs.colwise() -= prescribed_reaction_;
  const Eigen::MatrixXd free_u = solver_->solve(rhs);
  Eigen::MatrixXd u = prescribed_values_.replicate(1, loads.cols());
  for (int i = 0; i < free_count; ++i) u.row(free_dofs_[i]) = free_u.row(i);
  return u;
}

Eigen::Vector3d PlaneStressModel::StrainAt(int element, double xi, double eta,
                                           const Eigen::Ref<const Eigen::VectorXd>& u) const {
  return StrainMatrix(element, xi, eta) * ElementDisplacements(element, u);
}

Eigen::Vector3d PlaneStressModel::StressAt(int element, double xi, double eta,
                                           const Eigen::Ref<const Eigen::VectorXd>& u) const {
  return elasticity_ * StrainAt(element, xi, eta, u);
}

Eigen::Vector2d PlaneStressModel::PositionAt(int element, double xi, double eta) const {
  const Eigen::Matrix<double, 9, 1> shape = ShapeFunctions(xi, eta);
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  for (int n = 0; n < 9; ++n) position += shape[n] * mesh_.nodes[mesh_.elements[element][n]];
  return position;
}

void PlaneStressModel::AddEdgeTraction(int element, Side side, const Eigen::Vector2d& traction_mpa,
                                       Eigen::Ref<Eigen::VectorXd> loads) const {
  const std::array<int, 3> local = SideNodes(side);
  std::array<Eigen::Vector2d, 3> points;
  for (int k = 0; k < 3; ++k) points[k] = mesh_.nodes[mesh_.elements[element][local[k]]];
  // f_k = t * thickness * integral of L_k(s) |dx/ds| ds along the side.
  for (int g = 0; g < 3; ++g) {
    const double s = kGaussPoints[g];
    const Eigen::Vector3d shape = Lagrange(s);
    const Eigen::Vector3d d_shape = LagrangeDerivative(s);
    Eigen::Vector2d tangent = Eigen::Vector2d::Zero();
    for (int k = 0; k < 3; ++k) tangent += d_shape[k] * points[k];
    const double scale = tangent.norm() * kGaussWeights[g] * material_.thickness_mm;
    for (int k = 0; k < 3; ++k) {
      const int node = mesh_.elements[element][local[k]];
      loads[2 * node] += shape[k] * traction_mpa.x() * scale;
      loads[2 * node + 1] += shape[k] * traction_mpa.y() * scale;
    }
  }
}

}  // namespace graspbed::fea
