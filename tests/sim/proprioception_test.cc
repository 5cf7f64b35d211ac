// The simulated proprioception (sim/proprioception.h) against a real Simulation, one test per field
// of its profile: the ideal profile is the physics; the encoder quantises; the current has its
// gain, offset and noise; a reading appears latency_s after its sample; both filters are first
// order with their cutoff's time constant; the stop flags; a stuck encoder is flagged while its
// motor turns and not while the digit is stalled on the object.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <vector>

#include "hand/hand_state.h"
#include "sim/proprioception.h"
#include "tests/sim/sim_fixture.h"

namespace graspbed::sim {
namespace {

using Digits = std::array<DigitTruth, 2>;
using OnReading = std::function<void(const hand::HandState& state, const Digits& truth)>;

constexpr double kExactTol = 1e-12;
// Sample times are sums of 1 ms physics steps: equal to the nominal times to rounding.
constexpr double kTimeTol = 1e-9;
// How far the wrist rises so that closing meets nothing (the box is 80 mm tall) [m].
constexpr double kClearOfTheBoxM = 0.15;
// The pinch's effort, and the share of the stall torque the motor then makes held still on the
// box: the effort itself (measured: 0.4997 .. 0.5003 from 0.15 s on).
constexpr double kPinchEffort = 0.5;
constexpr double kStallShareTol = 2e-3;
constexpr double kSettledS = 0.3;  // the pinch is still by then (measured: from 0.15 s)
constexpr int kFinger = 0;
constexpr int kThumb = 1;

/// Every field exact: the ideal profile.
ProprioceptionConfig Exact() { return ProprioceptionProfile("ideal"); }

double SamplePeriodS(const ProprioceptionConfig& config) { return 1.0 / config.sample_rate_hz; }

class ProprioceptionTest : public test_support::MujocoTest {
 protected:
  /// The default scene: the 50 mm box in the hand's pre-shape.
  Simulation& Pinch() { return MakeSimulation(DefaultLayout(), SceneConfig{}); }

  /// Steps `simulation` to `end_s` [s] one physics step at a time; after each step polls every
  /// sensor and reads it at the simulation's time, calling `on_reading[k]` (if any) when sensor k
  /// has a new reading, with the physics as it is then.
  static void Run(Simulation& simulation, const std::vector<SimHandSensor*>& sensors, double end_s,
                  const std::vector<OnReading>& on_reading = {}) {
    std::vector<hand::HandState> states(sensors.size());
    while (simulation.time_s() < end_s - 0.5 * simulation.timestep_s()) {
      simulation.Step();
      const double now = simulation.time_s();
      for (size_t k = 0; k < sensors.size(); ++k) {
        sensors[k]->Poll(now);
        if (sensors[k]->Read(now, &states[k]) && k < on_reading.size() && on_reading[k]) {
          on_reading[k](states[k], simulation.ReadDigits());
        }
      }
    }
  }
  static void Run(Simulation& simulation, SimHandSensor& sensor, double end_s,
                  const OnReading& on_reading = {}) {
    Run(simulation, {&sensor}, end_s, {on_reading});
  }

