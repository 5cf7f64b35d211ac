// The unit's sensitivities k_n and k_t from the plane-stress FEA, checked against an independent
// model of the same frame: a 2D frame of beam elements (Timoshenko, on the members' centroid axes)
// for the two braces and the beam, the mesa a rigid block on the beam centre that carries the load,
// the shear's lever arm (mesa height + half the beam) included. Nothing of sensor/fea/ is used but
// the config's numbers, so a wrong width, modulus, lever arm, span or R1/R2 convention in the FEA
// shows up here. docs/fea.md quotes the FEA's figures; the test pins them as well.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "sensor/fea/fea_config.h"
#include "sensor/fea/unit_analysis.h"

namespace graspbed::fea {
namespace {

// The FEA's sensitivities at the shipped config, as docs/fea.md gives them (3 significant digits).
constexpr double kDocumentedKnPerN = 3.36e-5;
constexpr double kDocumentedKtPerN = 6.31e-6;
constexpr double kDocumentedRounding = 0.005;  // half a unit of the third digit, relative

/// Beam model of the inverted U. Members lie on their centroid axes (the textbook frame
/// idealisation: no rigid zones at the beam-brace joints); the mesa is rigid (0.7 mm deep over the
/// beam against its 0.2 mm: 43x the bending stiffness). Units: mm, N, N/mm^2.
class FrameModel {
 public:
  /// `lever_arm_scale` multiplies the shear's lever arm above the beam axis (1 = the real frame).
  explicit FrameModel(const FeaConfig& config, double lever_arm_scale = 1.0) : config_(config) {
    const GeometryConfig& g = config.geometry;
    const double e = config.material.youngs_modulus_gpa * 1e3;
    shear_modulus_ = e / (2.0 * (1.0 + config.material.poisson_ratio));
    youngs_ = e;
    beam_axis_y_ = g.brace_height_mm + 0.5 * g.beam_thickness_mm;
    const double brace_x = 0.5 * (g.beam_length_mm - g.brace_thickness_mm);
    const double half_mesa = 0.5 * g.mesa_length_mm;
    for (int side : {-1, 1}) {
      AddMember({side * brace_x, 0.0}, {side * brace_x, beam_axis_y_}, g.brace_thickness_mm, false);
    }
    // Beam nodes: braces, resistor ends, mesa edges and centre, so strain is linear within a member.
    std::vector<double> xs = {-brace_x,
                              brace_x,
                              -half_mesa,
                              half_mesa,
                              0.0,
                              config.gauge.r1.start_mm,
                              config.gauge.r1.end_mm,
                              config.gauge.r2.start_mm,
                              config.gauge.r2.end_mm};
    std::sort(xs.begin(), xs.end());
    xs.erase(std::unique(xs.begin(), xs.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }),
             xs.end());
    for (size_t i = 0; i + 1 < xs.size(); ++i) {
      const bool under_mesa = std::abs(0.5 * (xs[i] + xs[i + 1])) < half_mesa;
      AddMember({xs[i], beam_axis_y_}, {xs[i + 1], beam_axis_y_}, g.beam_thickness_mm, under_mesa);
    }
    centre_node_ = Node({0.0, beam_axis_y_});
    lever_arm_mm_ = lever_arm_scale * (g.mesa_height_mm + 0.5 * g.beam_thickness_mm);
  }

  /// Mean underside strain eps_xx over R1 and R2 [-] for Fn [N] down and Ft [N] along +x on the mesa.
  Eigen::Vector2d ResistorStrains(double fn_n, double ft_n) const {
    const Eigen::VectorXd u = Solve(fn_n, ft_n);
    return {MeanStrain(u, config_.gauge.r1), MeanStrain(u, config_.gauge.r2)};
  }

  /// Mean |eps_xx| over R1 [-] for Ft alone: the size of the strains k_t is the small residue of.
  double MeanAbsShearStrainR1(double ft_n) const {
    return MeanStrain(Solve(0.0, ft_n), config_.gauge.r1, /*absolute=*/true);
  }

 private:
  struct Member {
    int a, b;
    double thickness_mm;
    bool rigid;
  };

  int Node(const Eigen::Vector2d& p) {
    for (size_t i = 0; i < nodes_.size(); ++i) {
      if ((nodes_[i] - p).norm() < 1e-9) return static_cast<int>(i);
    }
    nodes_.push_back(p);
    return static_cast<int>(nodes_.size()) - 1;
  }
  int Node(const Eigen::Vector2d& p) const {
    for (size_t i = 0; i < nodes_.size(); ++i) {
      if ((nodes_[i] - p).norm() < 1e-9) return static_cast<int>(i);
    }
    return -1;
  }

  void AddMember(const Eigen::Vector2d& p, const Eigen::Vector2d& q, double thickness_mm, bool rigid) {
    members_.push_back({Node(p), Node(q), thickness_mm, rigid});
  }

