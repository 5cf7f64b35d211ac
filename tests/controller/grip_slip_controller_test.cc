#include "controller/grip_slip_controller.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <stdexcept>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tests/controller/synthetic_tactile.h"
#include "tests/support/error_of.h"

namespace graspbed::controller {
namespace {

using test_support::HandPlant;
using test_support::SyntheticContact;
using test_support::SyntheticTactile;
using ::testing::HasSubstr;

constexpr double kPeriodS = 0.001;                 // 1 kHz control and sensor rate
constexpr double kGravity = 9.81;                  // [m/s^2]
constexpr double kSlipLatencyLimitS = 0.030;       // detection target, well under the human 60-90 ms
constexpr double kGripTolN = 0.25;                 // force-loop tracking tolerance in a steady hold
constexpr double kCeilingTolN = 0.3;               // ceiling overshoot allowed (noise + loop transient)
constexpr double kSlowSlideLatencyLimitS = 0.100;  // slide seen only by centroid travel, light grip
constexpr double kAddedMassSlipLimitM = 5e-3;      // slide allowed after a load step of 2x the friction limit
constexpr double kLowFrictionSlipLimitM = 10e-3;
constexpr double kVibrationNoiseSigmas = 2.5;  // vibration floor from the readout's noise, when switched on
                                               // // slide allowed while a 2x friction overestimate is learned

/// Controller + plant + sensor at 1 kHz, with the tangential load given as a function of time.
class ClosedLoop {
 public:
  ClosedLoop(const GripSlipConfig& config, const HandPlant::Options& plant,
             const SyntheticTactile::Options& sensor)
      : controller(config), plant(plant), sensor(sensor) {}

  /// Runs until `end_s`; `load_n(t)` is the axial tangential load; `each` sees every tick.
  void RunUntil(double end_s, const std::function<double(double)>& load_n,
                const std::function<void(double)>& each = nullptr) {
    while (time_s < end_s - 1e-9) {
      time_s += kPeriodS;
      plant.Step(command, load_n(time_s), kPeriodS);
      const sensor::TactileState state = sensor.Frame(plant.Contact(), time_s);
      command = controller.Update(state, {}, time_s);
      max_grip_n = std::max(max_grip_n, plant.grip_n());
      if (controller.telemetry().slip_detected && first_slip_s < 0.0) first_slip_s = time_s;
      if (controller.telemetry().slip_events > events_seen) {
        events_seen = controller.telemetry().slip_events;
        const SlipSignals& signals = controller.diagnostics().signals;
        events_by_cue[0] += signals.ratio_slip;
        events_by_cue[1] += signals.vibration_slip;
        events_by_cue[2] += signals.centroid_slip;
      }
      if (each) each(time_s);
    }
  }

  /// Closes on the resting object, lifts it once the grip holds (the load ramps to `load_n` in
  /// 0.3 s) and lets the grip settle until `settle_until_s`; then forgets any slip of the plant.
  void Grasp(double load_n, double settle_until_s = 1.0) {
    controller.SetIntent(GraspIntent::kClose);
    double lift_start_s = -1.0;
    RunUntil(settle_until_s, [&](double t) {
      if (lift_start_s < 0.0 && std::string(controller.telemetry().phase) == "holding")
        lift_start_s = t + 0.1;
      return lift_start_s < 0.0 ? 0.0 : load_n * std::clamp((t - lift_start_s) / 0.3, 0.0, 1.0);
    });
    if (load_n > 0.0 && (lift_start_s < 0.0 || lift_start_s + 0.3 > settle_until_s)) {
      ADD_FAILURE() << "grasp not settled in time";
    }
    plant.ClearSlip();
    first_slip_s = -1.0;
  }

  GripSlipController controller;
  HandPlant plant;
  SyntheticTactile sensor;
  hand::HandCommand command;
  double time_s = 0.0;
  double max_grip_n = 0.0;
  double first_slip_s = -1.0;
  int events_seen = 0;
  int events_by_cue[3] = {0, 0, 0};  ///< slip events in which the ratio, vibration, centroid cue fired

