#include "controller/slip_detector.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <string>

#include "controller/filters.h"
#include "tests/controller/synthetic_tactile.h"

namespace graspbed::controller {
namespace {

using test_support::SyntheticContact;
using test_support::SyntheticTactile;
using ::testing::HasSubstr;

constexpr double kPeriodS = 0.001;
constexpr double kSlipLatencyLimitS = 0.030;
constexpr double kFriction = 0.5;
constexpr double kGripN = 3.0;
constexpr double kHoldLoadN = 0.9;
/// Stick-slip the vibration cue must see within the latency limit at the default noise, as a
/// fraction of the friction force [-]; HandPlant's own stick-slip is kPlantStickSlipFraction.
constexpr double kStickSlipMustSeeFraction = 0.8;
constexpr double kPlantStickSlipFraction = 0.3;
/// The same at 5 mN of shear noise with the default 0.03 N floor of the threshold [-].
constexpr double kStickSlipMustSeeAtLowNoiseFraction = 0.53;

/// Feeds a detector 1 kHz frames from `contact(t)`; returns the first time a cue fired, or -1.
struct Stream {
  explicit Stream(const SlipDetectorConfig& config, const SyntheticTactile::Options& sensor = {})
      : detector(config), sensor(sensor) {}

  double Run(double start_s, double end_s, const std::function<SyntheticContact(double)>& contact) {
    double first_s = -1.0;
    for (double t = start_s; t < end_s - 1e-9; t += kPeriodS) {
      const sensor::TactileState state = sensor.Frame(contact(t), t);
      const SlipSignals& signals = detector.Update(state, state.total_fn_n, kFriction, true, true);
      if (signals.any()) {
        ++flagged;
        if (first_s < 0.0) first_s = t;
      }
    }
    return first_s;
  }

