#include "sensor/readout.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "tests/support/error_of.h"
#include "tests/support/temp_dir.h"

namespace graspbed::sensor {
namespace {

using ::testing::HasSubstr;
using testing::ErrorOf;
using testing::TempDir;

constexpr double kRelTol = 1e-12;
constexpr int kUnits = 4;

RawFrame Frame(double r1, double r2, uint32_t sequence = 0) {
  RawFrame frame;
  frame.sequence = sequence;
  frame.time_s = sequence * 1e-3;
  frame.unit_count = kUnits;
  for (int u = 0; u < kUnits; ++u) {
    frame.r1_ohm[u] = r1;
    frame.r2_ohm[u] = r2;
  }
  return frame;
}

TEST(ReadoutTest, TaresByAveragingTheFirstFrames) {
  ReadoutConfig config;
  config.baseline_frames = 10;
  Readout readout(config, kUnits, 3400);
  ReadoutFrame out;
  EXPECT_FALSE(readout.tared());
  // Baseline alternates 3390 / 3410: mean 3400 for R1; R2 constant 3300.
  for (int i = 0; i < 10; ++i) {
    RawFrame frame = Frame(i % 2 == 0 ? 3390 : 3410, 3300, static_cast<uint32_t>(i));
    frame.r1_ohm[0] = 3500;
    readout.Process(frame, &out);
    EXPECT_EQ(out.validity[1], UnitValidity::kNotTared);
    EXPECT_EQ(out.dr1_rel[1], 0.0);
    EXPECT_EQ(out.sequence, static_cast<uint32_t>(i));
  }
  EXPECT_TRUE(readout.tared());
  EXPECT_NEAR(readout.baseline_r1_ohm()[1], 3400, 1e-9);
  EXPECT_NEAR(readout.baseline_r1_ohm()[0], 3500, 1e-9);
  readout.Process(Frame(3400 * 1.5, 3300 * 0.9, 10), &out);
  EXPECT_EQ(out.validity[1], UnitValidity::kValid);
  EXPECT_NEAR(out.dr1_rel[1], 0.5, kRelTol);
  EXPECT_NEAR(out.dr2_rel[1], -0.1, kRelTol);
  EXPECT_NEAR(out.dr1_rel[0], 3400 * 1.5 / 3500 - 1, kRelTol);
  EXPECT_EQ(out.sequence, 10u);
  EXPECT_DOUBLE_EQ(out.time_s, 0.01);
  // Reset starts a new tare window.
  readout.Reset();
  EXPECT_FALSE(readout.tared());
  readout.Process(Frame(3400, 3400), &out);
  EXPECT_EQ(out.validity[1], UnitValidity::kNotTared);
  EXPECT_EQ(readout.baseline_frames_seen(), 1);
}

TEST(ReadoutTest, StoredBaselineTaresAtOnce) {
  Readout readout(ReadoutConfig{}, kUnits, 3400);
  const std::vector<double> r1 = {3400, 3410, 3390, 3405};
  const std::vector<double> r2 = {3400, 3395, 3402, 3398};
  readout.SetBaseline(r1, r2);
  EXPECT_TRUE(readout.tared());
  ReadoutFrame out;
  readout.Process(Frame(3410, 3410), &out);
  EXPECT_EQ(out.validity[1], UnitValidity::kValid);
  EXPECT_NEAR(out.dr1_rel[1], 0.0, kRelTol);
  EXPECT_NEAR(out.dr2_rel[1], 3410.0 / 3395 - 1, kRelTol);
  EXPECT_THAT(ErrorOf([&] { readout.SetBaseline(std::vector<double>(3, 3400), r2); }),
              HasSubstr("baseline has 3/4 values for 4 units"));
  EXPECT_THAT(ErrorOf([&] { readout.SetBaseline(std::vector<double>{3400, -1, 3400, 3400}, r2); }),
              HasSubstr("baseline r1_ohm = -1: must be finite and > 0"));
}

class ReadoutValidityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    readout_.SetBaseline(std::vector<double>(kUnits, 3400), std::vector<double>(kUnits, 3400));
  }
  UnitValidity Validity(double r1, double r2) {
    RawFrame frame = Frame(3400, 3400);
    frame.r1_ohm[2] = r1;
    frame.r2_ohm[2] = r2;
    readout_.Process(frame, &out_);
    EXPECT_EQ(out_.validity[0], UnitValidity::kValid);
    return out_.validity[2];
  }
  ReadoutConfig config_{};
  Readout readout_{config_, kUnits, 3400};
  ReadoutFrame out_;
};

