// The sensing unit's analysis: symmetry of the normal-load profile, antisymmetry of the shear
// profile, superposition, linearity, R1/R2 convention, exact scalings, mesh convergence.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sensor/fea/fea_config.h"
#include "sensor/fea/unit_analysis.h"

namespace graspbed::fea {
namespace {

constexpr double kSymmetryTol = 1e-9;       // relative to the peak strain: mirror-symmetric mesh
constexpr double kSuperpositionTol = 0.01;  // 1 %, the bound docs/fea.md states
constexpr double kLinearityMinR2 = 0.9999;
constexpr double kScalingTol = 1e-9;      // relative; strain scales exactly as 1/E and 1/width
constexpr double kConvergenceTol = 0.01;  // change of k_n, k_t from h = 0.05 to 0.025 mm, per peak strain
constexpr double kForceTolN = 1e-9;

class UnitAnalysisTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { results_ = new FeaResults(RunUnitAnalysis(FeaConfig{})); }
  static void TearDownTestSuite() { delete results_; }
  static const FeaResults& results() { return *results_; }

 private:
  static FeaResults* results_;
};
FeaResults* UnitAnalysisTest::results_ = nullptr;

double MaxAbs(const std::vector<double>& values) {
  double largest = 0.0;
  for (double v : values) largest = std::max(largest, std::abs(v));
  return largest;
}

TEST_F(UnitAnalysisTest, ProfileCoversTheFreeSpanAtTheNodes) {
  const StrainProfile& p = results().profile;
  const GeometryConfig g;
  ASSERT_FALSE(p.x_mm.empty());
  EXPECT_NEAR(p.x_mm.front(), -0.5 * g.SpanMm(), 1e-12);
  EXPECT_NEAR(p.x_mm.back(), 0.5 * g.SpanMm(), 1e-12);
  // 9-node elements of 0.05 mm: a node every 0.025 mm.
  EXPECT_EQ(p.x_mm.size(), static_cast<size_t>(std::lround(g.SpanMm() / 0.025)) + 1);
  EXPECT_TRUE(std::is_sorted(p.x_mm.begin(), p.x_mm.end()));
}

TEST_F(UnitAnalysisTest, NormalProfileIsSymmetricAndShearProfileAntisymmetric) {
  const StrainProfile& p = results().profile;
  const size_t n = p.x_mm.size();
  const double normal_peak = MaxAbs(p.normal);
  const double shear_peak = MaxAbs(p.shear);
  ASSERT_GT(normal_peak, 0.0);
  ASSERT_GT(shear_peak, 0.0);
  for (size_t i = 0; i < n; ++i) {
    const size_t mirror = n - 1 - i;
    ASSERT_NEAR(p.x_mm[i], -p.x_mm[mirror], 1e-12);
    EXPECT_NEAR(p.normal[i], p.normal[mirror], kSymmetryTol * normal_peak) << "x = " << p.x_mm[i];
    EXPECT_NEAR(p.shear[i], -p.shear[mirror], kSymmetryTol * shear_peak) << "x = " << p.x_mm[i];
  }
  // Hence under Fn alone R1 and R2 read the same, and under Ft alone opposite values (paper eq. 3).
  EXPECT_LT(results().normal_to_shear_cross_talk, kSymmetryTol);
  EXPECT_LT(results().shear_to_normal_cross_talk, kSymmetryTol);
}

TEST_F(UnitAnalysisTest, CombinedLoadEqualsSumOfSingleLoads) {
  const StrainProfile& p = results().profile;
  const double peak = MaxAbs(p.both);
  for (size_t i = 0; i < p.x_mm.size(); ++i) {
    EXPECT_NEAR(p.both[i], p.normal[i] + p.shear[i], kSuperpositionTol * peak) << "x = " << p.x_mm[i];
    EXPECT_DOUBLE_EQ(p.sum[i], p.normal[i] + p.shear[i]);
  }
  EXPECT_LT(results().superposition_error, kSuperpositionTol);
}

TEST_F(UnitAnalysisTest, SweepsAreLinearAndStartAtZero) {
  const FeaResults& r = results();
  EXPECT_GT(r.normal_fit.r_squared, kLinearityMinR2);
  EXPECT_GT(r.shear_fit.r_squared, kLinearityMinR2);
  EXPECT_EQ(r.normal_sweep.force_n.size(), 11u);
  EXPECT_NEAR(r.normal_sweep.force_n.back(), 10.0, kForceTolN);
  EXPECT_EQ(r.normal_sweep.eps1.front(), 0.0);
  EXPECT_EQ(r.shear_sweep.eps2.front(), 0.0);
  // Doubling the force doubles the strain.
  EXPECT_NEAR(r.normal_sweep.eps1[10], 2.0 * r.normal_sweep.eps1[5], 1e-12);
  EXPECT_NEAR(r.sensitivities.kn_per_n * 10.0, 0.5 * (r.normal_sweep.eps1[10] + r.normal_sweep.eps2[10]),
              1e-12);
}

TEST_F(UnitAnalysisTest, SignConventionsMatchThePaper) {
  const FeaResults& r = results();
  // Pressing the mesa stretches the underside under the mesa (sagging) and compresses it at the braces.
  const StrainProfile& p = r.profile;
  const size_t centre = p.x_mm.size() / 2;
  EXPECT_NEAR(p.x_mm[centre], 0.0, 1e-12);
  EXPECT_GT(p.normal[centre], 0.0);
  EXPECT_LT(p.normal.front(), 0.0);
  EXPECT_GT(r.sensitivities.kn_per_n, 0.0);
  // R1 sits where +Ft adds tension: eps1 = eps_n + eps_t with eps_t > 0.
  EXPECT_GT(r.shear_sweep.eps1.back(), 0.0);
  EXPECT_LT(r.shear_sweep.eps2.back(), 0.0);
  EXPECT_GT(r.sensitivities.kt_per_n, 0.0);
  EXPECT_NEAR(r.kn_ratio, r.sensitivities.kn_per_n / 5.5e-4, 1e-15);
}

TEST(UnitModelTest, LoadVectorHasTheRequestedResultant) {
  const UnitModel unit{FeaConfig{}};
  const Eigen::VectorXd loads = unit.LoadVector(7.0, -3.0);
  double fx = 0.0, fy = 0.0;
  for (int node = 0; node < loads.size() / 2; ++node) {
    fx += loads[2 * node];
    fy += loads[2 * node + 1];
  }
  EXPECT_NEAR(fx, -3.0, kForceTolN);
  EXPECT_NEAR(fy, -7.0, kForceTolN);
}

TEST(UnitModelTest, DefaultMeshPutsFourElementsThroughTheBeam) {
  const UnitModel unit{FeaConfig{}};
  const Mesh& mesh = unit.model().mesh();
  int rows_in_beam = 0;
  for (int j = 0; j < mesh.CellsY(); ++j) {
    const double y = 0.5 * (mesh.y_lines[j] + mesh.y_lines[j + 1]);
    if (y > 3.0 && y < 3.2) ++rows_in_beam;
  }
  EXPECT_EQ(rows_in_beam, 4);
  EXPECT_NEAR(mesh.y_lines[unit.UndersideRow()], 3.0, 1e-12);
}

// Linear elasticity: strains scale exactly as 1/E and, in plane stress, as 1/width.
TEST(UnitModelTest, SensitivitiesScaleExactlyWithStiffnessAndWidth) {
  FeaConfig config;
  config.mesh.element_size_mm = 0.1;  // the scaling is exact at any mesh; keep it quick
  const Sensitivities base = ComputeSensitivities(config);
  FeaConfig stiffer = config;
  stiffer.material.youngs_modulus_gpa *= 2.0;
  const Sensitivities stiff = ComputeSensitivities(stiffer);
  EXPECT_NEAR(stiff.kn_per_n, 0.5 * base.kn_per_n, kScalingTol * base.kn_per_n);
  EXPECT_NEAR(stiff.kt_per_n, 0.5 * base.kt_per_n, kScalingTol * base.kt_per_n);
  FeaConfig narrower = config;
  narrower.geometry.width_mm = 1.0;
  const Sensitivities narrow = ComputeSensitivities(narrower);
  EXPECT_NEAR(narrow.kn_per_n, 2.0 * base.kn_per_n, kScalingTol * base.kn_per_n);
  EXPECT_NEAR(narrow.kt_per_n, 2.0 * base.kt_per_n, kScalingTol * base.kt_per_n);
  // A thicker beam is stiffer in bending: lower normal sensitivity.
  FeaConfig thicker = config;
  thicker.geometry.beam_thickness_mm = 0.3;
  EXPECT_LT(ComputeSensitivities(thicker).kn_per_n, base.kn_per_n);
}

// k_t is a small difference of large strains (the shear profile changes sign inside each resistor),
// so its relative mesh error is larger than k_n's; both are judged against the strain scale of the
// unit, the peak underside strain per newton.
TEST(UnitModelTest, SensitivitiesConvergeUnderMeshRefinement) {
  std::vector<FeaResults> runs;
  for (double size : {0.1, 0.05, 0.025}) {
    FeaConfig config;
    config.mesh.element_size_mm = size;
    runs.push_back(RunUnitAnalysis(config));
  }
  const double scale = runs[2].peak_normal_strain / 10.0;  // [1/N]
  std::printf("k_n: %.6e %.6e %.6e   k_t: %.6e %.6e %.6e  (h = 0.1, 0.05, 0.025 mm)\n",
              runs[0].sensitivities.kn_per_n, runs[1].sensitivities.kn_per_n, runs[2].sensitivities.kn_per_n,
              runs[0].sensitivities.kt_per_n, runs[1].sensitivities.kt_per_n, runs[2].sensitivities.kt_per_n);
  for (auto k : {&Sensitivities::kn_per_n, &Sensitivities::kt_per_n}) {
    const double coarse_change = std::abs(runs[1].sensitivities.*k - runs[0].sensitivities.*k);
    const double fine_change = std::abs(runs[2].sensitivities.*k - runs[1].sensitivities.*k);
    EXPECT_LT(fine_change, coarse_change);  // converging
    EXPECT_LT(fine_change, kConvergenceTol * scale);
  }
}

TEST(FitLineTest, RecoversSlopeInterceptAndRSquared) {
  const LineFit exact = FitLine({0, 1, 2, 3}, {1, 3, 5, 7});
  EXPECT_NEAR(exact.slope, 2.0, 1e-12);
  EXPECT_NEAR(exact.intercept, 1.0, 1e-12);
  EXPECT_NEAR(exact.r_squared, 1.0, 1e-12);
  const LineFit noisy = FitLine({0, 1, 2, 3}, {0, 1.5, 1.5, 3});
  EXPECT_LT(noisy.r_squared, 0.95);
  EXPECT_THROW(FitLine({1.0}, {1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace graspbed::fea