  SlipDetector detector;
  SyntheticTactile sensor;
  int flagged = 0;
};

SyntheticContact Hold(double) {
  SyntheticContact contact;
  contact.grip_n = kGripN;
  contact.load_axial_n = kHoldLoadN;
  return contact;
}

/// The streams below hold their load from the first frame, with no loading ramp to tell preload
/// from load, as a pinch square to the object: from zero shear (preload_reference 0). The preload
/// has its own tests at the end.
SlipDetectorConfig SquarePinch() {
  SlipDetectorConfig config;
  config.preload_reference = false;
  return config;
}

/// Only one cue enabled, to measure it alone.
SlipDetectorConfig OnlyCue(bool ratio, bool vibration, bool centroid) {
  SlipDetectorConfig config = SquarePinch();
  config.ratio_enabled = ratio;
  config.vibration_enabled = vibration;
  config.centroid_enabled = centroid;
  return config;
}

TEST(SlipDetectorTest, StaticHoldWithNoiseRaisesNothingAndLearnsTheNoise) {
  Stream stream(SquarePinch());
  EXPECT_LT(stream.Run(0.0, 30.0, Hold), 0.0);
  EXPECT_EQ(stream.flagged, 0);
  const SlipSignals& signals = stream.detector.signals();
  EXPECT_NEAR(signals.ratio, kHoldLoadN / kGripN, 0.03);
  EXPECT_NEAR(signals.tangential_load_n, kHoldLoadN, 0.1);
  EXPECT_TRUE(signals.orientation_consistent);
  // High-passed shear noise: 0.04 N white noise through a 40 Hz high-pass keeps ~90 % of its power.
  EXPECT_NEAR(signals.noise_rms_n, 0.04 * std::sqrt(0.9), 0.01);
  EXPECT_NEAR(signals.centroid_row, 2.0, 0.1);
  EXPECT_NEAR(signals.centroid_column, 1.5, 0.1);
}

/// First detection by the vibration cue alone of a 120 Hz sawtooth stick-slip of `peak_to_peak_n`
/// while sliding at the friction limit of a 3 N grip, after 2 s of quiet hold; -1 if not within 0.5 s.
double VibrationLatencyS(double peak_to_peak_n, const SyntheticTactile::Options& sensor,
                         double min_rms_n = SlipDetectorConfig{}.vibration_min_rms_n) {
  SlipDetectorConfig config = OnlyCue(false, true, false);
  config.vibration_min_rms_n = min_rms_n;
  Stream stream(config, sensor);
  // The load sits at the friction limit before and after the onset, so only the vibration changes.
  const auto at_limit = [](double t) {
    SyntheticContact contact = Hold(t);
    contact.load_axial_n = kFriction * kGripN;
    return contact;
  };
  if (stream.Run(0.0, 2.0, at_limit) >= 0.0) return -2.0;  // a false flag in the quiet hold
  constexpr double kOnsetS = 2.0;
  const double first_s = stream.Run(kOnsetS, 2.5, [&](double t) {
    SyntheticContact contact = at_limit(t);
    contact.vibration_n = peak_to_peak_n * (std::fmod(t * 120.0, 1.0) - 0.5);
    return contact;
  });
  return first_s < 0.0 ? -1.0 : first_s - kOnsetS;
}

TEST(SlipDetectorTest, StickSlipVibrationSweptInAmplitudeAtTwoNoiseLevels) {
  // Sliding at the friction limit (1.5 N of shear on a 3 N grip) with a 120 Hz sawtooth over the
  // whole contact, swept in amplitude as a fraction of the friction force. HandPlant's stick-slip is
  // 30 % (0.45 N peak to peak here). Two noise levels: this file's default (0.04 N per unit on the
  // shear, 3x the divider_12bit profile with the paper's sensitivities) and a realistic amplified
  // chain (inamp_16bit with the FEA's sensitivities: about 5 mN on the shear, 1 mN on the normal;
  // tests/sensor/sensor_profile_test.cc).
  SyntheticTactile::Options realistic;
  realistic.noise_fn_n = 0.001;
  realistic.noise_ft_n = 0.005;
  const double friction_force_n = kFriction * kGripN;
  // Third: the realistic noise with the threshold's absolute floor (vibration_min_rms_n, 0.03 N by
  // default, there for noise-free signals) lowered to 2x the noise, so the threshold follows the noise.
  double smallest_within_limit[3] = {-1.0, -1.0, -1.0};
  for (int level = 0; level < 3; ++level) {
    const SyntheticTactile::Options sensor = level == 0 ? SyntheticTactile::Options{} : realistic;
    const double min_rms_n =
        level == 2 ? 2.0 * realistic.noise_ft_n : SlipDetectorConfig{}.vibration_min_rms_n;
    bool seen_smaller = false;
    for (const double fraction : {0.8, 0.67, 0.53, 0.4, 0.3, 0.2, 0.1, 0.05}) {
      const double latency_s = VibrationLatencyS(fraction * friction_force_n, sensor, min_rms_n);
      ASSERT_NE(latency_s, -2.0) << "false flag in the quiet hold";
      std::printf(
          "[ measure  ] vibration cue alone, shear noise %.3f N/unit, floor %.3f N: stick-slip %2.0f %% "
          "(%.2f N p-p): %s %.0f ms\n",
          sensor.noise_ft_n, min_rms_n, 100 * fraction, fraction * friction_force_n,
          latency_s >= 0.0 ? "detected after" : "not detected in",
          latency_s >= 0.0 ? latency_s * 1e3 : 500.0);
      const bool within = latency_s >= 0.0 && latency_s < kSlipLatencyLimitS;
      // Larger amplitudes come first: once one is missed, smaller ones are not seen in time either.
      if (within && !seen_smaller) smallest_within_limit[level] = fraction;
      if (!within) seen_smaller = true;
    }
  }
  std::printf(
      "[ measure  ] smallest stick-slip seen within %.0f ms: %.0f %% at 0.04 N noise, %.0f %% at 0.005 N "
      "(0.03 N floor), %.0f %% at 0.005 N (0.01 N floor)\n",
      kSlipLatencyLimitS * 1e3, 100 * smallest_within_limit[0], 100 * smallest_within_limit[1],
      100 * smallest_within_limit[2]);
  // What the cue must see within the latency limit. At the default noise 80 % of the friction force,
  // not the plant's 30 % (the plant's slides are caught by the contact's travel instead, see
  // LearnsLowFrictionFromSlipAndThenHolds). At a realistic chain's noise the fixed 0.03 N floor, not
  // the noise, limits it to 53 %; with the floor at 2x the noise it sees the plant's 30 % and less.
  EXPECT_GT(smallest_within_limit[0], 0.0) << "not even 80 % seen at the default noise";
  EXPECT_LE(smallest_within_limit[0], kStickSlipMustSeeFraction);
  EXPECT_GT(smallest_within_limit[1], 0.0);
  EXPECT_LE(smallest_within_limit[1], kStickSlipMustSeeAtLowNoiseFraction);
  EXPECT_GT(smallest_within_limit[2], 0.0);
  EXPECT_LE(smallest_within_limit[2], kPlantStickSlipFraction);
}

TEST(SlipDetectorTest, ContactMovingAcrossUnitsDetectedWithinLatency) {
  Stream stream(OnlyCue(false, false, true));
  ASSERT_LT(stream.Run(0.0, 2.0, Hold), 0.0);
  constexpr double kOnsetS = 2.0;
  constexpr double kSlipSpeedPitchPerS = 40.0;  // 200 mm/s at 5 mm pitch: a dropping object
  const double first_s = stream.Run(kOnsetS, 2.5, [](double t) {
    SyntheticContact contact = Hold(t);
    contact.centre_row = 2.0 - kSlipSpeedPitchPerS * (t - kOnsetS);
    return contact;
  });
  ASSERT_GT(first_s, 0.0);
  std::printf("[ measure  ] centroid cue alone: contact moving at 200 mm/s detected after %.1f ms\n",
              (first_s - kOnsetS) * 1e3);
  EXPECT_LT(first_s - kOnsetS, kSlipLatencyLimitS);
}

TEST(SlipDetectorTest, LoadOutgrowingGripDetectedByRatioWithinLatency) {
  Stream stream(OnlyCue(true, false, false));
  ASSERT_LT(stream.Run(0.0, 2.0, Hold), 0.0);
  constexpr double kOnsetS = 2.0;
  // Load steps to the friction limit (ratio 0.5); the cue fires at 0.9 x 0.5.
  const double first_s = stream.Run(kOnsetS, 2.5, [](double t) {
    SyntheticContact contact = Hold(t);
    contact.load_axial_n = kFriction * kGripN;
    return contact;
  });
  ASSERT_GT(first_s, 0.0);
  std::printf("[ measure  ] ratio cue alone: load step to the friction limit detected after %.1f ms\n",
              (first_s - kOnsetS) * 1e3);
  EXPECT_LT(first_s - kOnsetS, kSlipLatencyLimitS);
}

TEST(SlipDetectorTest, SmoothLoadSwingsOfArmMotionRaiseNothing) {
  Stream stream(SquarePinch());
  // The load swings between 0.1 and 0.7 of the grip's friction limit at 1-5 Hz, the grip following
  // loosely: the ratio stays below 0.9 x friction, the shear is smooth, the contact does not move.
  const double first_s = stream.Run(0.0, 20.0, [](double t) {
    SyntheticContact contact = Hold(t);
    const double swing = std::sin(2.0 * std::numbers::pi * (1.0 + 0.2 * t) * t);
    contact.load_axial_n = kHoldLoadN * (1.0 + 0.7 * swing);
    contact.grip_n = kGripN * (1.0 + 0.3 * swing);
    return contact;
  });
  EXPECT_LT(first_s, 0.0);
  EXPECT_EQ(stream.flagged, 0);
}

TEST(SlipDetectorTest, NothingFiresDuringSettleOrWhenDisarmed) {
  SlipDetector detector(SquarePinch());
  SyntheticTactile sensor({});
  detector.Restart();
  SyntheticContact slipping = Hold(0.0);
  slipping.load_axial_n = 2.0 * kFriction * kGripN;
  for (int i = 0; i < 40; ++i) {  // within the default 50 ms settle time
    const sensor::TactileState state = sensor.Frame(slipping, i * kPeriodS);
    EXPECT_FALSE(detector.Update(state, state.total_fn_n, kFriction, true, true).any()) << i;
  }
  for (int i = 40; i < 200; ++i) {
    const sensor::TactileState state = sensor.Frame(slipping, i * kPeriodS);
    EXPECT_FALSE(detector.Update(state, state.total_fn_n, kFriction, false, true).any()) << i;
  }
  const sensor::TactileState state = sensor.Frame(slipping, 0.2);
  EXPECT_TRUE(detector.Update(state, state.total_fn_n, kFriction, true, true).ratio_slip);
}

TEST(SlipDetectorTest, CircumferentialLoadUsesTheOtherUnits) {
  Stream stream(SquarePinch());
  stream.Run(0.0, 0.5, [](double t) {
    SyntheticContact contact = Hold(t);
    contact.load_axial_n = 0.6;
    contact.load_circumferential_n = 0.8;
    return contact;
  });
  EXPECT_NEAR(stream.detector.signals().tangential_load_n, 1.0, 0.1);
}

TEST(SlipDetectorTest, WrongOrientationAssumptionIsNoticedAndFallsBack) {
  SlipDetectorConfig config = SquarePinch();
  config.even_units_axial = false;  // the sensor has even units axial
  Stream stream(config);
  stream.Run(0.0, 0.5, Hold);
  EXPECT_FALSE(stream.detector.signals().orientation_consistent);
  // Fallback: 2 x |total shear| / total normal; about right for a patch centred on the grid.
  EXPECT_NEAR(stream.detector.signals().tangential_load_n, kHoldLoadN, 0.25);
}

/// Preload (preload_reference, the default): the pad slides into place as it squeezes (shear
/// growing with the grip over the loading ramp), the grasp settles, and the contact sticks with
/// that shear in it. It is taken as preload, not load; more grip afterwards (a slip response) adds
/// no load; a load added on top is measured from it and flagged in time.
TEST(SlipDetectorTest, ShearLockedInAtTheGraspIsPreloadAndMoreGripAddsNoLoad) {
  constexpr double kPreloadRatio = 0.4;  // a flexing pad's oblique squeeze (docs/controller.md)
  constexpr double kRampS = 0.1;         // loading ramp, 0.5 -> kGripN
  Stream stream(SlipDetectorConfig{});
  const auto grasp = [&](double t) {
    SyntheticContact contact;
    contact.grip_n = 0.5 + (kGripN - 0.5) * std::min(t / kRampS, 1.0);
    contact.load_axial_n = kPreloadRatio * contact.grip_n;
    return contact;
  };
  // A ratio of 0.4 read as load would be near the cue's 0.9 x 0.5 and drive the grip up.
  EXPECT_LT(stream.Run(0.0, 0.6, grasp), 0.0);
  const SlipSignals& signals = stream.detector.signals();
  // Within the synthetic sensor's noise and cross-talk: 6 % of the grip.
  EXPECT_NEAR(signals.preload_shear_axial_n, kPreloadRatio * kGripN, 0.06 * kGripN);
  EXPECT_NEAR(signals.tangential_load_n, 0.0, 0.06 * kGripN);
  // Three times the grip with the same locked-in shear: still no load, nothing fires.
  EXPECT_LT(stream.Run(0.6, 1.0,
                       [&](double t) {
                         SyntheticContact contact = grasp(t);
                         contact.grip_n = kGripN * (1.0 + 2.0 * std::min((t - 0.6) / 0.1, 1.0));
                         return contact;
                       }),
            0.0);
  EXPECT_NEAR(signals.tangential_load_n, 0.0, 0.06 * 3.0 * kGripN);
  // A load on top of the preload, up to the friction limit at 3x the grip: flagged in time.
  constexpr double kOnsetS = 1.0;
  const double first_s = stream.Run(kOnsetS, 1.5, [&](double) {
    SyntheticContact contact;
    contact.grip_n = 3.0 * kGripN;
    contact.load_axial_n = kPreloadRatio * kGripN + kFriction * 3.0 * kGripN;
    return contact;
  });
  ASSERT_GT(first_s, 0.0);
  EXPECT_LT(first_s - kOnsetS, kSlipLatencyLimitS);
}

/// A pad that seated with shear locked in rolls with load and squeeze (docs/controller.md): its
/// pressure centroid moves without any slip. With a shear estimate to check it against, such a move
/// is slip only while the load ratio is at the ratio cue's threshold (centroid_load_fraction); a
/// square pinch (no preload) keeps the centroid as a cue of its own.
TEST(SlipDetectorTest, CentroidMoveOnARollingPadIsSlipOnlyWithTheLoadAtTheFrictionLimit) {
  constexpr double kPreloadRatio = 0.4;
  constexpr double kRampS = 0.1;
  constexpr double kMoveS = 0.6;
  constexpr double kMovePitchPerS = 50.0;  // 1 pitch in 20 ms: well over centroid_shift_units
  // Centroid moves counted after kMoveS, and whether the preload was there to gate them.
  const auto centroid_flags = [&](const SlipDetectorConfig& config, double load_ratio) {
    SlipDetectorConfig cues = config;
    cues.vibration_enabled = false;  // the moving patch shakes each unit's shear; watch the centroid
    SlipDetector detector(cues);
    SyntheticTactile sensor({});
    int flags = 0;
    for (double t = 0.0; t < 1.0; t += kPeriodS) {
      SyntheticContact contact;
      contact.grip_n = 0.5 + (kGripN - 0.5) * std::min(t / kRampS, 1.0);
      contact.load_axial_n = kPreloadRatio * contact.grip_n;
      if (t >= kMoveS) {
        contact.load_axial_n = kPreloadRatio * kGripN + load_ratio * kGripN;
        contact.centre_row = 2.0 - kMovePitchPerS * std::min(t - kMoveS, 0.02);
      }
      const sensor::TactileState state = sensor.Frame(contact, t);
      const SlipSignals& signals = detector.Update(state, state.total_fn_n, kFriction, true, true);
      if (t >= kMoveS && signals.centroid_slip) ++flags;
    }
    EXPECT_GT(std::hypot(detector.signals().preload_shear_axial_n,
                         detector.signals().preload_shear_circumferential_n),
              cues.centroid_rolling_preload_n);
    return flags;
  };
  const SlipDetectorConfig defaults;
  // The pad rolls a pitch under a light load (ratio 0.1 against the cue's 0.45): no slip.
  EXPECT_EQ(centroid_flags(defaults, 0.1), 0);
  // The same move with the check off is read as slip, so the check is what silences it.
  SlipDetectorConfig unchecked = defaults;
  unchecked.centroid_load_fraction = 0.0;
  EXPECT_GT(centroid_flags(unchecked, 0.1), 0);
  // With the load at the friction limit the move is slip, and the centroid says so.
  EXPECT_GT(centroid_flags(defaults, kFriction), 0);
}

/// A noise burst (three times the noise on every unit for 0.3 s, as degraded_sensor stages it) is
/// not slip: the units off the contact show it too, and the vibration threshold follows them
/// (vibration_noise_reference). Without that reference the same burst is flagged.
TEST(SlipDetectorTest, NoiseBurstOnEveryUnitRaisesNoVibrationFlag) {
  const auto vibration_flags = [](bool reference) {
    SlipDetectorConfig config = SquarePinch();
    config.vibration_noise_reference = reference;
    Stream stream(config);
    stream.Run(0.0, 2.0, Hold);
    int flags = 0;
    stream.sensor.SetNoiseScale(3.0);
    for (double t = 2.0; t < 2.3; t += kPeriodS) {
      const sensor::TactileState state = stream.sensor.Frame(Hold(t), t);
      flags += stream.detector.Update(state, state.total_fn_n, kFriction, true, true).vibration_slip;
    }
    return flags;
  };
  const int with_reference = vibration_flags(true);
  const int without_reference = vibration_flags(false);
  std::printf("[ measure  ] 3x noise burst, 0.3 s: %d flagged frames with the noise reference, %d without\n",
              with_reference, without_reference);
  EXPECT_EQ(with_reference, 0);
  EXPECT_GT(without_reference, 0) << "the burst was meant to reach the vibration cue";
}

TEST(SlipDetectorTest, ContactThresholdFollowsTheReportedNormalNoise) {
  // The FEA's sensitivities behind the 12-bit divider: 0.17 N of Fn noise per unit, above the
  // 0.15 N contact threshold. With the noise in the state a unit needs 5 sigma (0.85 N) and the sum
  // 5 sigma of the summed noise (3.8 N), so noise alone is no contact; an 8 N contact (the grip such
  // a shear-blind readout holds) still is.
  SyntheticTactile::Options noisy;
  noisy.noise_fn_n = 0.17;
  noisy.report_noise = true;
  const auto count_contact_frames = [&](double contact_noise_sigmas, double grip_n) {
    SlipDetectorConfig config = SquarePinch();
    config.contact_noise_sigmas = contact_noise_sigmas;
    Stream stream(config, noisy);
    int contact_frames = 0;
    for (int frame = 0; frame < 1000; ++frame) {
      SyntheticContact contact;
      contact.grip_n = grip_n;
      const sensor::TactileState state = stream.sensor.Frame(contact, frame * kPeriodS);
      const SlipSignals& signals = stream.detector.Update(state, state.total_fn_n, kFriction, false, true);
      if (signals.in_contact) ++contact_frames;
    }
    EXPECT_NEAR(stream.detector.signals().contact_threshold_n, std::max(0.15, contact_noise_sigmas * 0.17),
                1e-12);
    return contact_frames;
  };
  const int noise_only = count_contact_frames(5.0, 0.0);
  const int noise_only_fixed_threshold = count_contact_frames(0.0, 0.0);
  const int real_contact = count_contact_frames(5.0, 8.0);
  std::printf(
      "[ measure ] noise alone read as contact: %d of 1000 frames at 5 sigma, %d at the fixed 0.15 N; "
      "an 8 N contact: %d\n",
      noise_only, noise_only_fixed_threshold, real_contact);
  EXPECT_EQ(noise_only, 0);
  EXPECT_GT(noise_only_fixed_threshold, 500);  // what the fixed threshold did
  EXPECT_EQ(real_contact, 1000);
}

TEST(SlipDetectorTest, ConfigValidationNamesFieldAndValue) {
  SlipDetectorConfig config;
  config.vibration_highpass_hz = 600.0;
  try {
    SlipDetector detector(config);
    FAIL() << "no error";
  } catch (const std::invalid_argument& error) {
    EXPECT_THAT(error.what(), HasSubstr("vibration_highpass_hz = 600"));
  }
}

TEST(FiltersTest, HighPassRejectsConstantsAndRampsAndPassesVibration) {
  constexpr double kRateHz = 1000.0;
  HighPassBiquad constant(40.0, kRateHz);
  constant.Reset(3.0);
  for (int i = 0; i < 100; ++i) EXPECT_NEAR(constant.Update(3.0), 0.0, 1e-12);
  HighPassBiquad ramp(40.0, kRateHz);
  ramp.Reset(0.0);
  double ramp_out = 0.0;
  for (int i = 0; i < 1000; ++i) ramp_out = ramp.Update(i * 0.001);  // 1 N/s, a fast arm motion
  EXPECT_LT(std::abs(ramp_out), 1e-4);
  HighPassBiquad tone(40.0, kRateHz);
  tone.Reset(0.0);
  double peak = 0.0;
  for (int i = 0; i < 1000; ++i) {
    const double out = tone.Update(std::sin(2.0 * std::numbers::pi * 200.0 * i / kRateHz));
    if (i > 500) peak = std::max(peak, std::abs(out));
  }
  EXPECT_NEAR(peak, 1.0, 0.05);
}

TEST(FiltersTest, DelayLineReturnsOlderSamples) {
  DelayLine<int, 4> line;
  for (int i = 1; i <= 6; ++i) line.Push(i);
  EXPECT_EQ(line.size(), 4);
  EXPECT_EQ(line.Delayed(0), 6);
  EXPECT_EQ(line.Delayed(3), 3);
  line.Clear();
  EXPECT_EQ(line.size(), 0);
}

}  // namespace
}  // namespace graspbed::controller
