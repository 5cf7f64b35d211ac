// Per-frame cost of the sensor path for one 20-unit frame (default layout):
//   BM_ReadoutAndInversion: Readout::Process + Inversion::Invert (the hardware path's cost)
//   BM_ReadoutInversionController: the same plus GripSlipController::Update (the per-frame control path)
//   BM_StrainModelSample:   StrainModel::Sample, ideal and with every non-ideal option on
// Run: build/bench/readout_bench   (docs/sensor.md)
#include <benchmark/benchmark.h>

#include <vector>

#include "controller/grip_slip_controller.h"
#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/readout.h"
#include "sensor/strain_model.h"

namespace graspbed::sensor {
namespace {

std::vector<UnitLoad> Loads(int count) {
  std::vector<UnitLoad> loads(static_cast<size_t>(count));
  for (int u = 0; u < count; ++u) loads[static_cast<size_t>(u)] = {0.4 * u, 0.3 * u - 3.0, 0.1, 0.1e-3};
  return loads;
}

/// The hardware path's per-frame chain on the default layout, with a small ring of distinct tared
/// frames so the branch predictor does not see one frame forever.
struct FramePath {
  static constexpr int kFrames = 64;
  Layout layout = LoadLayout(DefaultLayoutPath());
  StrainModel model{layout, NoisyConfig(), 1};
  Readout readout{ReadoutConfig{}, layout.unit_count(), 3400};
  Inversion inversion{layout, PaperCalibration(layout.unit_count()), InversionConfig{}};
  std::vector<RawFrame> frames = std::vector<RawFrame>(kFrames);
  ReadoutFrame readout_frame;
  TactileState state;
  int index = 0;

  FramePath() {
    readout.SetBaseline(model.r0_ohm_r1(), model.r0_ohm_r2());
    const std::vector<UnitLoad> loads = Loads(layout.unit_count());
    for (int i = 0; i < kFrames; ++i) model.Sample(loads, i * 1e-3, &frames[static_cast<size_t>(i)]);
  }
  static StrainModelConfig NoisyConfig() {
    StrainModelConfig config;
    config.noise_ohm = 0.5;
    return config;
  }
  /// Readout + inversion of the next frame of the ring, stamped with `sequence`.
  const TactileState& Next(uint32_t sequence) {
    RawFrame& frame = frames[static_cast<size_t>(index)];
    frame.sequence = sequence;
    readout.Process(frame, &readout_frame);
    inversion.Invert(readout_frame, &state);
    index = (index + 1) % kFrames;
    return state;
  }
};

void BM_ReadoutAndInversion(benchmark::State& bench) {
  FramePath path;
  uint32_t sequence = 0;
  for (auto _ : bench) benchmark::DoNotOptimize(path.Next(++sequence).total_fn_n);
  bench.SetItemsProcessed(bench.iterations());
  bench.SetLabel("20 units, ns per frame");
}
BENCHMARK(BM_ReadoutAndInversion);

void BM_ReadoutInversionController(benchmark::State& bench) {
  FramePath path;
  controller::GripSlipController controller{controller::GripSlipConfig{}};
  controller.SetIntent(controller::GraspIntent::kClose);
  uint32_t sequence = 0;
  double time_s = 0.0;
  // The hand as the realistic proprioception reports a held pinch: both digits still, at stall.
  hand::HandState hand;
  hand.time_s = 0.0;
  hand.digit_count = 2;
  for (hand::DigitState& digit : hand.digits) {
    digit.joint_count = 1;
    digit.position_known = digit.velocity_known = digit.current_known = digit.stops_known = true;
    digit.joint_position[0] = 0.3;
    digit.motor_current_a = 0.3;
    digit.stall_current_a = 1.0;
  }
  for (auto _ : bench) {
    time_s += 1e-3;  // a new frame every 1 ms tick, as the loop delivers them
    hand.time_s = time_s;
    benchmark::DoNotOptimize(controller.Update(path.Next(++sequence), hand, time_s));
  }
  bench.SetItemsProcessed(bench.iterations());
  bench.SetLabel("20 units, grip_slip holding, ns per frame");
}
BENCHMARK(BM_ReadoutInversionController);

void BM_StrainModelSample(benchmark::State& bench) {
  const bool non_ideal = bench.range(0) != 0;
  const Layout layout = LoadLayout(DefaultLayoutPath());
  StrainModelConfig config;
  if (non_ideal) {
    config.r0_spread_fraction = 0.01;
    config.noise_ohm = 0.5;
    config.adc_bits = 16;
    config.temperature_coefficient_per_k = 1e-4;
    config.temperature_ramp_k_per_s = 0.01;
    config.saturation_force_n = 11;
    config.cross_talk_shear_fraction = 0.05;
    config.cross_talk_offset_per_mm = 0.1;
  }
  StrainModel model(layout, config, 1);
  const std::vector<UnitLoad> loads = Loads(layout.unit_count());
  RawFrame frame;
  double time_s = 0.0;
  for (auto _ : bench) {
    model.Sample(loads, time_s, &frame);
    benchmark::DoNotOptimize(frame.r1_ohm[0]);
    time_s += 1e-3;
  }
  bench.SetItemsProcessed(bench.iterations());
  bench.SetLabel(non_ideal ? "20 units, all non-ideal options on" : "20 units, ideal");
}
BENCHMARK(BM_StrainModelSample)->Arg(0)->Arg(1);

}  // namespace
}  // namespace graspbed::sensor

BENCHMARK_MAIN();
