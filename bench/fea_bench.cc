// Cost of the sensing unit's FEA at the paper's mesh size (0.05 mm) and finer.
// Run: build/bench/fea_bench
#include <benchmark/benchmark.h>

#include "sensor/fea/fea_config.h"
#include "sensor/fea/unit_analysis.h"

namespace graspbed::fea {
namespace {

FeaConfig WithMesh(double element_size_mm) {
  FeaConfig config;
  config.mesh.element_size_mm = element_size_mm;
  return config;
}

// Arg: element size in micrometres.
double SizeMm(const benchmark::State& state) { return static_cast<double>(state.range(0)) * 1e-3; }

// The whole analysis the CLI runs: mesh, assemble, factorise, 25 load cases, strain recovery.
void BM_FullAnalysis(benchmark::State& state) {
  const FeaConfig config = WithMesh(SizeMm(state));
  FeaStats stats;
  for (auto _ : state) {
    const FeaResults results = RunUnitAnalysis(config);
    benchmark::DoNotOptimize(results.sensitivities.kn_per_n);
    stats = results.stats;
  }
  state.counters["free_dofs"] = stats.free_dofs;
  state.counters["elements"] = stats.elements;
}
BENCHMARK(BM_FullAnalysis)->Arg(100)->Arg(50)->Arg(25)->Unit(benchmark::kMillisecond);

// Meshing, stiffness assembly and the sparse LDLT factorisation.
void BM_AssembleFactorise(benchmark::State& state) {
  const FeaConfig config = WithMesh(SizeMm(state));
  for (auto _ : state) {
    const UnitModel unit(config);
    benchmark::DoNotOptimize(unit.model().FreeDofCount());
  }
}
BENCHMARK(BM_AssembleFactorise)->Arg(50)->Unit(benchmark::kMillisecond);

// One factorisation reused: forward/back substitution for N load cases at once.
void BM_SolveLoadCases(benchmark::State& state) {
  const UnitModel unit(WithMesh(0.05));
  const int cases = static_cast<int>(state.range(0));
  Eigen::MatrixXd loads(unit.model().DofCount(), cases);
  for (int k = 0; k < cases; ++k) loads.col(k) = unit.LoadVector(10.0 * k / cases, 5.0);
  for (auto _ : state) {
    const Eigen::MatrixXd u = unit.model().Solve(loads);
    benchmark::DoNotOptimize(u.data());
  }
  state.counters["cases"] = cases;
}
BENCHMARK(BM_SolveLoadCases)->Arg(1)->Arg(25)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace graspbed::fea

BENCHMARK_MAIN();
