#include "sensor/fea/unit_analysis.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

namespace graspbed::fea {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

constexpr std::array<double, 3> kGaussPoints{-0.7745966692414834, 0.0, 0.7745966692414834};
constexpr std::array<double, 3> kGaussWeights{5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
constexpr double kSameXTolMm = 1e-9;  // node positions closer than this are the same node

// Elements of grid row `row` whose bottom face is free (no element directly below), by ascending x.
std::vector<int> FreeBottomElements(const Mesh& mesh, int row) {
  std::vector<int> elements;
  for (int i = 0; i < mesh.CellsX(); ++i) {
    const int element = mesh.CellElement(i, row);
    if (element >= 0 && mesh.CellElement(i, row - 1) < 0) elements.push_back(element);
  }
  return elements;
}

Mesh MeshUnit(const FeaConfig& config) {
  config.Validate();
  const GeometryConfig& g = config.geometry;
  const double half = 0.5 * g.beam_length_mm;
  const double h = g.brace_height_mm;
  const double top = h + g.beam_thickness_mm;
  const std::vector<Rect> rects{
      {-half, -half + g.brace_thickness_mm, 0.0, h},
      {half - g.brace_thickness_mm, half, 0.0, h},
      {-half, half, h, top},
      {-0.5 * g.mesa_length_mm, 0.5 * g.mesa_length_mm, top, top + g.mesa_height_mm},
  };
  // Resistor ends and the centre become grid lines so the averages cover whole element faces.
  const std::vector<double> extra_x{0.0, config.gauge.r1.start_mm, config.gauge.r1.end_mm,
                                    config.gauge.r2.start_mm, config.gauge.r2.end_mm};
  return MeshRectangles(rects, config.mesh.element_size_mm, extra_x);
}

std::vector<PrescribedDof> FixedFeet(const Mesh& mesh) {
  std::vector<PrescribedDof> fixed;
  for (int node = 0; node < static_cast<int>(mesh.nodes.size()); ++node) {
    if (std::abs(mesh.nodes[node].y()) < kSameXTolMm) {
      fixed.push_back({2 * node, 0.0});
      fixed.push_back({2 * node + 1, 0.0});
    }
  }
  return fixed;
}

double MaxAbs(const std::vector<double>& values) {
  double largest = 0.0;
  for (double value : values) largest = std::max(largest, std::abs(value));
  return largest;
}

}  // namespace

LineFit FitLine(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size() || x.size() < 2) {
    throw std::invalid_argument("FitLine: need two equally long series of at least 2 points");
  }
  const double n = static_cast<double>(x.size());
  double mean_x = 0.0, mean_y = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    mean_x += x[i] / n;
    mean_y += y[i] / n;
  }
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mean_x) * (x[i] - mean_x);
    sxy += (x[i] - mean_x) * (y[i] - mean_y);
    syy += (y[i] - mean_y) * (y[i] - mean_y);
  }
  LineFit fit;
  fit.slope = sxx > 0.0 ? sxy / sxx : 0.0;
  fit.intercept = mean_y - fit.slope * mean_x;
  double residual = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double r = y[i] - (fit.slope * x[i] + fit.intercept);
    residual += r * r;
  }
  fit.r_squared = syy > 0.0 ? 1.0 - residual / syy : 1.0;
  return fit;
}

namespace {

StrainLine BottomStrainOf(const PlaneStressModel& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                          const std::vector<int>& elements) {
  StrainLine line;
  std::vector<int> shared;  // how many elements contributed to each point
  for (int element : elements) {
    for (double xi : {-1.0, 0.0, 1.0}) {
      const double x = model.PositionAt(element, xi, -1.0).x();
      const double eps = model.StrainAt(element, xi, -1.0, u)[0];
      if (!line.x_mm.empty() && std::abs(line.x_mm.back() - x) < kSameXTolMm) {
        line.eps.back() = (line.eps.back() * shared.back() + eps) / (shared.back() + 1);
        ++shared.back();
      } else {
        line.x_mm.push_back(x);
        line.eps.push_back(eps);
        shared.push_back(1);
      }
    }
  }
  return line;
}

double AverageBottomStrainOf(const PlaneStressModel& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                             const std::vector<int>& elements, double x_start_mm, double x_end_mm) {
  double integral = 0.0;
  double covered = 0.0;
  for (int element : elements) {
    const double x0 = model.PositionAt(element, -1.0, -1.0).x();
    const double x1 = model.PositionAt(element, 1.0, -1.0).x();
    const double a = std::max(x0, x_start_mm);
    const double b = std::min(x1, x_end_mm);
    if (!(b > a)) continue;
    // Map the overlap [a, b] into xi; MeshRectangles elements are axis-aligned rectangles.
    for (int g = 0; g < 3; ++g) {
      const double x = 0.5 * (a + b) + 0.5 * (b - a) * kGaussPoints[g];
      const double xi = 2.0 * (x - x0) / (x1 - x0) - 1.0;
      integral += model.StrainAt(element, xi, -1.0, u)[0] * 0.5 * (b - a) * kGaussWeights[g];
    }
    covered += b - a;
  }
  if (!(covered > 0.0)) {
    throw std::invalid_argument("AverageBottomStrain: no free bottom face lies in [" +
                                std::to_string(x_start_mm) + ", " + std::to_string(x_end_mm) + "] mm");
  }
  return integral / covered;
}

}  // namespace