TEST_F(ReadoutValidityTest, OpenShortImplausibleOutOfRange) {
  EXPECT_EQ(Validity(5270, 5270), UnitValidity::kValid);
  EXPECT_EQ(Validity(kOpenCircuitOhm, 3400), UnitValidity::kOpen);
  EXPECT_EQ(Validity(3400, 2e6), UnitValidity::kOpen);
  EXPECT_EQ(Validity(kShortCircuitOhm, 3400), UnitValidity::kShort);
  EXPECT_EQ(Validity(3400, 0.5), UnitValidity::kShort);
  EXPECT_EQ(Validity(kShortCircuitOhm, kOpenCircuitOhm), UnitValidity::kOpen);
  EXPECT_EQ(Validity(100, 3400), UnitValidity::kImplausible);     // far below any strain
  EXPECT_EQ(Validity(20000, 3400), UnitValidity::kImplausible);   // > 3 R0
  EXPECT_EQ(Validity(std::nan(""), 3400), UnitValidity::kImplausible);
  EXPECT_EQ(Validity(3400 * 0.75, 3400 * 0.75), UnitValidity::kImplausible);  // pulled: mean dR/R -0.25
  EXPECT_EQ(Validity(3400 * 2.6, 3400), UnitValidity::kOutOfRange);  // dR/R 1.6 > 1.5
  EXPECT_NEAR(out_.dr1_rel[2], 1.6, kRelTol);
  // Frame for another unit count: every unit implausible.
  RawFrame wrong = Frame(3400, 3400);
  wrong.unit_count = 3;
  readout_.Process(wrong, &out_);
  EXPECT_EQ(out_.validity[0], UnitValidity::kImplausible);
  EXPECT_EQ(out_.unit_count, kUnits);
}

TEST(ReadoutTest, AdcFullScaleAndBadBaselines) {
  ReadoutConfig config;
  config.adc_full_scale_ohm = 8000;
  config.baseline_frames = 4;
  Readout readout(config, kUnits, 3400);
  ReadoutFrame out;
  for (int i = 0; i < 4; ++i) {
    RawFrame frame = Frame(3400, 3400);
    frame.r1_ohm[1] = kOpenCircuitOhm;  // open through the whole tare window
    frame.r1_ohm[2] = 4600;             // baseline 35% above nominal
    readout.Process(frame, &out);
    EXPECT_EQ(out.validity[1], UnitValidity::kOpen);
    EXPECT_EQ(out.validity[0], UnitValidity::kNotTared);
  }
  RawFrame frame = Frame(3400, 3400);
  frame.r1_ohm[3] = 8000;
  frame.r1_ohm[2] = 4600;
  readout.Process(frame, &out);
  EXPECT_EQ(out.validity[0], UnitValidity::kValid);
  EXPECT_EQ(out.validity[1], UnitValidity::kImplausible);  // recovered, but never tared
  EXPECT_EQ(out.validity[2], UnitValidity::kImplausible);  // bad tare
  EXPECT_EQ(out.validity[3], UnitValidity::kOutOfRange);   // ADC at full scale
}

TEST(ReadoutConfigTest, LoadsAndRejectsBadInput) {
  TempDir dir;
  const std::string good = dir.Write("r.yaml", "baseline_frames: 50\nadc_full_scale_ohm: 9000\nmax_abs_dr_rel: 1.2\n");
  const ReadoutConfig config = LoadReadoutConfig(common::YamlMap::LoadFile(good));
  EXPECT_EQ(config.baseline_frames, 50);
  EXPECT_EQ(config.adc_full_scale_ohm, 9000);
  EXPECT_EQ(config.max_abs_dr_rel, 1.2);
  const std::string bad = dir.Write("b.yaml", "baseline_frames: 50\nbaseline_frame: 0\n");
  EXPECT_THAT(ErrorOf([&] { LoadReadoutConfig(common::YamlMap::LoadFile(bad)); }),
              HasSubstr(dir.Path("b.yaml") + ":2: baseline_frame: unknown key"));
  const std::string zero = dir.Write("z.yaml", "baseline_frames: 0\n");
  EXPECT_EQ(ErrorOf([&] { LoadReadoutConfig(common::YamlMap::LoadFile(zero)); }),
            dir.Path("z.yaml") + ":1: baseline_frames = 0: must be >= 1");
  EXPECT_THAT(ErrorOf([] { Readout readout(ReadoutConfig{}, 0, 3400); }), HasSubstr("unit count 0 outside 1..64"));
  EXPECT_THAT(ErrorOf([] { Readout readout(ReadoutConfig{}, 4, -3400); }),
              HasSubstr("nominal_r0_ohm = -3400: must be finite and > 0"));
}

}  // namespace
}  // namespace graspbed::sensor