  /// Lifts the wrist clear of the box (the sensor polled meanwhile), so that the digits close on
  /// nothing; returns with the motor off.
  static void LiftClear(Simulation& simulation, SimHandSensor& sensor) {
    std::array<double, 3> target = simulation.wrist_target();
    target[2] += kClearOfTheBoxM;
    simulation.SetWristTarget(target);
    Run(simulation, sensor, simulation.time_s() + 0.3);
  }
};

TEST_F(ProprioceptionTest, TheIdealProfileReportsThePhysicsExactly) {
  Simulation& simulation = Pinch();
  SimHandSensor sensor(simulation, Exact(), 1);
  simulation.SetGripEffort(kPinchEffort);
  int readings = 0;
  Run(simulation, sensor, 0.4, [&](const hand::HandState& state, const Digits& truth) {
    ++readings;
    EXPECT_NEAR(state.time_s, simulation.time_s(), kTimeTol) << "no delay";
    ASSERT_EQ(state.digit_count, 2);
    for (const int d : {kFinger, kThumb}) {
      const hand::DigitState& digit = state.digits[d];
      ASSERT_EQ(digit.joint_count, truth[d].joint_count);
      EXPECT_TRUE(digit.position_known && digit.velocity_known && digit.current_known && digit.stops_known);
      EXPECT_FALSE(digit.linear);
      for (int j = 0; j < digit.joint_count; ++j) {
        EXPECT_EQ(digit.joint_position[j], truth[d].position[j]);
        EXPECT_EQ(digit.joint_velocity[j], truth[d].velocity[j]);
      }
      EXPECT_DOUBLE_EQ(digit.motor_current_a, Exact().stall_current_a * truth[d].motor_torque_share);
      EXPECT_EQ(digit.stall_current_a, Exact().stall_current_a);
    }
  });
  EXPECT_EQ(readings, 400);  // one per 1 ms sample, from the first step on
  // The premise: the finger flexed, and the motor pushes against the box by the end.
  const Digits truth = simulation.ReadDigits();
  EXPECT_GT(truth[kFinger].position[0], 0.05);
  EXPECT_NEAR(truth[kFinger].motor_torque_share, kPinchEffort, kStallShareTol);
}

TEST_F(ProprioceptionTest, ReadingsComeAtTheSampleRate) {
  Simulation& simulation = Pinch();
  ProprioceptionConfig config = Exact();
  config.sample_rate_hz = 250.0;
  SimHandSensor sensor(simulation, config, 1);
  std::vector<double> times;
  Run(simulation, sensor, 0.1,
      [&](const hand::HandState& state, const Digits&) { times.push_back(state.time_s); });
  ASSERT_EQ(times.size(), 26u);  // 4 ms apart, the first at 0 ms: 0 .. 100 ms
  for (size_t k = 0; k < times.size(); ++k) EXPECT_NEAR(times[k], 0.004 * static_cast<double>(k), kTimeTol);
}

TEST_F(ProprioceptionTest, ADisabledSensorReportsNothing) {
  Simulation& simulation = Pinch();
  ProprioceptionConfig config = Exact();
  config.enabled = false;
  SimHandSensor sensor(simulation, config, 1);
  int readings = 0;
  Run(simulation, sensor, 0.05, [&](const hand::HandState&, const Digits&) { ++readings; });
  EXPECT_EQ(readings, 0);
  hand::HandState state;
  EXPECT_FALSE(sensor.Read(1.0, &state));
  EXPECT_FALSE(state.any_known());
}

TEST_F(ProprioceptionTest, PositionsAreQuantisedToTheEncoderResolution) {
  // The realistic 12-bit encoder, and a coarse one whose steps a 0.1 s close crosses many times.
  for (const double resolution_rad : {ProprioceptionConfig{}.encoder_resolution_rad, 0.01}) {
    SCOPED_TRACE(resolution_rad);
    Simulation& simulation = Pinch();
    ProprioceptionConfig config = Exact();
    config.encoder_resolution_rad = resolution_rad;
    SimHandSensor sensor(simulation, config, 1);
    simulation.SetGripEffort(kPinchEffort);
    std::vector<double> seen;
    Run(simulation, sensor, 0.2, [&](const hand::HandState& state, const Digits& truth) {
      for (const int d : {kFinger, kThumb}) {
        for (int j = 0; j < truth[d].joint_count; ++j) {
          const double reading = state.digits[d].joint_position[j];
          const double counts = reading / resolution_rad;
          EXPECT_NEAR(counts, std::round(counts), 1e-9) << "a whole number of counts";
          EXPECT_LE(std::abs(reading - truth[d].position[j]), 0.5 * resolution_rad + kExactTol);
        }
      }
      seen.push_back(state.digits[kFinger].joint_position[0]);
    });
    std::sort(seen.begin(), seen.end());
    const long steps = std::unique(seen.begin(), seen.end()) - seen.begin();
    EXPECT_GE(steps, 5) << "the premise: the finger crossed several counts";
  }
}

TEST_F(ProprioceptionTest, SlidesAreQuantisedToTheirOwnResolution) {
  SceneConfig jaw;
  jaw.hand.model = HandModel::kJaw;
  jaw.hand.open_gap_m = 0.065;
  Simulation& simulation = MakeSimulation(DefaultLayout(), jaw);
  ProprioceptionConfig config = Exact();
  config.encoder_resolution_m = 1e-4;
  SimHandSensor sensor(simulation, config, 1);
  simulation.SetGripEffort(kPinchEffort);
  int readings = 0;
  Run(simulation, sensor, 0.2, [&](const hand::HandState& state, const Digits& truth) {
    const hand::DigitState& finger = state.digits[kFinger];
    ASSERT_TRUE(finger.linear);
    ASSERT_GE(finger.joint_count, 1);
    const double counts = finger.joint_position[0] / config.encoder_resolution_m;
    EXPECT_NEAR(counts, std::round(counts), 1e-9);
    EXPECT_LE(std::abs(finger.joint_position[0] - truth[kFinger].position[0]),
              0.5 * config.encoder_resolution_m + kExactTol);
    ++readings;
  });
  EXPECT_EQ(readings, 200);
}

TEST_F(ProprioceptionTest, CurrentGainOffsetAndStallCurrentScaleTheTrueCurrent) {
  Simulation& simulation = Pinch();
  ProprioceptionConfig config = Exact();
  config.current_gain = 1.02;
  config.current_offset_a = 0.01;
  config.stall_current_a = 2.0;
  SimHandSensor sensor(simulation, config, 1);
  simulation.SetGripEffort(kPinchEffort);
  const auto expected = [&](double share) {
    return config.current_gain * config.stall_current_a * share + config.current_offset_a;
  };
  hand::HandState last;
  Run(simulation, sensor, kSettledS, [&](const hand::HandState& state, const Digits& truth) {
    for (const int d : {kFinger, kThumb}) {
      EXPECT_NEAR(state.digits[d].motor_current_a, expected(truth[d].motor_torque_share), kExactTol);
      EXPECT_EQ(state.digits[d].stall_current_a, config.stall_current_a);
    }
    last = state;
  });
  // Stalled on the box: the motor makes the effort's share of its stall torque.
  EXPECT_NEAR(last.digits[kFinger].motor_current_a, expected(kPinchEffort),
              config.current_gain * config.stall_current_a * kStallShareTol);
  // Braked, the motor is off: the reading is the offset alone.
  simulation.SetGripBrake(true);
  Run(simulation, sensor, kSettledS + 0.01,
      [&](const hand::HandState& state, const Digits&) { last = state; });
  EXPECT_NEAR(last.digits[kFinger].motor_current_a, config.current_offset_a, kExactTol);
  EXPECT_NEAR(last.digits[kThumb].motor_current_a, config.current_offset_a, kExactTol);
}

TEST_F(ProprioceptionTest, CurrentNoiseHasTheConfiguredStandardDeviationAtStall) {
  Simulation& simulation = Pinch();
  ProprioceptionConfig config = Exact();
  config.current_noise_a = ProprioceptionConfig{}.current_noise_a;  // the realistic 5 mA
  SimHandSensor sensor(simulation, config, 7);
  simulation.SetGripEffort(kPinchEffort);
  Run(simulation, sensor, kSettledS);
  std::vector<double> residual_a;
  Run(simulation, sensor, kSettledS + 4.0, [&](const hand::HandState& state, const Digits& truth) {
    residual_a.push_back(state.digits[kFinger].motor_current_a -
                         config.stall_current_a * truth[kFinger].motor_torque_share);
  });
  ASSERT_EQ(residual_a.size(), 4000u);
  const double n = static_cast<double>(residual_a.size());
  double mean = 0.0;
  for (const double r : residual_a) mean += r / n;
  double variance = 0.0;
  for (const double r : residual_a) variance += (r - mean) * (r - mean) / (n - 1.0);
  // Four standard errors: of the mean, sigma / sqrt(n); of a normal sample's standard deviation,
  // sigma / sqrt(2 (n - 1)) (6.3 % of sigma at 4000 samples).
  const double sigma = config.current_noise_a;
  EXPECT_NEAR(mean, 0.0, 4.0 * sigma / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(variance), sigma, 4.0 * sigma / std::sqrt(2.0 * (n - 1.0)));
}

TEST_F(ProprioceptionTest, AReadingAppearsExactlyLatencyAfterItsSampleTime) {
  // Physics at 0.25 ms, so that a reading early or late by a quarter of a sample would show.
  SceneConfig scene;
  scene.physics.timestep_s = 0.00025;
  Simulation& simulation = MakeSimulation(DefaultLayout(), scene);
  ProprioceptionConfig prompt = ProprioceptionProfile("realistic");
  prompt.latency_s = 0.0;
  ProprioceptionConfig delayed = prompt;
  delayed.latency_s = 0.005;
  SimHandSensor prompt_sensor(simulation, prompt, 3);
  SimHandSensor delayed_sensor(simulation, delayed, 3);  // the same seed: the same noise
  simulation.SetGripEffort(kPinchEffort);
  std::map<long, hand::HandState> sampled;  // the prompt sensor's readings by sample index
  int delayed_readings = 0;
  const auto index_of = [&](double time_s) { return std::lround(time_s * prompt.sample_rate_hz); };
  Run(simulation, {&prompt_sensor, &delayed_sensor}, 0.2,
      {[&](const hand::HandState& state, const Digits&) { sampled[index_of(state.time_s)] = state; },
       [&](const hand::HandState& state, const Digits&) {
         ++delayed_readings;
         EXPECT_NEAR(simulation.time_s() - state.time_s, delayed.latency_s, kTimeTol)
             << "at " << state.time_s;
         const auto prompt_reading = sampled.find(index_of(state.time_s));
         ASSERT_NE(prompt_reading, sampled.end());
         EXPECT_EQ(state.digits[kFinger].joint_position,
                   prompt_reading->second.digits[kFinger].joint_position);
         EXPECT_EQ(state.digits[kFinger].motor_current_a,
                   prompt_reading->second.digits[kFinger].motor_current_a);
       }});
  EXPECT_EQ(sampled.size(), 201u);   // the samples of 0 .. 200 ms
  EXPECT_EQ(delayed_readings, 196);  // those of 0 .. 195 ms, released by 0.2 s
}

TEST_F(ProprioceptionTest, TheVelocityFilterIsFirstOrderWithItsTimeConstant) {
  // A clean step of the differentiated encoder: the digit closes freely at its no-load speed, then
  // its encoder sticks; from there on the counts stand still and the filtered velocity must decay
  // as exp(-t / tau), tau = 1 / (2 pi f).
  Simulation& simulation = Pinch();
  ProprioceptionConfig config = Exact();
  config.velocity_filter_hz = 10.0;
  config.stuck_encoder_timeout_s = 10.0;  // keep the velocity known throughout
  const double tau_s = 1.0 / (2.0 * std::numbers::pi * config.velocity_filter_hz);
  SimHandSensor sensor(simulation, config, 1);
  LiftClear(simulation, sensor);
  simulation.SetGripEffort(kPinchEffort);
  hand::HandState before;
  Run(simulation, sensor, simulation.time_s() + 0.2, [&](const hand::HandState& state, const Digits& truth) {
    before = state;
    (void)truth;
  });
  const double speed = before.digits[kFinger].joint_velocity[0];
  const double true_speed = simulation.ReadDigits()[kFinger].velocity[0];
  ASSERT_GT(speed, 0.5) << "the premise: closing freely";
  EXPECT_NEAR(speed, true_speed, 0.01 * true_speed) << "settled at the true speed";
  const double stuck_at_s = before.time_s;
  sensor.SetEncoderStuck(kFinger, true);
  double crossed_s = -1.0;
  Run(simulation, sensor, simulation.time_s() + 5.0 * tau_s,
      [&](const hand::HandState& state, const Digits&) {
        const double elapsed_s = state.time_s - stuck_at_s;
        EXPECT_NEAR(state.digits[kFinger].joint_velocity[0], speed * std::exp(-elapsed_s / tau_s), 1e-9);
        if (crossed_s < 0.0 && state.digits[kFinger].joint_velocity[0] <= speed / std::numbers::e)
          crossed_s = elapsed_s;
      });
  EXPECT_NEAR(crossed_s, tau_s, SamplePeriodS(config)) << "1/e of the step after one time constant";
}

TEST_F(ProprioceptionTest, TheCurrentFilterIsFirstOrderWithItsTimeConstant) {
  // A clean step of the true current: stalled on the box, then braked (the motor is off at once).
  Simulation& simulation = Pinch();
  ProprioceptionConfig config = Exact();
  config.current_filter_hz = 20.0;
  const double tau_s = 1.0 / (2.0 * std::numbers::pi * config.current_filter_hz);
  SimHandSensor sensor(simulation, config, 1);
  simulation.SetGripEffort(kPinchEffort);
  hand::HandState before;
  Run(simulation, sensor, kSettledS, [&](const hand::HandState& state, const Digits&) { before = state; });
  const double current_a = before.digits[kFinger].motor_current_a;
  ASSERT_NEAR(current_a, config.stall_current_a * kPinchEffort, config.stall_current_a * kStallShareTol);
  simulation.SetGripBrake(true);
  double crossed_s = -1.0;
  Run(simulation, sensor, kSettledS + 5.0 * tau_s, [&](const hand::HandState& state, const Digits&) {
    const double elapsed_s = state.time_s - before.time_s;
    EXPECT_NEAR(state.digits[kFinger].motor_current_a, current_a * std::exp(-elapsed_s / tau_s), 1e-9);
    if (crossed_s < 0.0 && state.digits[kFinger].motor_current_a <= current_a / std::numbers::e)
      crossed_s = elapsed_s;
  });
  EXPECT_NEAR(crossed_s, tau_s, SamplePeriodS(config));
}

TEST_F(ProprioceptionTest, TheStopFlagsMarkTheEndStops) {
  // Clear of the box, the digits close all the way at full effort, then open all the way.
  Simulation& simulation = Pinch();
  const ProprioceptionConfig config = ProprioceptionProfile("realistic");
  SimHandSensor sensor(simulation, config, 1);
  LiftClear(simulation, sensor);
  std::array<std::array<int, 2>, 2> flagged{};  // [digit][open, closed]: readings with the flag set
  const OnReading check = [&](const hand::HandState& state, const Digits& truth) {
    for (const int d : {kFinger, kThumb}) {
      const hand::DigitState& digit = state.digits[d];
      ASSERT_TRUE(digit.stops_known);
      const double q = digit.joint_position[0];
      EXPECT_EQ(digit.at_open_stop, q <= truth[d].open_stop + config.stop_tolerance_rad) << q;
      EXPECT_EQ(digit.at_closed_stop, q >= truth[d].closed_stop - config.stop_tolerance_rad) << q;
      flagged[d][0] += digit.at_open_stop ? 1 : 0;
      flagged[d][1] += digit.at_closed_stop ? 1 : 0;
    }
  };
  simulation.SetGripEffort(1.0);
  Run(simulation, sensor, simulation.time_s() + 1.5, check);
  hand::HandState state;
  for (const int d : {kFinger, kThumb}) {
    EXPECT_EQ(flagged[d][0], 0) << "digit " << d;
    EXPECT_GT(flagged[d][1], 0) << "digit " << d << " never reached its closed stop";
  }
  simulation.SetGripEffort(-1.0);
  Run(simulation, sensor, simulation.time_s() + 2.0, check);
  for (const int d : {kFinger, kThumb})
    EXPECT_GT(flagged[d][0], 0) << "digit " << d << " never reached its open stop";
}

TEST_F(ProprioceptionTest, AStuckEncoderIsFlaggedWhileTheMotorTurns) {
  Simulation& simulation = Pinch();
  const ProprioceptionConfig config = ProprioceptionProfile("realistic");
  SimHandSensor sensor(simulation, config, 1);
  LiftClear(simulation, sensor);
  simulation.SetGripEffort(kPinchEffort);
  hand::HandState before;
  Run(simulation, sensor, simulation.time_s() + 0.1,
      [&](const hand::HandState& state, const Digits&) { before = state; });
  ASSERT_GT(before.digits[kFinger].joint_velocity[0], 0.5) << "the premise: closing freely";
  // The encoder sticks at its newest sample's counts, which the controller sees latency_s later.
  sensor.SetEncoderStuck(kFinger, true);
  const double last_change_s = before.time_s + config.latency_s;
  std::array<double, hand::kMaxDigitJoints> stuck_counts{};
  double flagged_s = -1.0;
  Run(simulation, sensor, simulation.time_s() + 0.2, [&](const hand::HandState& state, const Digits&) {
    const hand::DigitState& finger = state.digits[kFinger];
    if (state.time_s < last_change_s - kTimeTol) return;  // sampled before it stuck
    if (state.time_s < last_change_s + kTimeTol) stuck_counts = finger.joint_position;
    EXPECT_EQ(finger.joint_position, stuck_counts) << "stuck at " << state.time_s;
    if (finger.encoder_fault && flagged_s < 0.0) flagged_s = state.time_s - last_change_s;
    if (flagged_s >= 0.0) {
      EXPECT_TRUE(finger.encoder_fault) << "flagged for as long as the motor turns";
      EXPECT_FALSE(finger.position_known);
      EXPECT_FALSE(finger.velocity_known);
      EXPECT_FALSE(finger.stops_known);
    } else {
      EXPECT_TRUE(finger.position_known);
    }
    EXPECT_FALSE(state.digits[kThumb].encoder_fault) << "the thumb's encoder is fine";
    EXPECT_TRUE(state.digits[kThumb].position_known);
  });
  EXPECT_NEAR(flagged_s, config.stuck_encoder_timeout_s, 0.5 * SamplePeriodS(config))
      << "flagged once the counts stood still for stuck_encoder_timeout_s";
  EXPECT_GT(sensor.encoder_fault_samples(), 0u);
  // Freed, it counts again and the flag goes.
  sensor.SetEncoderStuck(kFinger, false);
  hand::HandState after;
  Run(simulation, sensor, simulation.time_s() + 0.01,
      [&](const hand::HandState& state, const Digits&) { after = state; });
  EXPECT_FALSE(after.digits[kFinger].encoder_fault);
  EXPECT_TRUE(after.digits[kFinger].position_known);
}

TEST_F(ProprioceptionTest, AStuckEncoderIsNotFlaggedWhileTheDigitIsStalledOnTheObject) {
  Simulation& simulation = Pinch();
  const ProprioceptionConfig config = ProprioceptionProfile("realistic");
  SimHandSensor sensor(simulation, config, 1);
  simulation.SetGripEffort(kPinchEffort);
  Run(simulation, sensor, kSettledS);
  sensor.SetEncoderStuck(kFinger, true);
  int readings = 0;
  Run(simulation, sensor, kSettledS + 10.0 * config.stuck_encoder_timeout_s,
      [&](const hand::HandState& state, const Digits&) {
        ++readings;
        EXPECT_FALSE(state.digits[kFinger].encoder_fault) << "at " << state.time_s;
        EXPECT_TRUE(state.digits[kFinger].position_known);
      });
  EXPECT_GT(readings, 0);
  EXPECT_EQ(sensor.encoder_fault_samples(), 0u);
}

}  // namespace
}  // namespace graspbed::sim