  // Local stiffness (axial; Timoshenko bending with shear factor 5/6) in (u1, v1, th1, u2, v2, th2).
  Eigen::Matrix<double, 6, 6> LocalStiffness(const Member& m, double length) const {
    const double w = config_.geometry.width_mm;
    const double stiffening = m.rigid ? 1e6 : 1.0;  // a rigid block: 1e6 x the beam, no shear strain
    const double ea = stiffening * youngs_ * w * m.thickness_mm;
    const double ei = stiffening * youngs_ * w * std::pow(m.thickness_mm, 3) / 12.0;
    const double phi =
        m.rigid ? 0.0 : 12.0 * ei / (5.0 / 6.0 * shear_modulus_ * w * m.thickness_mm * length * length);
    const double l = length;
    const double c = ei / (l * l * l * (1.0 + phi));
    Eigen::Matrix<double, 6, 6> k = Eigen::Matrix<double, 6, 6>::Zero();
    k(0, 0) = k(3, 3) = ea / l;
    k(0, 3) = k(3, 0) = -ea / l;
    const int v[4] = {1, 2, 4, 5};
    const double b[4][4] = {{12, 6 * l, -12, 6 * l},
                            {6 * l, (4 + phi) * l * l, -6 * l, (2 - phi) * l * l},
                            {-12, -6 * l, 12, -6 * l},
                            {6 * l, (2 - phi) * l * l, -6 * l, (4 + phi) * l * l}};
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) k(v[i], v[j]) = c * b[i][j];
    }
    return k;
  }

  Eigen::Matrix<double, 6, 6> Rotation(const Member& m, double* length) const {
    const Eigen::Vector2d d = nodes_[m.b] - nodes_[m.a];
    *length = d.norm();
    const double c = d.x() / *length, s = d.y() / *length;
    Eigen::Matrix<double, 6, 6> t = Eigen::Matrix<double, 6, 6>::Zero();
    for (int n = 0; n < 2; ++n) {
      t(3 * n, 3 * n) = c;
      t(3 * n, 3 * n + 1) = s;
      t(3 * n + 1, 3 * n) = -s;
      t(3 * n + 1, 3 * n + 1) = c;
      t(3 * n + 2, 3 * n + 2) = 1.0;
    }
    return t;
  }

  Eigen::Matrix<double, 6, 1> Gather(const Member& m, const Eigen::VectorXd& u) const {
    Eigen::Matrix<double, 6, 1> out;
    for (int i = 0; i < 3; ++i) {
      out(i) = u(3 * m.a + i);
      out(3 + i) = u(3 * m.b + i);
    }
    return out;
  }

  Eigen::VectorXd Solve(double fn_n, double ft_n) const {
    const int dofs = 3 * static_cast<int>(nodes_.size());
    Eigen::MatrixXd k = Eigen::MatrixXd::Zero(dofs, dofs);
    for (const Member& m : members_) {
      double length = 0.0;
      const Eigen::Matrix<double, 6, 6> t = Rotation(m, &length);
      const Eigen::Matrix<double, 6, 6> global = t.transpose() * LocalStiffness(m, length) * t;
      for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
          k((i < 3 ? 3 * m.a : 3 * m.b) + i % 3, (j < 3 ? 3 * m.a : 3 * m.b) + j % 3) += global(i, j);
        }
      }
    }
    Eigen::VectorXd f = Eigen::VectorXd::Zero(dofs);
    // The mesa is rigid: its top load acts at the beam centre with the shear's moment about the axis.
    f(3 * centre_node_) = ft_n;
    f(3 * centre_node_ + 1) = -fn_n;
    f(3 * centre_node_ + 2) = -ft_n * lever_arm_mm_;  // +x force above the axis turns clockwise
    for (size_t n = 0; n < nodes_.size(); ++n) {
      if (std::abs(nodes_[n].y()) > 1e-9) continue;  // brace feet: fixed
      for (int i = 0; i < 3; ++i) {
        const int d = 3 * static_cast<int>(n) + i;
        k.row(d).setZero();
        k.col(d).setZero();
        k(d, d) = 1.0;
        f(d) = 0.0;
      }
    }
    return k.ldlt().solve(f);
  }

  // Mean (or mean absolute) underside strain over `extent`, from the beam members' end forces: axial
  // strain plus bending strain at the underside, linear along each member (no load inside one).
  double MeanStrain(const Eigen::VectorXd& u, const ResistorExtent& extent, bool absolute = false) const {
    const double t = config_.geometry.beam_thickness_mm;
    const double w = config_.geometry.width_mm;
    double integral = 0.0;
    for (const Member& m : members_) {
      const Eigen::Vector2d p = nodes_[m.a], q = nodes_[m.b];
      if (std::abs(p.y() - beam_axis_y_) > 1e-9 || std::abs(q.y() - beam_axis_y_) > 1e-9) continue;
      const double x0 = std::min(p.x(), q.x()), x1 = std::max(p.x(), q.x());
      if (x0 < extent.start_mm - 1e-9 || x1 > extent.end_mm + 1e-9) continue;
      if (m.rigid) continue;  // the beam under a rigid mesa does not strain
      double length = 0.0;
      const Eigen::Matrix<double, 6, 6> rotation = Rotation(m, &length);
      const Eigen::Matrix<double, 6, 1> end_forces = LocalStiffness(m, length) * (rotation * Gather(m, u));
      const double tension = -end_forces(0);
      const double ea = youngs_ * w * t;
      const double ei = youngs_ * w * t * t * t / 12.0;
      // Sagging moment at distance s from the first node; sagging stretches the underside.
      const auto strain = [&](double s) {
        return tension / ea + (s * end_forces(1) - end_forces(2)) * 0.5 * t / ei;
      };
      const double e0 = strain(0.0), e1 = strain(length);
      if (!absolute || e0 * e1 >= 0.0) {
        integral += (absolute ? 0.5 * (std::abs(e0) + std::abs(e1)) : 0.5 * (e0 + e1)) * length;
      } else {
        // The strain changes sign inside: two triangles.
        integral += 0.5 * (e0 * e0 + e1 * e1) / std::abs(e1 - e0) * length;
      }
    }
    return integral / (extent.end_mm - extent.start_mm);
  }

  const FeaConfig config_;
  double youngs_ = 0.0;
  double shear_modulus_ = 0.0;
  double beam_axis_y_ = 0.0;
  double lever_arm_mm_ = 0.0;
  int centre_node_ = -1;
  std::vector<Eigen::Vector2d> nodes_;
  std::vector<Member> members_;
};

