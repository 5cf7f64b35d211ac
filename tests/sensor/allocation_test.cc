// The per-frame path (StrainModel::Sample, Readout::Process, Inversion::Invert) must not allocate:
// this executable links the counting replacement of the global operator new.
#include <gtest/gtest.h>

#include <vector>

#include "sensor/inversion.h"
#include "sensor/readout.h"
#include "sensor/strain_model.h"
#include "tests/support/allocation_counter.h"

namespace {
int* volatile escaped = nullptr;  // keeps the probe allocation from being optimised away
}  // namespace

namespace graspbed::sensor {
namespace {

TEST(AllocationTest, PerFramePathAllocatesNothing) {
  const Layout layout = LoadLayout(DefaultLayoutPath());
  StrainModelConfig config;  // every option on, so every branch runs
  config.r0_spread_fraction = 0.01;
  config.noise_ohm = 1.0;
  config.adc_bits = 16;
  config.temperature_coefficient_per_k = 1e-4;
  config.temperature_ramp_k_per_s = 0.1;
  config.saturation_force_n = 11;
  config.cross_talk_shear_fraction = 0.05;
  config.cross_talk_offset_per_mm = 0.1;
  config.dead_units = {2};
  config.shorted_units = {3};
  StrainModel model(layout, config, 1);
  ReadoutConfig readout_config;
  readout_config.baseline_frames = 5;
  Readout readout(readout_config, 20, 3400);
  const Inversion inversion(layout, PaperCalibration(20), InversionConfig{});
  std::vector<UnitLoad> loads(20, UnitLoad{3.0, 1.0, 0.5, 0.2e-3});
  loads[0].fn_n = 30.0;
  RawFrame frame;
  ReadoutFrame readout_frame;
  TactileState state;
  const long before = graspbed::test_support::AllocationCount();
  for (int i = 0; i < 50; ++i) {  // spans taring and tared frames
    model.Sample(loads, i * 1e-3, &frame);
    readout.Process(frame, &readout_frame);
    inversion.Invert(readout_frame, &state);
  }
  EXPECT_EQ(graspbed::test_support::AllocationCount() - before, 0);
  EXPECT_TRUE(readout.tared());
  EXPECT_EQ(state.validity[2], UnitValidity::kOpen);
  // The counter does count: a vector allocates.
  std::vector<int> probe(10);
  escaped = probe.data();
  EXPECT_GT(graspbed::test_support::AllocationCount() - before, 0);
}

}  // namespace
}  // namespace graspbed::sensor