  /// "ratio r, vibration v, centroid c" for messages.
  std::string Cues() const {
    return "ratio " + std::to_string(events_by_cue[0]) + ", vibration " + std::to_string(events_by_cue[1]) +
           ", centroid " + std::to_string(events_by_cue[2]);
  }
};

GripSlipConfig DefaultConfig() { return GripSlipConfig{}; }

// The errors refused here are std::invalid_argument; one of another type fails the test.
std::string ErrorOf(const std::function<void()>& action) {
  return graspbed::test_support::ErrorOf<std::invalid_argument>(action);
}

TEST(GripSlipControllerTest, ClosesUntilContactThenLoadsToInitialGrip) {
  ClosedLoop loop(DefaultConfig(), {}, {});
  loop.controller.SetIntent(GraspIntent::kClose);
  double contact_s = -1.0;
  double loading_s = -1.0;
  double peak_loading_grip_n = 0.0;
  loop.RunUntil(
      0.8, [](double) { return 0.0; },
      [&](double t) {
        if (std::string(loop.controller.telemetry().phase) == "loading") {
          peak_loading_grip_n = std::max(peak_loading_grip_n, loop.plant.grip_n());
        }
        if (contact_s < 0.0 &&
            loop.plant.grip_n() > loop.controller.config().slip.contact_unit_threshold_n * 2.0) {
          contact_s = t;
        }
        if (loading_s < 0.0 && std::string(loop.controller.telemetry().phase) == "loading") loading_s = t;
      });
  ASSERT_GT(contact_s, 0.0) << "the plant never touched";
  ASSERT_GT(loading_s, 0.0) << "contact never detected";
  // Before the finger touched, noise alone never looked like contact.
  EXPECT_GE(loading_s, contact_s - 0.003);
  EXPECT_LT(loading_s - contact_s, 0.010);
  EXPECT_STREQ(loop.controller.telemetry().phase, "holding");
  EXPECT_NEAR(peak_loading_grip_n, loop.controller.config().initial_grip_n, kGripTolN);
  // Nothing to carry yet: the hold relaxes to the minimum grip.
  EXPECT_NEAR(loop.plant.grip_n(), loop.controller.config().min_grip_n, kGripTolN);
  EXPECT_EQ(loop.controller.telemetry().slip_events, 0);
}

TEST(GripSlipControllerTest, NoContactFromNoiseWhileClosingInAir) {
  HandPlant::Options plant;
  plant.start_gap = 1.0;            // object far away
  plant.closing_speed_per_s = 0.1;  // never reached in this test
  ClosedLoop loop(DefaultConfig(), plant, {});
  loop.controller.SetIntent(GraspIntent::kClose);
  loop.RunUntil(5.0, [](double) { return 0.0; });
  EXPECT_STREQ(loop.controller.telemetry().phase, "closing");
  EXPECT_DOUBLE_EQ(loop.command.grip_effort, loop.controller.config().close_effort);
}

TEST(GripSlipControllerTest, HoldCouplesGripToLoadOverFrictionTimesMargin) {
  const GripSlipConfig config = DefaultConfig();
  ClosedLoop loop(config, {}, {});
  const double load_n = 1.5;
  loop.Grasp(load_n, 2.0);
  const double expected = load_n / config.friction_initial * config.safety_margin;
  EXPECT_NEAR(loop.controller.telemetry().grip_target_n, expected, 0.1 * expected);
  EXPECT_NEAR(loop.plant.grip_n(), loop.controller.telemetry().grip_target_n, kGripTolN);
  EXPECT_FALSE(loop.plant.sliding());
  EXPECT_EQ(loop.controller.telemetry().slip_events, 0);
}

/// False slips in a long static hold, at the default noise and at twice it.
TEST(GripSlipControllerTest, NoFalseSlipInLongStaticHold) {
  for (const double noise_scale : {1.0, 2.0}) {
    SyntheticTactile::Options sensor;
    sensor.noise_fn_n *= noise_scale;
    sensor.noise_ft_n *= noise_scale;
    sensor.seed = 7;
    ClosedLoop loop(DefaultConfig(), {}, sensor);
    loop.Grasp(0.5, 1.0);
    const int events_after_grasp = loop.controller.telemetry().slip_events;
    int detected_ticks = 0;
    int cue_ticks[3] = {0, 0, 0};
    constexpr double kHoldS = 60.0;
    loop.RunUntil(
        1.0 + kHoldS, [](double) { return 0.5; },
        [&](double) {
          if (loop.controller.telemetry().slip_detected) ++detected_ticks;
          const SlipSignals& signals = loop.controller.diagnostics().signals;
          cue_ticks[0] += signals.ratio_slip;
          cue_ticks[1] += signals.vibration_slip;
          cue_ticks[2] += signals.centroid_slip;
        });
    std::printf("[ measure  ] flagged ticks by cue: ratio %d, vibration %d, centroid %d\n", cue_ticks[0],
                cue_ticks[1], cue_ticks[2]);
    const int false_events = loop.controller.telemetry().slip_events - events_after_grasp;
    std::printf(
        "[ measure  ] noise x%.0f (fn %.3f N, ft %.3f N per unit): %d false slip events, %d flagged ticks in "
        "%.0f s static hold; vibration noise rms %.4f N, threshold %.4f N\n",
        noise_scale, sensor.noise_fn_n, sensor.noise_ft_n, false_events, detected_ticks, kHoldS,
        loop.controller.diagnostics().signals.noise_rms_n,
        loop.controller.diagnostics().signals.vibration_threshold_n);
    EXPECT_EQ(events_after_grasp, 0) << "noise x" << noise_scale;
    EXPECT_EQ(false_events, 0) << "noise x" << noise_scale;
    EXPECT_EQ(detected_ticks, 0) << "noise x" << noise_scale;
    EXPECT_FALSE(loop.plant.sliding());
  }
}

/// Noise-aware cues (vibration_noise_sigmas): with the readout's own noise figure in the state,
/// the vibration threshold's floor rises with the sensor's noise above the fixed 0.03 N and the
/// centroid's noise is the sensor's normal-force noise. At the noise of realistic readout chains
/// (tests/sensor/sensor_profile_test.cc: divider_12bit with the paper's sensitivities, inamp_16bit
/// with the FEA's) and at the noisy FEA case (FEA sensitivities, 0.5 Ohm channel noise, 16-bit ADC), a minute
/// of static hold raises at most one false slip, and the slips of the tests above are still flagged.
TEST(GripSlipControllerTest, NoiseAwareCuesUnderRealisticProfileNoise) {
  struct Level {
    const char* name;
    double fn_n, ft_n;
  };
  // Third: the FEA's sensitivities behind 0.5 Ohm of channel noise (the noisy FEA case; no shipped
  // profile is this noisy), where the noise, not the fixed floor, has to set the threshold.
  for (const Level level :
       {Level{"divider_12bit, paper", 0.0103, 0.0138}, Level{"inamp_16bit, fea", 0.00083, 0.0044},
        Level{"0.5 Ohm, fea", 0.031, 0.165}}) {
    // Without the noise figure in the state (today's learned-noise cues), with it (the centroid's
    // noise from the readout's figures), and with the vibration floor from it too.
    for (const int mode : {0, 1, 2}) {
      const double sigmas = mode == 2 ? kVibrationNoiseSigmas : 0.0;
      SCOPED_TRACE(std::string(level.name) + " mode " + std::to_string(mode));
      SyntheticTactile::Options sensor;
      sensor.noise_fn_n = level.fn_n;
      sensor.noise_ft_n = level.ft_n;
      sensor.report_noise = mode > 0;
      sensor.seed = 7;
      GripSlipConfig config = DefaultConfig();
      config.slip.vibration_noise_sigmas = sigmas;

      // A minute of static hold.
      ClosedLoop hold(config, {}, sensor);
      hold.Grasp(0.5, 1.0);
      const int events_after_grasp = hold.controller.telemetry().slip_events;
      constexpr double kHoldS = 60.0;
      hold.RunUntil(1.0 + kHoldS, [](double) { return 0.5; });
      const int false_events = hold.controller.telemetry().slip_events - events_after_grasp;
      EXPECT_EQ(events_after_grasp, 0);
      EXPECT_LE(false_events, 1) << "more than one false slip per minute held";
      EXPECT_FALSE(hold.plant.dropped());

      // Added mass (load 0.5 -> 1.5 N at mu 0.5). The object is grasped with its 0.5 N already on,
      // which preload_reference would take as locked-in preload (docs/controller.md, "Shear
      // preload"): here the square pinch of this plant, load from zero shear.
      HandPlant::Options slippery;
      slippery.friction = 0.5;
      GripSlipConfig square = config;
      square.slip.preload_reference = false;
      ClosedLoop added(square, slippery, sensor);
      added.Grasp(0.5, 1.0);
      added.RunUntil(2.0, [](double t) { return t < 1.2 ? 0.5 : 1.5; });
      ASSERT_GT(added.plant.slip_onset_s(), 0.0);
      ASSERT_GT(added.first_slip_s, 0.0) << "added mass not flagged";
      const double added_latency_s = added.first_slip_s - added.plant.slip_onset_s();
      EXPECT_LT(added_latency_s, kSlipLatencyLimitS);
      EXPECT_FALSE(added.plant.dropped());

      // Low friction (0.25 against 0.5), lifted in 0.5 s and in 0.2 s.
      double low_latency_s[2] = {-1.0, -1.0};
      bool low_dropped[2] = {false, false};
      for (int fast = 0; fast < 2; ++fast) {
        HandPlant::Options low;
        low.friction = 0.25;
        ClosedLoop lift(config, low, sensor);
        lift.Grasp(0.0, 0.5);
        const double ramp_s = fast ? 0.2 : 0.5;
        lift.RunUntil(3.0, [&](double t) { return std::clamp((t - 0.5) / ramp_s, 0.0, 1.0) * 1.2; });
        ASSERT_GT(lift.plant.slip_onset_s(), 0.0);
        ASSERT_GT(lift.first_slip_s, 0.0) << "low-friction slide not flagged";
        low_latency_s[fast] = lift.first_slip_s - lift.plant.slip_onset_s();
        low_dropped[fast] = lift.plant.dropped();
      }
      // Without a noise figure at the noisiest level the vibration cue is the only one left to see
      // this slide, and one cue episode gets one slip step (a vibration cue held up is also the
      // step's own ringing, docs/controller.md): the slide outlasts the floor's rise and the 0.5 s
      // lift is dropped too. Every realistic profile reports its noise figure (mode > 0).
      if (mode > 0 || level.ft_n < 0.1) {
        EXPECT_FALSE(low_dropped[0]) << "the 0.5 s lift was dropped";
      }
      // With the noise figure the centroid's noise is the normal-force noise, not the (up to 5x
      // larger) shear noise: at the noisy FEA level that holds the 0.2 s lift the learned noise drops.
      if (mode > 0) {
        EXPECT_FALSE(low_dropped[1]) << "the 0.2 s lift was dropped";
      }
      std::printf(
          "[ measure  ] %s noise (fn %.4f, ft %.4f N), %s: %d false slips in %.0f s held (vibration "
          "threshold "
          "%.4f N); added mass flagged after %.0f ms; low friction flagged after %.0f ms (0.5 s lift, %s), "
          "%.0f ms (0.2 s lift, %s)\n",
          level.name, level.fn_n, level.ft_n,
          mode == 0 ? "learned noise only"
                    : (mode == 1 ? "noise figure, centroid" : "noise figure, centroid + vibration floor"),
          false_events, kHoldS, hold.controller.diagnostics().signals.vibration_threshold_n,
          added_latency_s * 1e3, low_latency_s[0] * 1e3, low_dropped[0] ? "dropped" : "held",
          low_latency_s[1] * 1e3, low_dropped[1] ? "dropped" : "held");
    }
  }
}

/// Arm motion: the wrist accelerates the held object (lift, carry, shake), so the inertial load
/// changes smoothly by up to +-70 % of the weight. Friction is ample, so nothing slips.
TEST(GripSlipControllerTest, NoFalseSlipDuringArmMotion) {
  const double mass_kg = 0.1;
  const double weight_per_finger_n = mass_kg * kGravity / 2.0;
  ClosedLoop loop(DefaultConfig(), {}, {});
  loop.Grasp(weight_per_finger_n, 1.0);
  double max_ratio_of_load = 0.0;
  // Lift/carry profile: 1.5 Hz swings of +-7 m/s^2, then a 4 Hz shake of +-5 m/s^2.
  const auto load = [&](double t) {
    const double tm = t - 1.0;
    const double acceleration = tm < 6.0 ? 7.0 * std::sin(2.0 * std::numbers::pi * 1.5 * tm)
                                         : 5.0 * std::sin(2.0 * std::numbers::pi * 4.0 * tm);
    return mass_kg * (kGravity + acceleration) / 2.0;
  };
  loop.RunUntil(11.0, load, [&](double t) {
    max_ratio_of_load = std::max(max_ratio_of_load, load(t) / weight_per_finger_n);
  });
  std::printf("[ measure  ] arm motion: load up to %.2f x weight, %d slip events (%s), plant slid %.3f mm\n",
              max_ratio_of_load, loop.controller.telemetry().slip_events, loop.Cues().c_str(),
              loop.plant.slip_distance_m() * 1e3);
  EXPECT_GT(max_ratio_of_load, 1.6);
  EXPECT_EQ(loop.controller.telemetry().slip_events, 0);
  EXPECT_EQ(loop.plant.slip_distance_m(), 0.0);
}

/// Sudden added mass: the load jumps beyond what the grip holds; the object slides with stick-slip.
TEST(GripSlipControllerTest, DetectsSlipFromAddedMassWithinLatencyAndStopsIt) {
  HandPlant::Options plant;
  plant.friction = 0.5;  // the estimate is right; the load step outruns the grip
  ClosedLoop loop(DefaultConfig(), plant, {});
  loop.Grasp(0.5, 1.0);
  ASSERT_EQ(loop.controller.telemetry().slip_events, 0);
  const double grip_before_n = loop.plant.grip_n();
  loop.RunUntil(2.0, [](double t) { return t < 1.2 ? 0.5 : 1.5; });
  ASSERT_GT(loop.plant.slip_onset_s(), 0.0) << "the load step did not make the object slip";
  ASSERT_GT(loop.first_slip_s, 0.0) << "slip not detected";
  const double latency_s = loop.first_slip_s - loop.plant.slip_onset_s();
  std::printf(
      "[ measure  ] added mass: slip detected %.1f ms after onset, slid %.2f mm, grip %.2f -> %.2f N\n",
      latency_s * 1e3, loop.plant.slip_distance_m() * 1e3, grip_before_n, loop.plant.grip_n());
  EXPECT_GE(latency_s, 0.0);
  EXPECT_LT(latency_s, kSlipLatencyLimitS);
  EXPECT_FALSE(loop.plant.sliding()) << "the slip response did not stop the slip";
  EXPECT_GT(loop.plant.grip_n(), 1.5 / plant.friction);
  EXPECT_LT(loop.plant.slip_distance_m(), kAddedMassSlipLimitM);
}

/// Low friction: the object is slipperier than the estimate (0.25 against 0.5). Neither the ratio
/// cue (it compares against the wrong estimate) nor the vibration cue (the plant's 30 % stick-slip
/// is below the noise at 1.5 N of grip) can see the slide; the contact's travel reveals it, the
/// estimate is learned from the ratio at slip, and the grasp then holds with no further slips.
/// The lift takes 0.5 s; a 0.2 s lift outruns the slip response (next test).
TEST(GripSlipControllerTest, LearnsLowFrictionFromSlipAndThenHolds) {
  HandPlant::Options plant;
  plant.friction = 0.25;
  const GripSlipConfig config = DefaultConfig();
  ClosedLoop loop(config, plant, {});
  // Grasp with no load (object resting), then lift: load ramps to 1.2 N in 0.5 s.
  loop.Grasp(0.0, 0.5);
  const auto load = [](double t) { return std::clamp((t - 0.5) / 0.5, 0.0, 1.0) * 1.2; };
  double max_slid_m = 0.0;
  const auto watch = [&](double) { max_slid_m = std::max(max_slid_m, loop.plant.slip_distance_m()); };
  loop.RunUntil(1.5, load, watch);
  ASSERT_GT(loop.plant.slip_onset_s(), 0.0) << "the lift did not make the object slip";
  ASSERT_GT(loop.first_slip_s, 0.0) << "the slide was never flagged";
  ASSERT_FALSE(loop.plant.dropped()) << "the object slid out of the grasp";
  const double latency_s = loop.first_slip_s - loop.plant.slip_onset_s();
  const int events_after_learning = loop.controller.telemetry().slip_events;
  std::printf(
      "[ measure  ] low friction %.2f (estimate %.2f), 0.5 s lift: detected %.1f ms after onset (%s), "
      "friction learned %.3f, %d slip events, slid %.2f mm, grip %.2f N for %.2f N needed\n",
      plant.friction, config.friction_initial, latency_s * 1e3, loop.Cues().c_str(),
      loop.controller.telemetry().friction_estimate, events_after_learning, max_slid_m * 1e3,
      loop.plant.grip_n(), 1.2 / plant.friction);
  EXPECT_GE(latency_s, 0.0);
  EXPECT_LT(latency_s, kSlowSlideLatencyLimitS);
  EXPECT_LE(loop.controller.telemetry().friction_estimate, plant.friction + 0.05) << "estimate not lowered";
  EXPECT_FALSE(loop.plant.sliding());
  loop.RunUntil(10.0, load, watch);
  EXPECT_EQ(loop.controller.telemetry().slip_events, events_after_learning)
      << "slips after the estimate was learned";
  EXPECT_FALSE(loop.plant.sliding());
  EXPECT_FALSE(loop.plant.dropped());
  EXPECT_LT(max_slid_m, kLowFrictionSlipLimitM);
  EXPECT_GT(loop.plant.grip_n(), 1.2 / plant.friction) << "holding without the grip the load needs";
}

/// The limit of the previous case, moved: the same object lifted in 0.2 s accelerates (20 mm in about
/// 130 ms) before the contact's travel is flagged; it used to be dropped, the grip raised in 40 ms
/// steps (slip_refractory_s). With the slip floor rising while the cues keep reporting slip
/// (slip_grip_rate_n_per_s) the grip catches up and the object is held.
TEST(GripSlipControllerTest, FastLiftOfAnObjectWithHalfTheEstimatedFrictionIsHeldByTheSlipRamp) {
  HandPlant::Options plant;
  plant.friction = 0.25;
  ClosedLoop loop(DefaultConfig(), plant, {});
  loop.Grasp(0.0, 0.5);
  double dropped_at_s = -1.0;
  double max_slid_m = 0.0;
  loop.RunUntil(
      1.5, [](double t) { return std::clamp((t - 0.5) / 0.2, 0.0, 1.0) * 1.2; },
      [&](double t) {
        if (dropped_at_s < 0.0 && loop.plant.dropped()) dropped_at_s = t;
        max_slid_m = std::max(max_slid_m, loop.plant.slip_distance_m());
      });
  ASSERT_GT(loop.first_slip_s, 0.0) << "the slide was never flagged";
  std::printf("[ measure  ] low friction 0.25, 0.2 s lift: flagged %.1f ms after onset, slid %.1f mm, %s\n",
              (loop.first_slip_s - loop.plant.slip_onset_s()) * 1e3, max_slid_m * 1e3,
              loop.plant.dropped() ? "dropped" : "held");
  EXPECT_FALSE(loop.plant.dropped());
  // Without the ramp (the steps alone) it is still dropped: the ramp, not the cues, moved the limit.
  GripSlipConfig steps_only = DefaultConfig();
  steps_only.slip_grip_rate_n_per_s = 0.0;
  ClosedLoop steps(steps_only, plant, {});
  steps.Grasp(0.0, 0.5);
  steps.RunUntil(1.5, [](double t) { return std::clamp((t - 0.5) / 0.2, 0.0, 1.0) * 1.2; });
  EXPECT_TRUE(steps.plant.dropped());
}

/// A task ceiling below what a pull needs: while the pull lasts the object slides through the
/// fingers (a long object: the plant's drop distance is 300 mm) with the grip pressed against the
/// ceiling and never beyond it; after the pull the object is held again.
TEST(GripSlipControllerTest, CeilingHonouredEvenWhileSlipping) {
  HandPlant::Options plant;
  plant.friction = 0.3;
  plant.drop_distance_m = 0.3;
  // A motor 20 % stronger than the controller's feed-forward assumes (20 N): the effort cap alone
  // would allow 3.6 N, so the force loop has to keep the grip at the ceiling.
  plant.stall_force_n = 24.0;
  ClosedLoop loop(DefaultConfig(), plant, {});
  constexpr double kCeilingN = 3.0;
  loop.controller.SetGripCeiling(kCeilingN);
  loop.Grasp(0.2, 1.0);
  double max_target_n = 0.0;
  double max_grip_during_pull_n = 0.0;
  // The 0.3 s pull of 1.0 N needs 1.0 / 0.3 = 3.3 N of grip: more than the fragile object may take.
  const auto load = [](double t) { return t < 1.2 ? 0.2 : (t < 1.5 ? 1.0 : 0.5); };
  loop.RunUntil(3.0, load, [&](double t) {
    max_target_n = std::max(max_target_n, loop.controller.telemetry().grip_target_n);
    if (t >= 1.2 && t < 1.5) max_grip_during_pull_n = std::max(max_grip_during_pull_n, loop.plant.grip_n());
  });
  std::printf(
      "[ measure  ] ceiling %.1f N: peak grip %.2f N (pull %.2f N), peak target %.2f N, %d slip events, "
      "slid %.1f mm, held %d, grip at end %.2f N\n",
      kCeilingN, loop.max_grip_n, max_grip_during_pull_n, max_target_n,
      loop.controller.telemetry().slip_events, loop.plant.slip_distance_m() * 1e3, !loop.plant.dropped(),
      loop.plant.grip_n());
  ASSERT_FALSE(loop.plant.dropped()) << "the ceiling check needs the object in the hand";
  EXPECT_GT(loop.controller.telemetry().slip_events, 0);
  EXPECT_GT(loop.plant.slip_distance_m(), 1e-3) << "the pull should exceed what the ceiling can hold";
  EXPECT_FALSE(loop.plant.sliding()) << "held again after the pull";
  EXPECT_LE(max_target_n, kCeilingN + 1e-9);
  EXPECT_LE(loop.max_grip_n, kCeilingN + kCeilingTolN);
  // The grip did press against the ceiling, so the check above could fail.
  EXPECT_GE(max_grip_during_pull_n, kCeilingN - kCeilingTolN);
  EXPECT_GE(loop.command.grip_effort, 0.0);
}

/// max_grip_n caps the grip even when the task allows more. The load (0.65 N at friction 0.2) needs
/// 3.25 N, the coupled target with its margin 4.55 N: the cap of 4 N binds, and the object is held.
TEST(GripSlipControllerTest, MaxGripParameterIsTheOverallCeiling) {
  GripSlipConfig config = DefaultConfig();
  config.max_grip_n = 4.0;
  HandPlant::Options plant;
  plant.friction = 0.2;
  ClosedLoop loop(config, plant, {});
  loop.controller.SetGripCeiling(8.0);  // the task allows more; the overall ceiling wins
  loop.Grasp(0.2, 1.0);
  double max_target_n = 0.0;
  loop.RunUntil(
      4.0, [](double t) { return t < 1.2 ? 0.2 : 0.2 + 0.45 * std::clamp((t - 1.2) / 0.5, 0.0, 1.0); },
      [&](double) { max_target_n = std::max(max_target_n, loop.controller.telemetry().grip_target_n); });
  std::printf(
      "[ measure  ] max_grip 4 N: peak grip %.2f N, peak target %.2f N, slid %.2f mm, held %d, grip at end "
      "%.2f N\n",
      loop.max_grip_n, max_target_n, loop.plant.slip_distance_m() * 1e3, !loop.plant.dropped(),
      loop.plant.grip_n());
  EXPECT_DOUBLE_EQ(loop.controller.diagnostics().ceiling_n, 4.0);
  EXPECT_FALSE(loop.plant.dropped());
  EXPECT_FALSE(loop.plant.sliding());
  EXPECT_LE(max_target_n, 4.0 + 1e-9);
  EXPECT_GE(max_target_n, 4.0 - 1e-9) << "the cap never bound, so the check above could not fail";
  EXPECT_LE(loop.max_grip_n, 4.0 + kCeilingTolN);
}

/// A load beyond what the ceiling holds by the friction estimate keeps the ratio cue up, with the
/// target at the ceiling, while the (grippier) object does not move: the flag rises once, then
/// stops counting as slip after slip_refractory_s, so a later slip would be a new flag.
TEST(GripSlipControllerTest, RatioCueHeldAtTheCeilingStopsCountingAsSlip) {
  HandPlant::Options plant;
  plant.friction = 1.2;  // the object holds: no slip whatever the estimate says
  ClosedLoop loop(DefaultConfig(), plant, {});
  constexpr double kCeilingN = 3.0;
  constexpr double kOnsetS = 1.2;
  loop.controller.SetGripCeiling(kCeilingN);
  loop.Grasp(0.2, 1.0);
  int ratio_up_ticks = 0;
  int flagged_ticks = 0;
  int flagged_late_ticks = 0;  // flagged with the ratio cue up longer than the refractory time
  double ratio_rise_s = -1.0;
  // 1.8 N at 3 N is a load ratio of 0.6, over the cue's 0.9 x 0.5.
  loop.RunUntil(
      2.5, [](double t) { return t < kOnsetS ? 0.2 : 1.8; },
      [&](double t) {
        const bool ratio_up = loop.controller.diagnostics().signals.ratio_slip;
        if (ratio_up && ratio_rise_s < 0.0) ratio_rise_s = t;
        ratio_up_ticks += ratio_up;
        const bool flagged = loop.controller.telemetry().slip_detected;
        flagged_ticks += flagged;
        if (flagged && ratio_rise_s > 0.0 &&
            t - ratio_rise_s > loop.controller.config().slip_refractory_s + 0.01)
          ++flagged_late_ticks;
      });
  std::printf("[ measure  ] ratio cue up %d ms, flagged %d ms, slid %.2f mm, target %.2f N\n", ratio_up_ticks,
              flagged_ticks, loop.plant.slip_distance_m() * 1e3, loop.controller.telemetry().grip_target_n);
  ASSERT_FALSE(loop.plant.dropped());
  EXPECT_LT(loop.plant.slip_distance_m(), 0.5e-3) << "the object was meant to hold";
  EXPECT_DOUBLE_EQ(loop.controller.telemetry().grip_target_n, kCeilingN);
  // The cue stayed up for most of the 1.3 s, so the check below could fail.
  EXPECT_GT(ratio_up_ticks, 1000);
  EXPECT_GT(flagged_ticks, 0) << "the load's rise is still flagged";
  EXPECT_EQ(flagged_late_ticks, 0);
}

/// A load that hovers at the ratio cue's threshold with the target at the ceiling (pouring into a
/// held cup): the cue falls and rises again every 80 ms, past its hysteresis, while the (grippier)
/// object does not move. Its first rise, with the target still below the ceiling, is a flag; at the
/// ceiling the cue counts no more, so the crossings after it raise none, whatever the rearm window.
/// With a count window at the ceiling (ratio_ceiling_count_s 40 ms), each rise soon after a fall
/// continues the episode (still one flag); with ratio_ceiling_rearm_s 0 too, every rise is a flag.
TEST(GripSlipControllerTest, ALoadHoveringAtTheThresholdAtTheCeilingIsOneFlag) {
  constexpr double kCountS = 0.04;
  const auto flag_rises = [](double count_s, double rearm_s, int* ratio_rises) {
    HandPlant::Options plant;
    plant.friction = 1.2;  // the object holds: no slip whatever the estimate says
    GripSlipConfig config = DefaultConfig();
    config.ratio_ceiling_count_s = count_s;
    config.ratio_ceiling_rearm_s = rearm_s;
    ClosedLoop loop(config, plant, {});
    loop.controller.SetGripCeiling(3.0);
    loop.Grasp(0.2, 1.0);
    int rises = 0;
    bool was_flagged = false;
    bool ratio_was_up = false;
    *ratio_rises = 0;
    // At 3 N the cue rises above a load of 1.35 N (0.9 x 0.5 x 3) and falls below 0.85 of that.
    loop.RunUntil(
        2.5,
        [](double t) {
          if (t < 1.2) return 0.2;
          return static_cast<int>((t - 1.2) / 0.08) % 2 == 0 ? 1.8 : 0.6;
        },
        [&](double) {
          const bool flagged = loop.controller.telemetry().slip_detected;
          rises += flagged && !was_flagged;
          was_flagged = flagged;
          const bool ratio_up = loop.controller.diagnostics().signals.ratio_slip;
          *ratio_rises += ratio_up && !ratio_was_up;
          ratio_was_up = ratio_up;
        });
    EXPECT_FALSE(loop.plant.dropped());
    EXPECT_LT(loop.plant.slip_distance_m(), 0.5e-3) << "the object was meant to hold";
    return rises;
  };
  const GripSlipConfig defaults = DefaultConfig();
  int ratio_rises = 0;
  const int flags = flag_rises(defaults.ratio_ceiling_count_s, defaults.ratio_ceiling_rearm_s, &ratio_rises);
  std::printf("[ measure  ] ratio cue rose %d times, flag rose %d times\n", ratio_rises, flags);
  // The cue did cross again and again, so one flag is the ceiling's hold at work.
  EXPECT_GE(ratio_rises, 5);
  EXPECT_EQ(flags, 1);
  int rises = 0;
  EXPECT_EQ(flag_rises(defaults.ratio_ceiling_count_s, 0.0, &rises), 1);
  EXPECT_EQ(flag_rises(kCountS, defaults.ratio_ceiling_rearm_s, &rises), 1);
  EXPECT_GE(rises, 5);
  EXPECT_EQ(flag_rises(kCountS, 0.0, &rises), rises);
}

/// slip_flag_hold_s: the reported flag stays up until the cues have counted no slip for the hold
/// time, so a cue flickering about its threshold is one flag per episode, and it is up whenever a
/// cue counts. A vibration cue set to fire on the readout's own noise (factor 1, one frame to
/// confirm; the other cues off) flickers frame by frame.
TEST(GripSlipControllerTest, TheSlipFlagIsHeldThroughACueFlickeringWithinAnEpisode) {
  struct Count {
    int flag_rises = 0;
    int cue_episodes = 0;  ///< cue rises after at least the hold time without it
    int short_gaps = 0;    ///< cue rises after less than the hold time without it
    int flag_down_with_cue = 0;
    int flag_up_late = 0;  ///< frames flagged more than the hold time after the cue was last up
  };
  const auto run = [](double hold_s) {
    GripSlipConfig config = DefaultConfig();
    config.slip.vibration_factor = 1.0;
    config.slip.vibration_confirm_frames = 1;
    config.slip.ratio_enabled = false;
    config.slip.centroid_enabled = false;
    config.slip_flag_hold_s = hold_s;
    SyntheticTactile::Options sensor;
    sensor.seed = 11;
    ClosedLoop loop(config, {}, sensor);
    loop.controller.SetGripCeiling(4.0);
    loop.Grasp(0.3, 1.0);
    Count count;
    bool was_flagged = loop.controller.telemetry().slip_detected;
    double cue_last_s = -1.0;
    loop.RunUntil(
        3.0, [](double) { return 0.3; },
        [&](double t) {
          const bool cue = loop.controller.diagnostics().signals.vibration_slip;
          const bool flagged = loop.controller.telemetry().slip_detected;
          if (cue && !flagged) ++count.flag_down_with_cue;
          if (cue && cue_last_s >= 0.0 && t - cue_last_s > 1.5 * kPeriodS) {
            ++(t - cue_last_s > hold_s + 0.5 * kPeriodS ? count.cue_episodes : count.short_gaps);
          }
          if (cue) cue_last_s = t;
          if (flagged && !cue && (cue_last_s < 0.0 || t - cue_last_s > hold_s + 0.5 * kPeriodS))
            ++count.flag_up_late;
          count.flag_rises += flagged && !was_flagged;
          was_flagged = flagged;
        });
    return count;
  };
  const double hold_s = DefaultConfig().slip_flag_hold_s;
  ASSERT_GE(hold_s, 2.0 * kPeriodS);
  const Count held = run(hold_s);
  std::printf("[ measure  ] hold %.0f ms: cue episodes %d, rises within one %d, flag rises %d\n",
              hold_s * 1e3, held.cue_episodes, held.short_gaps, held.flag_rises);
  EXPECT_GE(held.short_gaps, 20) << "the cue was meant to flicker";
  EXPECT_EQ(held.flag_down_with_cue, 0);
  EXPECT_EQ(held.flag_up_late, 0);
  // The first rise of the window may continue an episode begun before it.
  EXPECT_LE(held.flag_rises, held.cue_episodes + 1);
  EXPECT_GE(held.flag_rises, held.cue_episodes);
  const Count frame_by_frame = run(0.0);
  EXPECT_EQ(frame_by_frame.flag_down_with_cue, 0);
  EXPECT_EQ(frame_by_frame.flag_up_late, 0);
  EXPECT_GE(frame_by_frame.flag_rises, frame_by_frame.cue_episodes + frame_by_frame.short_gaps);
  EXPECT_GT(frame_by_frame.flag_rises, held.flag_rises);
}

/// The closing impact's shear, coupled at once while the cues are still settling, asks for more than
/// the ceiling; the coupled target then falls from the ceiling at grip_decrease_rate_n_per_s, not
/// from the 8 N the spike asked for (which would hold the grip at a 4 N ceiling for 2 s more).
TEST(GripSlipControllerTest, AnImpactSpikeAboveTheCeilingDecaysFromTheCeiling) {
  HandPlant::Options plant;
  plant.friction = 1.2;  // the object holds: no slip whatever the estimate says
  // Coupled to the whole shear, preload included (preload_coupling 1): coupled to the load alone
  // the spike is part of the tare and never reaches the ceiling.
  GripSlipConfig config = DefaultConfig();
  config.preload_coupling = 1.0;
  ClosedLoop loop(config, plant, {});
  constexpr double kCeilingN = 4.0;
  loop.controller.SetGripCeiling(kCeilingN);
  loop.controller.SetIntent(GraspIntent::kClose);
  double contact_s = -1.0;
  double target_at_ceiling_until_s = -1.0;
  loop.RunUntil(
      1.5,
      [&](double t) {
        const std::string phase = loop.controller.telemetry().phase;
        if (contact_s < 0.0 && (phase == "loading" || phase == "holding")) contact_s = t;
        // 3 N of shear for 5 ms as contact is made: 3 / 0.5 x 1.4 = 8.4 N coupled.
        return contact_s > 0.0 && t - contact_s < 0.005 ? 3.0 : 0.1;
      },
      [&](double t) {
        if (loop.controller.telemetry().grip_target_n >= kCeilingN - 1e-9) target_at_ceiling_until_s = t;
      });
  ASSERT_GT(contact_s, 0.0) << "no contact made";
  ASSERT_GT(target_at_ceiling_until_s, contact_s) << "the spike was meant to take the target to the ceiling";
  std::printf("[ measure  ] contact at %.3f s, target at the ceiling until %.3f s, target %.2f N at 1.5 s\n",
              contact_s, target_at_ceiling_until_s, loop.controller.telemetry().grip_target_n);
  EXPECT_EQ(loop.controller.telemetry().slip_events, 0) << "a slip response would hold the target up itself";
  // From the ceiling down to the 1.5 N floor at 2 N/s: about 1.25 s, so at 1.5 s it is well below.
  EXPECT_LT(target_at_ceiling_until_s - contact_s, 0.1);
  EXPECT_LT(loop.controller.telemetry().grip_target_n,
            kCeilingN - config.grip_decrease_rate_n_per_s * (1.5 - contact_s - 0.1) + 0.1);
  EXPECT_FALSE(loop.plant.dropped());
}

/// Held at its ceiling on a noisy readout, the force loop leaves the units' summed noise alone: the
/// effort moves frame to frame far less than with the P term answering it, and the grip still sits
/// at the ceiling.
TEST(GripSlipControllerTest, AtTheCeilingTheForceLoopDoesNotAnswerTheReadoutsNoise) {
  const auto hold = [](double deadband_n, double* grip_n) {
    HandPlant::Options plant;
    plant.friction = 1.2;  // held whatever the estimate says
    // Stronger than the feed-forward assumes (20 N): the effort cap allows 3.6 N, so the force loop
    // regulates the ceiling rather than the cap pinning the effort.
    plant.stall_force_n = 24.0;
    SyntheticTactile::Options sensor;
    sensor.noise_fn_n = 0.03;  // 20 units: 0.13 N (1 sigma) on the summed grip, under the band
    GripSlipConfig config = DefaultConfig();
    config.ceiling_deadband_n = deadband_n;
    ClosedLoop loop(config, plant, sensor);
    loop.controller.SetGripCeiling(3.0);
    loop.Grasp(1.8, 1.0);  // a load ratio of 0.6 at 3 N: the target sits at the ceiling
    double previous = loop.command.grip_effort;
    double square_sum = 0.0;
    int ticks = 0;
    double grip_sum = 0.0;
    loop.RunUntil(
        2.0, [](double) { return 1.8; },
        [&](double) {
          const double step = loop.command.grip_effort - previous;
          previous = loop.command.grip_effort;
          square_sum += step * step;
          grip_sum += loop.plant.grip_n();
          ++ticks;
        });
    EXPECT_DOUBLE_EQ(loop.controller.telemetry().grip_target_n, 3.0)
        << "not at the ceiling: nothing compared";
    EXPECT_FALSE(loop.plant.dropped());
    *grip_n = grip_sum / ticks;
    return std::sqrt(square_sum / ticks);
  };
  double grip_with_band_n = 0.0;
  double grip_without_n = 0.0;
  const double with_band = hold(DefaultConfig().ceiling_deadband_n, &grip_with_band_n);
  const double without = hold(0.0, &grip_without_n);
  std::printf(
      "[ measure  ] effort step RMS at the ceiling: %.5f with the band, %.5f without; grip %.2f / %.2f N\n",
      with_band, without, grip_with_band_n, grip_without_n);
  EXPECT_LT(with_band, 0.5 * without);
  EXPECT_NEAR(grip_with_band_n, 3.0, kCeilingTolN);
}

/// Friction is learned from a slip at the friction limit, not from a jolt: a vibration burst under
/// a light load (ratio 0.1 against the estimate 0.5) is flagged but teaches nothing; the same burst
/// with the load at 0.4 lowers the estimate to about that ratio.
TEST(GripSlipControllerTest, AJoltTeachesNoFrictionASlipAtTheLimitDoes) {
  GripSlipController controller(DefaultConfig());
  SyntheticTactile sensor({});
  controller.SetIntent(GraspIntent::kClose);
  constexpr double kGripN = 3.0;
  // The sensor reports a steady 3 N pinch (open loop: the frames do not follow the commands).
  const auto run = [&](double from_s, double to_s, double load_ratio, double burst_n) {
    for (double t = from_s; t < to_s - 1e-9; t += kPeriodS) {
      SyntheticContact contact;
      contact.grip_n = kGripN;
      contact.load_axial_n = load_ratio * kGripN;
      contact.vibration_n = burst_n * (std::fmod(t * 120.0, 1.0) - 0.5);  // 120 Hz sawtooth
      controller.Update(sensor.Frame(contact, t), {}, t);
    }
  };
  const double initial = controller.config().friction_initial;
  run(0.0, 0.6, 0.0, 0.0);
  ASSERT_STREQ(controller.telemetry().phase, "holding");
  run(0.6, 1.0, 0.1, 0.0);  // a light load comes on smoothly: nothing to flag
  ASSERT_EQ(controller.telemetry().slip_events, 0);
  run(1.0, 1.1, 0.1, 1.5);
  run(1.1, 1.5, 0.1, 0.0);
  const int jolt_events = controller.telemetry().slip_events;
  const double after_jolt = controller.telemetry().friction_estimate;
  run(1.5, 1.9, 0.4, 0.0);
  run(1.9, 2.0, 0.4, 1.5);
  std::printf("[ measure  ] jolt at ratio 0.1: %d events, estimate %.3f; burst at ratio 0.4: estimate %.3f\n",
              jolt_events, after_jolt, controller.telemetry().friction_estimate);
  EXPECT_GT(jolt_events, 0) << "the burst was meant to be flagged";
  EXPECT_DOUBLE_EQ(after_jolt, initial);
  EXPECT_GT(controller.telemetry().slip_events, jolt_events);
  EXPECT_LT(controller.telemetry().friction_estimate, initial - 0.05);
  EXPECT_GT(controller.telemetry().friction_estimate,
            initial * (1.0 - controller.config().friction_learn_max_drop));
}

TEST(GripSlipControllerTest, SafeHoldOnStaleDataKeepsCommandAndNeverOpens) {
  ClosedLoop loop(DefaultConfig(), {}, {});
  loop.Grasp(0.8, 1.0);
  const hand::HandCommand before = loop.command;
  ASSERT_GT(before.grip_effort, 0.0);
  // Stale frames whose forces read zero, as if the object were gone: the controller must not react.
  sensor::TactileState stale = loop.sensor.Frame(SyntheticContact{}, loop.time_s);
  stale.stale = true;
  for (int i = 0; i < 300; ++i) {
    loop.time_s += kPeriodS;
    const hand::HandCommand command = loop.controller.Update(stale, {}, loop.time_s);
    ASSERT_DOUBLE_EQ(command.grip_effort, before.grip_effort) << "tick " << i;
    ASSERT_GE(command.grip_effort, 0.0);
    ASSERT_TRUE(command.enable);
    ASSERT_TRUE(loop.controller.telemetry().safe_hold);
    ASSERT_STREQ(loop.controller.telemetry().phase, "safe_hold");
    ASSERT_FALSE(loop.controller.telemetry().slip_detected);
  }
  // Data back: hold resumes without a false slip from the gap.
  loop.RunUntil(loop.time_s + 1.0, [](double) { return 0.8; });
  EXPECT_STREQ(loop.controller.telemetry().phase, "holding");
  EXPECT_FALSE(loop.controller.telemetry().safe_hold);
  EXPECT_EQ(loop.controller.telemetry().slip_events, 0);
  EXPECT_FALSE(loop.plant.sliding());
}

TEST(GripSlipControllerTest, SafeHoldWhenTooFewUnitsAreValid) {
  GripSlipConfig config = DefaultConfig();
  config.min_valid_units = 4;
  ClosedLoop loop(config, {}, {});
  loop.Grasp(0.8, 1.0);
  const double effort_before = loop.command.grip_effort;
  for (int unit = 0; unit < 17; ++unit) loop.sensor.SetUnitValidity(unit, sensor::UnitValidity::kOpen);
  loop.RunUntil(1.2, [](double) { return 0.8; });
  EXPECT_TRUE(loop.controller.telemetry().safe_hold);
  EXPECT_DOUBLE_EQ(loop.command.grip_effort, effort_before);
}

TEST(GripSlipControllerTest, DeadUnitsDuringHoldCauseNoFalseSlip) {
  ClosedLoop loop(DefaultConfig(), {}, {});
  loop.Grasp(0.8, 1.0);
  loop.RunUntil(1.5, [](double) { return 0.8; });
  loop.sensor.SetUnitValidity(9, sensor::UnitValidity::kShort);  // under the patch centre
  loop.RunUntil(2.5, [](double) { return 0.8; });
  loop.sensor.SetUnitValidity(9, sensor::UnitValidity::kValid);  // comes back
  loop.sensor.SetUnitValidity(10, sensor::UnitValidity::kOpen);
  loop.RunUntil(4.0, [](double) { return 0.8; });
  EXPECT_EQ(loop.controller.telemetry().slip_events, 0);
  EXPECT_FALSE(loop.controller.telemetry().safe_hold);
  EXPECT_STREQ(loop.controller.telemetry().phase, "holding");
}

TEST(GripSlipControllerTest, ReleasesOnOpenIntent) {
  const GripSlipConfig config = DefaultConfig();
  ClosedLoop loop(config, {}, {});
  loop.Grasp(0.5, 1.0);
  loop.controller.SetIntent(GraspIntent::kOpen);
  loop.RunUntil(1.1, [](double) { return 0.0; });
  EXPECT_STREQ(loop.controller.telemetry().phase, "releasing");
  EXPECT_DOUBLE_EQ(loop.command.grip_effort, -config.open_effort);
  EXPECT_DOUBLE_EQ(loop.plant.grip_n(), 0.0);
  loop.RunUntil(1.0 + config.release_time_s + 0.01, [](double) { return 0.0; });
  EXPECT_STREQ(loop.controller.telemetry().phase, "open");
  EXPECT_DOUBLE_EQ(loop.command.grip_effort, 0.0);
  // Closing again starts a fresh grasp.
  loop.controller.SetIntent(GraspIntent::kClose);
  loop.RunUntil(loop.time_s + 1.0, [](double) { return 0.5; });
  EXPECT_STREQ(loop.controller.telemetry().phase, "holding");
}

TEST(GripSlipControllerTest, SaturatedUnitStopsTheEffortFromRising) {
  GripSlipConfig config = DefaultConfig();
  ClosedLoop loop(config, {}, {});
  loop.Grasp(0.5, 1.0);
  // A point-like heavy load: the centre unit saturates while the total still reads low.
  SyntheticContact contact = loop.plant.Contact();
  contact.grip_n = 12.0;
  contact.centre_column = 1.0;  // on unit 9 (row 2, column 1)
  contact.patch_sigma_units = 0.3;
  contact.load_axial_n = 3.0;
  const double effort_before = loop.command.grip_effort;
  double max_effort = 0.0;
  for (int i = 0; i < 200; ++i) {
    loop.time_s += kPeriodS;
    const sensor::TactileState state = loop.sensor.Frame(contact, loop.time_s);
    ASSERT_EQ(state.validity[9], sensor::UnitValidity::kOutOfRange);
    max_effort = std::max(max_effort, loop.controller.Update(state, {}, loop.time_s).grip_effort);
  }
  EXPECT_GE(loop.controller.diagnostics().saturated_units, 1);
  EXPECT_LE(max_effort, effort_before + 1e-12);
}

TEST(GripSlipControllerTest, TelemetryFilledEveryUpdate) {
  ClosedLoop loop(DefaultConfig(), {}, {});
  EXPECT_STREQ(loop.controller.telemetry().phase, "idle");
  EXPECT_DOUBLE_EQ(loop.controller.telemetry().friction_estimate, loop.controller.config().friction_initial);
  loop.Grasp(1.0, 1.0);
  const ControllerTelemetry telemetry = loop.controller.telemetry();
  EXPECT_STREQ(telemetry.phase, "holding");
  EXPECT_GT(telemetry.grip_target_n, 0.0);
  EXPECT_FALSE(telemetry.safe_hold);
  EXPECT_EQ(loop.controller.name(), "grip_slip");
  EXPECT_GT(loop.controller.diagnostics().signals.tangential_load_n, 0.5);
  EXPECT_TRUE(loop.controller.diagnostics().signals.orientation_consistent);
  // The logged diagnostic channels read the same diagnostics, by name.
  const std::span<const DiagnosticChannel> channels = loop.controller.diagnostic_channels();
  std::vector<double> values(channels.size(), -1.0);
  loop.controller.ReadDiagnostics(values);
  const auto value = [&](std::string_view name) {
    for (size_t i = 0; i < channels.size(); ++i) {
      if (name == channels[i].name) return values[i];
    }
    ADD_FAILURE() << "no channel " << name;
    return -1.0;
  };
  const GripSlipDiagnostics& diagnostics = loop.controller.diagnostics();
  EXPECT_EQ(value("measured_grip_n"), diagnostics.measured_grip_n);
  EXPECT_EQ(value("load_ratio"), diagnostics.signals.load_ratio);
  EXPECT_EQ(value("vibration_threshold_n"), diagnostics.signals.vibration_threshold_n);
  EXPECT_EQ(value("centroid_drift_threshold_pitch"), diagnostics.signals.centroid_drift_threshold);
  EXPECT_EQ(value("settled"), 1.0);
  loop.controller.Reset();
  EXPECT_STREQ(loop.controller.telemetry().phase, "idle");
  EXPECT_EQ(loop.controller.telemetry().slip_events, 0);
}

TEST(GripSlipControllerTest, NanCeilingIsRejected) {
  GripSlipController controller(DefaultConfig());
  EXPECT_THAT(ErrorOf([&] { controller.SetGripCeiling(std::nan("")); }), HasSubstr("grip ceiling = nan"));
  controller.SetGripCeiling(0.0);  // no task ceiling
  EXPECT_DOUBLE_EQ(controller.diagnostics().ceiling_n, controller.config().max_grip_n);
}

}  // namespace
}  // namespace graspbed::controller
