// Validation against beam theory: a plain clamped-clamped beam (no braces, no mesa) under a central
// point load, compared with the Euler-Bernoulli surface strain, and the error under mesh refinement.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "sensor/fea/mesh.h"
#include "sensor/fea/plane_stress.h"
#include "sensor/fea/unit_analysis.h"

namespace graspbed::fea {
namespace {

constexpr double kLengthMm = 6.0;
constexpr double kThicknessMm = 0.2;
constexpr double kWidthMm = 2.0;
constexpr double kYoungsMpa = 197000.0;
constexpr double kLoadN = 1.0;
// Stay this many beam thicknesses away from the load and the clamps (local 2D effects decay there).
constexpr double kKeepAwayThicknesses = 4.0;
// Compare pointwise where the beam-theory strain is at least this fraction of its peak (the strain
// crosses zero at the quarter points, where a relative error means nothing).
constexpr double kMinStrainFraction = 0.25;
constexpr double kBeamTheoryTol = 0.02;

struct BeamErrors {
  double max_relative = 0.0;  // pointwise, where |eps_eb| >= kMinStrainFraction * peak
  double max_of_peak = 0.0;   // max |eps_fe - eps_eb| / peak eps_eb, away from load and clamps
  int compared_points = 0;
};

// Clamped-clamped Euler-Bernoulli beam with a central load P: M(x) = P (4x - L) / 8 for x <= L/2
// (sagging positive), bottom-fibre strain = M c / (E I) = 6 M / (E w t^2).
double EulerBernoulliBottomStrain(double x) {
  const double xs = std::min(x, kLengthMm - x);
  const double moment = kLoadN * (4.0 * xs - kLengthMm) / 8.0;
  return 6.0 * moment / (kYoungsMpa * kWidthMm * kThicknessMm * kThicknessMm);
}

BeamErrors SolveBeam(double element_size_mm) {
  Mesh mesh = MeshRectangles({{0.0, kLengthMm, 0.0, kThicknessMm}}, element_size_mm, {0.5 * kLengthMm});
  std::vector<PrescribedDof> clamps;
  int load_node = -1;
  for (int node = 0; node < static_cast<int>(mesh.nodes.size()); ++node) {
    const Eigen::Vector2d& p = mesh.nodes[node];
    if (p.x() < 1e-9 || p.x() > kLengthMm - 1e-9) {
      clamps.push_back({2 * node, 0.0});
      clamps.push_back({2 * node + 1, 0.0});
    }
    if (std::abs(p.x() - 0.5 * kLengthMm) < 1e-9 && std::abs(p.y() - kThicknessMm) < 1e-9) load_node = node;
  }
  EXPECT_GE(load_node, 0);
  const PlaneStressModel model(std::move(mesh), {kYoungsMpa, 0.3, kWidthMm}, std::move(clamps));
  Eigen::MatrixXd loads = Eigen::MatrixXd::Zero(model.DofCount(), 1);
  loads(2 * load_node + 1, 0) = -kLoadN;
  const Eigen::MatrixXd u = model.Solve(loads);
  const StrainLine line = BottomSurfaceStrain(model, u.col(0), 0);

  const double peak = std::abs(EulerBernoulliBottomStrain(0.5 * kLengthMm));
  const double keep_away = kKeepAwayThicknesses * kThicknessMm;
  BeamErrors errors;
  for (size_t i = 0; i < line.x_mm.size(); ++i) {
    const double x = line.x_mm[i];
    if (x < keep_away || x > kLengthMm - keep_away || std::abs(x - 0.5 * kLengthMm) < keep_away) continue;
    const double expected = EulerBernoulliBottomStrain(x);
    const double difference = std::abs(line.eps[i] - expected);
    errors.max_of_peak = std::max(errors.max_of_peak, difference / peak);
    if (std::abs(expected) >= kMinStrainFraction * peak) {
      errors.max_relative = std::max(errors.max_relative, difference / std::abs(expected));
      ++errors.compared_points;
    }
  }
  return errors;
}

TEST(BeamTheoryTest, ClampedBeamMatchesEulerBernoulliAwayFromLoadAndClamps) {
  const BeamErrors errors = SolveBeam(0.05);
  EXPECT_GT(errors.compared_points, 20);
  EXPECT_LT(errors.max_relative, kBeamTheoryTol);
  EXPECT_LT(errors.max_of_peak, kBeamTheoryTol);
  std::printf("h = 0.05 mm: max relative error %.4f, max error / peak %.4f over %d points\n",
              errors.max_relative, errors.max_of_peak, errors.compared_points);
}

TEST(BeamTheoryTest, ErrorFallsUnderMeshRefinement) {
  std::vector<double> errors;
  for (double size : {0.2, 0.1, 0.05, 0.025}) {
    const BeamErrors e = SolveBeam(size);
    std::printf("h = %.3f mm: max relative error %.5f, max error / peak %.5f\n", size, e.max_relative,
                e.max_of_peak);
    errors.push_back(e.max_of_peak);
  }
  for (size_t k = 1; k < errors.size(); ++k) EXPECT_LT(errors[k], errors[k - 1]) << "refinement step " << k;
}

}  // namespace
}  // namespace graspbed::fea
