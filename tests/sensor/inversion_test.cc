#include "sensor/inversion.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <vector>

#include "sensor/strain_model.h"
#include "tests/support/error_of.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::sensor {
namespace {

using test_support::ErrorOf;
using test_support::SourcePath;
using test_support::TempDir;
using ::testing::HasSubstr;

constexpr double kForceTolN = 1e-9;

class InversionPipelineTest : public ::testing::Test {
 protected:
  InversionPipelineTest()
      : layout_(LoadLayout(DefaultLayoutPath())),
        model_(layout_, StrainModelConfig{}, 1),
        readout_(ReadoutConfig{}, layout_.unit_count(), 3400),
        inversion_(layout_, PaperCalibration(layout_.unit_count()), InversionConfig{}) {
    readout_.SetBaseline(std::vector<double>(20, 3400), std::vector<double>(20, 3400));
  }
  const TactileState& Run(const std::vector<UnitLoad>& loads) {
    model_.Sample(loads, 0.0, &frame_);
    readout_.Process(frame_, &readout_frame_);
    inversion_.Invert(readout_frame_, &state_);
    return state_;
  }
  Layout layout_;
  StrainModel model_;
  Readout readout_;
  Inversion inversion_;
  RawFrame frame_;
  ReadoutFrame readout_frame_;
  TactileState state_;
};

TEST_F(InversionPipelineTest, RoundTripAcrossTheRatedRange) {
  std::vector<UnitLoad> loads(20);
  for (int step = 0; step <= 20; ++step) {
    for (int u = 0; u < 20; ++u) {
      // Every unit a different point of the 0..10 N x -10..10 N square, over the steps.
      loads[u].fn_n = 10.0 * ((step + u) % 21) / 20.0;
      loads[u].ft_n = -10.0 + 20.0 * ((3 * step + 7 * u) % 21) / 20.0;
    }
    const TactileState& state = Run(loads);
    for (int u = 0; u < 20; ++u) {
      ASSERT_EQ(state.validity[u], UnitValidity::kValid) << "unit " << u << " step " << step;
      EXPECT_NEAR(state.fn_n[u], loads[u].fn_n, kForceTolN);
      EXPECT_NEAR(state.ft_n[u], loads[u].ft_n, kForceTolN);
    }
  }
}

TEST_F(InversionPipelineTest, TotalsUseEachUnitsOrientation) {
  std::vector<UnitLoad> loads(20);
  // Unit 0 (row 0, col 0) axial; unit 1 circumferential; unit 2 axial; unit 3 circumferential.
  loads[0] = {2.0, 1.5, 0, 0};
  loads[1] = {3.0, -0.5, 0, 0};
  loads[2] = {1.0, 0.25, 0, 0};
  loads[3] = {0.04, 2.0, 0, 0};  // below the contact threshold
  const TactileState& state = Run(loads);
  EXPECT_EQ(state.unit_count, 20);
  EXPECT_EQ(state.valid_count, 20);
  EXPECT_NEAR(state.total_fn_n, 6.04, 1e-9);
  EXPECT_NEAR(state.total_shear_axial_n, 1.75, 1e-9);
  EXPECT_NEAR(state.total_shear_circumferential_n, 1.5, 1e-9);
  EXPECT_EQ(state.contact_count, 3);
  // A dead unit drops out of the totals.
  model_.SetUnitFault(0, UnitFault::kOpen);
  const TactileState& faulty = Run(loads);
  EXPECT_EQ(faulty.valid_count, 19);
  EXPECT_EQ(faulty.validity[0], UnitValidity::kOpen);
  EXPECT_EQ(faulty.fn_n[0], 0.0);
  EXPECT_NEAR(faulty.total_fn_n, 4.04, 1e-9);
  EXPECT_NEAR(faulty.total_shear_axial_n, 0.25, 1e-9);
  EXPECT_EQ(faulty.contact_count, 2);
}

TEST_F(InversionPipelineTest, OutOfRangeBeyondRatedPlusMargin) {
  std::vector<UnitLoad> loads(20);
  loads[0] = {10.4, 0, 0, 0};  // within the 5% margin
  loads[1] = {10.6, 0, 0, 0};
  loads[2] = {1.0, -10.6, 0, 0};
  const TactileState& state = Run(loads);
  EXPECT_EQ(state.validity[0], UnitValidity::kValid);
  EXPECT_EQ(state.validity[1], UnitValidity::kOutOfRange);
  EXPECT_NEAR(state.fn_n[1], 10.6, kForceTolN);  // the estimate is kept for the curious
  EXPECT_EQ(state.validity[2], UnitValidity::kOutOfRange);
  EXPECT_EQ(state.valid_count, 18);
  EXPECT_NEAR(state.total_fn_n, 10.4, 1e-9);
  EXPECT_EQ(state.contact_count, 3);  // overloaded units are touching
}

TEST(InversionTest, PerUnitSensitivitiesAndOffsets) {
  const Layout layout = LoadLayout(SourcePath("sensor/layouts/paper_3x3.yaml"));
  Calibration calibration = PaperCalibration(9);
  calibration.units[4] = {100, 6.0e-4, 3.0e-4, 0.5, -0.25};
  const Inversion inversion(layout, calibration, InversionConfig{});
  ReadoutFrame frame;
  frame.unit_count = 9;
  frame.dr1_rel[4] = 0.3;
  frame.dr2_rel[4] = 0.1;
  TactileState state;
  inversion.Invert(frame, &state);
  EXPECT_NEAR(state.fn_n[4], 0.4 / (2 * 100 * 6.0e-4) - 0.5, kForceTolN);
  EXPECT_NEAR(state.ft_n[4], 0.2 / (2 * 100 * 3.0e-4) + 0.25, kForceTolN);
  EXPECT_NEAR(state.fn_n[0], 0.0, kForceTolN);
}

TEST(InversionTest, MismatchedCalibrationAndBadConfig) {
  const Layout layout = LoadLayout(DefaultLayoutPath());
  EXPECT_THAT(ErrorOf([&] { Inversion inversion(layout, PaperCalibration(9), InversionConfig{}); }),
              HasSubstr("calibration has 9 units, layout 'default_20' has 20"));
  Calibration calibration = PaperCalibration(20);
  calibration.units[3].kn_per_n = 0;
  EXPECT_THAT(ErrorOf([&] { Inversion inversion(layout, calibration, InversionConfig{}); }),
              HasSubstr("units[3].kn_per_n = 0: must be > 0"));
  TempDir dir;
  const std::string path = dir.Write("i.yaml", "contact_threshold_n: 0.1\nrated_force_n: -10\n");
  EXPECT_EQ(ErrorOf([&] { LoadInversionConfig(common::YamlMap::LoadFile(path)); }),
            dir.Path("i.yaml") + ":2: rated_force_n = -10: must be > 0");
  const std::string good = dir.Write("g.yaml", "contact_threshold_n: 0.1\nrated_force_n: 12\n");
  const InversionConfig config = LoadInversionConfig(common::YamlMap::LoadFile(good));
  EXPECT_EQ(config.contact_threshold_n, 0.1);
  EXPECT_EQ(config.rated_force_n, 12);
}

}  // namespace
}  // namespace graspbed::sensor