StrainLine BottomSurfaceStrain(const PlaneStressModel& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                               int row) {
  return BottomStrainOf(model, u, FreeBottomElements(model.mesh(), row));
}

double AverageBottomStrain(const PlaneStressModel& model, const Eigen::Ref<const Eigen::VectorXd>& u, int row,
                           double x_start_mm, double x_end_mm) {
  return AverageBottomStrainOf(model, u, FreeBottomElements(model.mesh(), row), x_start_mm, x_end_mm);
}

PlaneStressModel UnitModel::BuildModel(const FeaConfig& config, double* mesh_s, double* assemble_factor_s) {
  const Clock::time_point mesh_start = Clock::now();
  Mesh mesh = MeshUnit(config);
  std::vector<PrescribedDof> fixed = FixedFeet(mesh);
  *mesh_s = Seconds(mesh_start);
  const Clock::time_point factor_start = Clock::now();
  PlaneStressModel model(
      std::move(mesh),
      {config.material.youngs_modulus_gpa * 1000.0, config.material.poisson_ratio, config.geometry.width_mm},
      std::move(fixed));
  *assemble_factor_s = Seconds(factor_start);
  return model;
}

UnitModel::UnitModel(const FeaConfig& config)
    : config_(config), model_(BuildModel(config_, &mesh_s_, &assemble_factor_s_)) {
  const Mesh& m = model_.mesh();
  const double underside_y = config_.geometry.brace_height_mm;
  underside_row_ = -1;
  for (int j = 0; j < m.CellsY(); ++j) {
    if (std::abs(m.y_lines[j] - underside_y) < kSameXTolMm) underside_row_ = j;
  }
  if (underside_row_ < 0) throw std::logic_error("UnitModel: no grid line at the beam underside");
  underside_elements_ = FreeBottomElements(m, underside_row_);
  const int top_row = m.CellsY() - 1;
  for (int i = 0; i < m.CellsX(); ++i) {
    const int element = m.CellElement(i, top_row);
    if (element >= 0) mesa_top_elements_.push_back(element);
  }
}

Eigen::VectorXd UnitModel::LoadVector(double fn_n, double ft_n) const {
  Eigen::VectorXd loads = Eigen::VectorXd::Zero(model_.DofCount());
  const double area_mm2 = config_.geometry.mesa_length_mm * config_.geometry.width_mm;
  const Eigen::Vector2d traction(ft_n / area_mm2, -fn_n / area_mm2);
  for (int element : mesa_top_elements_) model_.AddEdgeTraction(element, Side::kTop, traction, loads);
  return loads;
}

StrainLine UnitModel::Underside(const Eigen::Ref<const Eigen::VectorXd>& u) const {
  return BottomStrainOf(model_, u, underside_elements_);
}

Eigen::Vector2d UnitModel::ResistorStrains(const Eigen::Ref<const Eigen::VectorXd>& u) const {
  const GaugeConfig& gauge = config_.gauge;
  return {AverageBottomStrainOf(model_, u, underside_elements_, gauge.r1.start_mm, gauge.r1.end_mm),
          AverageBottomStrainOf(model_, u, underside_elements_, gauge.r2.start_mm, gauge.r2.end_mm)};
}

