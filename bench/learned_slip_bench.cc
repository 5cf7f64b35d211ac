// Per-tick cost of the learned slip cue on a 20-unit state (default layout), the shipped model:
//   BM_SlipFeatures:      SlipFeatureExtractor::Update alone
//   BM_LearnedSlipCue:    features + the model (LearnedSlipCue::Update), the cue's whole per-tick cost
//   BM_SlipModelEvaluate: the model alone on one feature vector
// A ring of distinct states (a contact that loads and slides, with noise) so the trees do not see
// one input forever. Run: build/bench/learned_slip_bench   (docs/training-slip-detector.md)
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "common/data_dir.h"
#include "controller/learned_slip_cue.h"

namespace graspbed::controller {
namespace {

constexpr int kStates = 1024;

std::vector<sensor::TactileState> States() {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::vector<sensor::TactileState> states(kStates);
  for (int i = 0; i < kStates; ++i) {
    sensor::TactileState& s = states[static_cast<size_t>(i)];
    s.unit_count = 20;
    s.time_s = i * 1e-3;
    const double centre = 2.0 + 0.5 * std::sin(i * 0.01);
    for (int u = 0; u < 20; ++u) {
      const double d = (u / 4) - centre;
      s.fn_n[static_cast<size_t>(u)] = 1.5 * std::exp(-d * d) + noise(rng);
      s.ft_n[static_cast<size_t>(u)] = 0.4 * std::exp(-d * d) * std::sin(i * 0.05) + noise(rng);
      s.total_fn_n += s.fn_n[static_cast<size_t>(u)];
      ((u / 4 + u % 4) % 2 == 0 ? s.total_shear_axial_n : s.total_shear_circumferential_n) += s.ft_n[static_cast<size_t>(u)];
    }
    s.valid_count = 20;
  }
  return states;
}

SlipModel ShippedModel() {
  return LoadSlipModel(common::DataPath("models/slip/default_20.json"), {.layout_name = "default_20", .units = 20});
}

void BM_SlipFeatures(benchmark::State& bench) {
  const std::vector<sensor::TactileState> states = States();
  SlipFeatureExtractor extractor(SlipFeatureLayoutFor(20), 1e-3);
  std::array<double, kSlipFeatureCount> features{};
  size_t i = 0;
  for (auto _ : bench) {
    extractor.Update(states[i % kStates], static_cast<double>(i) * 1e-3, features);
    benchmark::DoNotOptimize(features);
    ++i;
  }
}
BENCHMARK(BM_SlipFeatures);

void BM_LearnedSlipCue(benchmark::State& bench) {
  const std::vector<sensor::TactileState> states = States();
  LearnedSlipCue cue(ShippedModel());
  size_t i = 0;
  for (auto _ : bench) {
    benchmark::DoNotOptimize(cue.Update(states[i % kStates], static_cast<double>(i) * 1e-3));
    ++i;
  }
}
BENCHMARK(BM_LearnedSlipCue);

void BM_SlipModelEvaluate(benchmark::State& bench) {
  const std::vector<sensor::TactileState> states = States();
  const SlipModel model = ShippedModel();
  SlipFeatureExtractor extractor(SlipFeatureLayoutFor(20), 1e-3);
  std::vector<std::array<double, kSlipFeatureCount>> rows(kStates);
  for (int k = 0; k < kStates; ++k) extractor.Update(states[static_cast<size_t>(k)], k * 1e-3, rows[static_cast<size_t>(k)]);
  size_t i = 0;
  for (auto _ : bench) {
    benchmark::DoNotOptimize(EvaluateSlipModel(model, rows[i % kStates]));
    ++i;
  }
}
BENCHMARK(BM_SlipModelEvaluate);

}  // namespace
}  // namespace graspbed::controller

BENCHMARK_MAIN();