// How far a beam model can be trusted here. Beam theory holds where plane sections stay plane; next
// to a joint or a load introduction (the brace corners, the mesa edges) they do not, over a zone
// about one beam depth long (Saint-Venant). Each free segment between mesa and brace is
// l = (span - mesa) / 2 = 0.75 mm long against a depth t = 0.2 mm, so that zone is t / l = 27 % of
// it, and the model's strains are good to that fraction (the centroid-axis joints and the rigid mesa
// err in opposite directions: the first overstates the flexible length, the second ignores the
// strain under the mesa). k_n is an average of one sign and takes it as a relative tolerance. k_t is
// the small residue of a shear profile that changes sign inside each resistor, so its tolerance is
// that fraction of the mean |strain| under the resistor, not of the residue.
double TrustedFraction(const GeometryConfig& g) {
  return g.beam_thickness_mm / (0.5 * (g.SpanMm() - g.mesa_length_mm));
}

class FrameModelTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { results_ = new FeaResults(RunUnitAnalysis(FeaConfig{})); }
  static void TearDownTestSuite() { delete results_; }
  static double FeaKn() { return results_->sensitivities.kn_per_n; }
  static double FeaKt() { return results_->sensitivities.kt_per_n; }

 private:
  static FeaResults* results_;
};
FeaResults* FrameModelTest::results_ = nullptr;

TEST_F(FrameModelTest, FeaSensitivitiesAreTheOnesTheDocsQuote) {
  EXPECT_NEAR(FeaKn(), kDocumentedKnPerN, kDocumentedRounding * kDocumentedKnPerN);
  EXPECT_NEAR(FeaKt(), kDocumentedKtPerN, kDocumentedRounding * kDocumentedKtPerN);
}

TEST_F(FrameModelTest, FeaKnAgreesWithTheBeamModel) {
  const FeaConfig config;
  const FrameModel frame(config);
  const double force_n = config.load.max_force_n;
  const Eigen::Vector2d normal = frame.ResistorStrains(force_n, 0.0);
  EXPECT_NEAR(normal(0), normal(1), 1e-6 * std::abs(normal(0)));  // symmetric (1e6-stiff mesa: 6 digits)
  const double kn_beam = 0.5 * (normal(0) + normal(1)) / force_n;
  const double tolerance = TrustedFraction(config.geometry);
  EXPECT_NEAR(FeaKn() / kn_beam, 1.0, tolerance) << "FEA " << FeaKn() << ", beam model " << kn_beam;
}

TEST_F(FrameModelTest, FeaKtAgreesWithTheBeamModelWithTheMesaMoment) {
  const FeaConfig config;
  const FrameModel frame(config);
  const double force_n = config.load.max_force_n;
  const Eigen::Vector2d shear = frame.ResistorStrains(0.0, force_n);
  EXPECT_NEAR(shear(0), -shear(1), 1e-6 * std::abs(shear(0)));  // antisymmetric
  const double kt_beam = 0.5 * (shear(0) - shear(1)) / force_n;
  const double tolerance = TrustedFraction(config.geometry) * frame.MeanAbsShearStrainR1(force_n) / force_n;
  EXPECT_GT(kt_beam, 0.0) << "R1 is the half a positive shear stretches (paper eq. 3)";
  EXPECT_NEAR(FeaKt(), kt_beam, tolerance) << "FEA " << FeaKt() << ", beam model " << kt_beam;

  // The check sees the mesa moment: without the lever arm, and with R1 and R2 swapped (k_t of the
  // opposite sign), the beam model is further from the FEA than the tolerance.
  const FrameModel no_lever(config, 0.0);
  const Eigen::Vector2d flat = no_lever.ResistorStrains(0.0, force_n);
  EXPECT_GT(std::abs(FeaKt() - 0.5 * (flat(0) - flat(1)) / force_n), tolerance);
  EXPECT_GT(std::abs(-FeaKt() - kt_beam), tolerance);
}

}  // namespace
}  // namespace graspbed::fea
