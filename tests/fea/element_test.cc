// The 9-node plane-stress element: shape functions, rigid-body motion, patch tests on a distorted
// mesh (constant strain reproduced exactly), consistent edge loads, and refused inputs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "sensor/fea/mesh.h"
#include "sensor/fea/plane_stress.h"
#include "tests/support/error_of.h"

namespace graspbed::fea {
namespace {

using graspbed::test_support::ErrorOf;
using ::testing::HasSubstr;

constexpr double kExactTol = 1e-10;  // "exact" up to rounding, for strains of order 1e-3
constexpr double kYoungsMpa = 197000.0;
constexpr double kPoisson = 0.3;
constexpr double kThicknessMm = 2.0;

// A 2 x 2 patch of 9-node elements over [0, 2] x [0, 1.5] whose interior corner node is moved off
// the grid and whose internal edges are curved slightly (mid-edge nodes moved), so no element is a
// rectangle or even a parallelogram.
Mesh DistortedPatch() {
  // 5 x 5 node grid, tensor order.
  const double xs[5] = {0.0, 0.5, 1.0, 1.5, 2.0};
  const double ys[5] = {0.0, 0.375, 0.75, 1.125, 1.5};
  Mesh mesh;
  for (int j = 0; j < 5; ++j) {
    for (int i = 0; i < 5; ++i) mesh.nodes.emplace_back(xs[i], ys[j]);
  }
  auto id = [](int i, int j) { return 5 * j + i; };
  mesh.nodes[id(2, 2)] += Eigen::Vector2d(0.17, -0.11);  // interior corner
  mesh.nodes[id(1, 2)] += Eigen::Vector2d(0.05, 0.04);   // mid-edge nodes of interior edges
  mesh.nodes[id(2, 1)] += Eigen::Vector2d(-0.03, 0.02);
  mesh.nodes[id(3, 2)] += Eigen::Vector2d(0.02, -0.06);
  mesh.nodes[id(2, 3)] += Eigen::Vector2d(0.06, 0.01);
  // Centre nodes moved too (they need not sit at the element centre).
  mesh.nodes[id(1, 1)] += Eigen::Vector2d(0.04, 0.03);
  mesh.nodes[id(3, 3)] += Eigen::Vector2d(-0.05, 0.02);
  for (int ej = 0; ej < 2; ++ej) {
    for (int ei = 0; ei < 2; ++ei) {
      std::array<int, 9> element{};
      for (int b = 0; b < 3; ++b) {
        for (int a = 0; a < 3; ++a) element[3 * b + a] = id(2 * ei + a, 2 * ej + b);
      }
      mesh.elements.push_back(element);
    }
  }
  return mesh;
}

bool OnBoundary(const Eigen::Vector2d& p) {
  return p.x() < 1e-12 || p.x() > 2.0 - 1e-12 || p.y() < 1e-12 || p.y() > 1.5 - 1e-12;
}

TEST(ElementTest, ShapeFunctionsArePartitionOfUnityAndInterpolating) {
  for (double xi : {-1.0, -0.3, 0.0, 0.71, 1.0}) {
    for (double eta : {-1.0, 0.2, 1.0}) EXPECT_NEAR(ShapeFunctions(xi, eta).sum(), 1.0, kExactTol);
  }
  const double nodes[3] = {-1.0, 0.0, 1.0};
  for (int b = 0; b < 3; ++b) {
    for (int a = 0; a < 3; ++a) {
      const auto shape = ShapeFunctions(nodes[a], nodes[b]);
      for (int k = 0; k < 9; ++k) EXPECT_NEAR(shape[k], k == 3 * b + a ? 1.0 : 0.0, kExactTol);
    }
  }
}

// Displacement patch test: prescribe a linear field on the boundary; the interior nodes must follow
// it and the strain must be the field's constant strain at every point of every element.
TEST(ElementTest, DisplacementPatchTestReproducesConstantStrainExactly) {
  const double a0 = 1e-4, ax = 2e-3, ay = -7e-4, b0 = -3e-4, bx = 5e-4, by = 1.2e-3;
  auto field = [&](const Eigen::Vector2d& p) {
    return Eigen::Vector2d(a0 + ax * p.x() + ay * p.y(), b0 + bx * p.x() + by * p.y());
  };
  const Mesh mesh = DistortedPatch();
  std::vector<PrescribedDof> prescribed;
  for (int node = 0; node < static_cast<int>(mesh.nodes.size()); ++node) {
    if (!OnBoundary(mesh.nodes[node])) continue;
    const Eigen::Vector2d u = field(mesh.nodes[node]);
    prescribed.push_back({2 * node, u.x()});
    prescribed.push_back({2 * node + 1, u.y()});
  }
  const PlaneStressModel model(mesh, {kYoungsMpa, kPoisson, kThicknessMm}, prescribed);
  ASSERT_GT(model.FreeDofCount(), 0);
  const Eigen::MatrixXd u = model.Solve(Eigen::MatrixXd::Zero(model.DofCount(), 1));
  for (int node = 0; node < static_cast<int>(mesh.nodes.size()); ++node) {
    const Eigen::Vector2d expected = field(mesh.nodes[node]);
    EXPECT_NEAR(u(2 * node, 0), expected.x(), kExactTol) << "node " << node;
    EXPECT_NEAR(u(2 * node + 1, 0), expected.y(), kExactTol) << "node " << node;
  }
  for (int element = 0; element < 4; ++element) {
    for (double xi : {-1.0, -0.5, 0.3, 1.0}) {
      for (double eta : {-1.0, 0.0, 0.8}) {
        const Eigen::Vector3d strain = model.StrainAt(element, xi, eta, u.col(0));
        EXPECT_NEAR(strain[0], ax, kExactTol);
        EXPECT_NEAR(strain[1], by, kExactTol);
        EXPECT_NEAR(strain[2], ay + bx, kExactTol);
      }
    }
  }
}

// Force patch test: uniform tension applied as an edge traction on the right side of the distorted
// patch, minimal supports on the left; the stress must be uniform sigma_xx = traction everywhere.
TEST(ElementTest, TractionPatchTestGivesUniformStress) {
  constexpr double kTractionMpa = 50.0;
  const Mesh mesh = DistortedPatch();
  std::vector<PrescribedDof> supports;
  for (int node = 0; node < static_cast<int>(mesh.nodes.size()); ++node) {
    const Eigen::Vector2d& p = mesh.nodes[node];
    if (p.x() < 1e-12) supports.push_back({2 * node, 0.0});                       // u_x = 0 on the left
    if (p.x() < 1e-12 && p.y() < 1e-12) supports.push_back({2 * node + 1, 0.0});  // and one u_y
  }
  const PlaneStressModel model(mesh, {kYoungsMpa, kPoisson, kThicknessMm}, supports);
  Eigen::VectorXd loads = Eigen::VectorXd::Zero(model.DofCount());
  model.AddEdgeTraction(1, Side::kRight, {kTractionMpa, 0.0}, loads);  // elements 1 and 3 are on x = 2
  model.AddEdgeTraction(3, Side::kRight, {kTractionMpa, 0.0}, loads);
  EXPECT_NEAR(loads.sum(), kTractionMpa * 1.5 * kThicknessMm, 1e-9);  // resultant = traction x area
  const Eigen::MatrixXd u = model.Solve(loads);
  constexpr double kStressTolMpa = 1e-8;
  for (int element = 0; element < 4; ++element) {
    for (double xi : {-1.0, 0.0, 0.6}) {
      for (double eta : {-0.7, 1.0}) {
        const Eigen::Vector3d stress = model.StressAt(element, xi, eta, u.col(0));
        EXPECT_NEAR(stress[0], kTractionMpa, kStressTolMpa);
        EXPECT_NEAR(stress[1], 0.0, kStressTolMpa);
        EXPECT_NEAR(stress[2], 0.0, kStressTolMpa);
      }
    }
  }
  // Lateral contraction -nu * eps_xx: plane stress, not plane strain.
  const Eigen::Vector3d strain = model.StrainAt(0, 0.0, 0.0, u.col(0));
  EXPECT_NEAR(strain[1], -kPoisson * strain[0], kExactTol);
}

TEST(ElementTest, RigidBodyMotionGivesNoStrain) {
  const Mesh mesh = MeshRectangles({{0.0, 1.0, 0.0, 0.2}}, 0.1);
  // A small rotation theta about the origin plus a translation, prescribed everywhere on the left
  // edge; nothing loads the beam, so the whole beam follows the rigid motion with zero strain.
  const double theta = 1e-3;
  auto rigid = [&](const Eigen::Vector2d& p) {
    return Eigen::Vector2d(0.01 - theta * p.y(), -0.02 + theta * p.x());
  };
  std::vector<PrescribedDof> prescribed;
  for (int node = 0; node < static_cast<int>(mesh.nodes.size()); ++node) {
    if (mesh.nodes[node].x() > 1e-12) continue;
    const Eigen::Vector2d u = rigid(mesh.nodes[node]);
    prescribed.push_back({2 * node, u.x()});
    prescribed.push_back({2 * node + 1, u.y()});
  }
  const PlaneStressModel model(mesh, {kYoungsMpa, kPoisson, kThicknessMm}, prescribed);
  const Eigen::MatrixXd u = model.Solve(Eigen::MatrixXd::Zero(model.DofCount(), 1));
  for (int node = 0; node < static_cast<int>(mesh.nodes.size()); ++node) {
    const Eigen::Vector2d expected = rigid(mesh.nodes[node]);
    EXPECT_NEAR(u(2 * node, 0), expected.x(), kExactTol);
    EXPECT_NEAR(u(2 * node + 1, 0), expected.y(), kExactTol);
  }
  EXPECT_LT(model.StrainAt(3, 0.2, -1.0, u.col(0)).cwiseAbs().maxCoeff(), kExactTol);
}

TEST(ElementTest, MeshRectanglesPutsEdgesOnGeometryAndExtraLines) {
  const Mesh mesh = MeshRectangles({{-1.5, 1.5, 3.0, 3.2}, {-1.5, -1.0, 0.0, 3.0}}, 0.05, {0.0, 0.75, -0.33});
  EXPECT_EQ(mesh.CellsY(), 60 + 4);
  for (double line : {-1.0, 0.0, 0.75, -0.33}) {
    EXPECT_TRUE(std::any_of(mesh.x_lines.begin(), mesh.x_lines.end(), [&](double x) {
      return std::abs(x - line) < 1e-12;
    })) << line;
  }
  // The void under the beam right of the brace holds no elements.
  EXPECT_EQ(mesh.CellElement(mesh.CellsX() - 1, 0), -1);
  EXPECT_GE(mesh.CellElement(0, 0), 0);
  for (size_t k = 1; k < mesh.x_lines.size(); ++k)
    EXPECT_LE(mesh.x_lines[k] - mesh.x_lines[k - 1], 0.05 + 1e-12);
}

TEST(ElementTest, RefusesUnconstrainedPartsAndBadInput) {
  const Mesh mesh = MeshRectangles({{0.0, 1.0, 0.0, 0.2}}, 0.1);
  EXPECT_THAT(ErrorOf([&] {
                PlaneStressModel(mesh, {kYoungsMpa, kPoisson, kThicknessMm}, {});
              }),
              HasSubstr("not fully constrained"));
  EXPECT_THAT(ErrorOf([&] {
                PlaneStressModel(mesh, {kYoungsMpa, 0.5, kThicknessMm}, {{0, 0.0}});
              }),
              HasSubstr("nu = 0.5"));
  EXPECT_THAT(ErrorOf([&] {
                PlaneStressModel(mesh, {kYoungsMpa, kPoisson, kThicknessMm}, {{-1, 0.0}});
              }),
              HasSubstr("prescribed dof -1"));
  EXPECT_THAT(ErrorOf([&] {
                MeshRectangles({{0.0, 0.0, 0.0, 0.2}}, 0.1);
              }),
              HasSubstr("degenerate rectangle"));
  EXPECT_THAT(ErrorOf([&] { MeshRectangles({{0.0, 1.0, 0.0, 0.2}}, -0.1); }), HasSubstr("must be > 0"));
  Mesh inverted = mesh;
  std::swap(inverted.elements[0][0], inverted.elements[0][2]);
  std::swap(inverted.elements[0][3], inverted.elements[0][5]);
  std::swap(inverted.elements[0][6], inverted.elements[0][8]);
  EXPECT_THAT(ErrorOf([&] {
                PlaneStressModel(inverted, {kYoungsMpa, kPoisson, kThicknessMm}, {{0, 0.0}});
              }),
              HasSubstr("inverted or degenerate"));
}

}  // namespace
}  // namespace graspbed::fea