FeaResults RunUnitAnalysis(const FeaConfig& config) {
  const UnitModel unit(config);
  FeaResults results;
  results.stats.mesh_s = unit.mesh_s();

  const Clock::time_point solve_start = Clock::now();
  const int levels = config.load.steps + 1;
  const double max_n = config.load.max_force_n;
  // Columns: normal sweep, shear sweep, then the Fig. 4 cases normal, shear, both.
  const int cases = 2 * levels + 3;
  Eigen::MatrixXd loads(unit.model().DofCount(), cases);
  std::vector<double> forces(levels);
  for (int k = 0; k < levels; ++k) {
    forces[k] = max_n * k / config.load.steps;
    loads.col(k) = unit.LoadVector(forces[k], 0.0);
    loads.col(levels + k) = unit.LoadVector(0.0, forces[k]);
  }
  loads.col(2 * levels) = unit.LoadVector(max_n, 0.0);
  loads.col(2 * levels + 1) = unit.LoadVector(0.0, max_n);
  loads.col(2 * levels + 2) = unit.LoadVector(max_n, max_n);
  const Eigen::MatrixXd u = unit.model().Solve(loads);

  results.normal_sweep.force_n = forces;
  results.shear_sweep.force_n = forces;
  std::vector<double> mean_normal, half_diff_shear;
  for (int k = 0; k < levels; ++k) {
    const Eigen::Vector2d n = unit.ResistorStrains(u.col(k));
    const Eigen::Vector2d t = unit.ResistorStrains(u.col(levels + k));
    results.normal_sweep.eps1.push_back(n[0]);
    results.normal_sweep.eps2.push_back(n[1]);
    results.shear_sweep.eps1.push_back(t[0]);
    results.shear_sweep.eps2.push_back(t[1]);
    mean_normal.push_back(0.5 * (n[0] + n[1]));
    half_diff_shear.push_back(0.5 * (t[0] - t[1]));
  }
  const StrainLine normal = unit.Underside(u.col(2 * levels));
  const StrainLine shear = unit.Underside(u.col(2 * levels + 1));
  const StrainLine both = unit.Underside(u.col(2 * levels + 2));
  results.stats.solve_s = Seconds(solve_start);

  StrainProfile& profile = results.profile;
  profile.x_mm = normal.x_mm;
  profile.normal = normal.eps;
  profile.shear = shear.eps;
  profile.both = both.eps;
  double worst_difference = 0.0;
  for (size_t i = 0; i < normal.eps.size(); ++i) {
    profile.sum.push_back(normal.eps[i] + shear.eps[i]);
    worst_difference = std::max(worst_difference, std::abs(both.eps[i] - profile.sum.back()));
  }
  // Also on the resistor averages, which is what the sensor model uses.
  const Eigen::Vector2d r_n = unit.ResistorStrains(u.col(2 * levels));
  const Eigen::Vector2d r_t = unit.ResistorStrains(u.col(2 * levels + 1));
  const Eigen::Vector2d r_both = unit.ResistorStrains(u.col(2 * levels + 2));
  const double resistor_difference = (r_both - r_n - r_t).cwiseAbs().maxCoeff();
  results.superposition_error =
      std::max(worst_difference / MaxAbs(profile.both), resistor_difference / r_both.cwiseAbs().maxCoeff());

  results.normal_fit = FitLine(forces, mean_normal);
  results.shear_fit = FitLine(forces, half_diff_shear);
  results.sensitivities = {results.normal_fit.slope, results.shear_fit.slope};
  results.kn_ratio = results.sensitivities.kn_per_n / config.reference.kn_per_n;
  results.kt_ratio = results.sensitivities.kt_per_n / config.reference.kt_per_n;
  results.normal_to_shear_cross_talk = std::abs(r_n[0] - r_n[1]) / std::abs(r_n[0] + r_n[1]);
  results.shear_to_normal_cross_talk = std::abs(r_t[0] + r_t[1]) / std::abs(r_t[0] - r_t[1]);
  results.peak_normal_strain = MaxAbs(profile.normal);
  results.peak_shear_strain = MaxAbs(profile.shear);

  results.stats.nodes = static_cast<int>(unit.model().mesh().nodes.size());
  results.stats.elements = static_cast<int>(unit.model().mesh().elements.size());
  results.stats.free_dofs = unit.model().FreeDofCount();
  results.stats.stiffness_non_zeros = unit.model().StiffnessNonZeros();
  results.stats.load_cases = cases;
  results.stats.assemble_factor_s = unit.assemble_factor_s();
  return results;
}

Sensitivities ComputeSensitivities(const FeaConfig& config) { return RunUnitAnalysis(config).sensitivities; }

}  // namespace graspbed::fea
