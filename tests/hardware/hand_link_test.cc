// The hand's proprioception over the serial link (HAND, protocol version 2; docs/protocol.md), over
// real pseudo-terminals: negotiated at HELLO, decoded into the loop's HandState, a version-1 device
// negotiated down to no HAND at all (every field unknown, never zero), and HAND faults counted while
// the frames go on.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "controller/control_loop.h"
#include "controller/grasp_controller.h"
#include "hardware/device_emulator.h"
#include "hardware/hardware_backend.h"
#include "hardware/serial_hand_sensor.h"
#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "tests/hardware/serial_test_util.h"

namespace graspbed::hardware {
namespace {

using test_support::WaitFor;

constexpr int kUnits = 20;
constexpr double kWireTol = 0.5e-6;  // HAND carries micro-units: [urad], [urad/s], [uA]

/// The emulated hand's proprioception at device time t: index flexing 0.4 + 0.1 t rad (MCP) and half
/// that (PIP), drawing 0.3 A of a 1 A stall current; the thumb a single hinge with no current sensor.
bool ScriptedHand(double device_time_s, hand::HandState* state) {
  state->digit_count = 2;
  hand::DigitState& index = state->digits[0];
  index.joint_count = 2;
  index.position_known = index.velocity_known = index.current_known = index.stops_known = true;
  index.joint_position = {0.4 + 0.1 * device_time_s, 0.2 + 0.05 * device_time_s};
  index.joint_velocity = {0.1, 0.05};
  index.motor_current_a = 0.3;
  index.stall_current_a = 1.0;
  hand::DigitState& thumb = state->digits[1];
  thumb.joint_count = 1;
  thumb.position_known = thumb.velocity_known = true;
  thumb.joint_position = {0.25, 0.0};
  thumb.joint_velocity = {0.0, 0.0};
  thumb.current_known = false;
  return true;
}

/// Holds what the loop gave it last: the controller a proprioceptive controller would be.
class RecordingController final : public controller::GraspController {
 public:
  void Reset() override {}
  void SetIntent(controller::GraspIntent) override {}
  hand::HandCommand Update(const sensor::TactileState&, const hand::HandState& hand, double) override {
    last_hand = hand;
    ++updates;
    return {};
  }
  void SetGripCeiling(double) override {}
  controller::ControllerTelemetry telemetry() const override { return {}; }
  std::string name() const override { return "recording"; }
  hand::HandState last_hand;
  int updates = 0;
};

class HandLinkTest : public ::testing::Test {
 protected:
  void Start(int device_version) {
    EmulatorConfig config;
    config.link_path = test_support::UniqueLinkPath("hand");
    config.unit_count = kUnits;
    config.protocol_version = device_version;
    emulator_ = std::make_unique<DeviceEmulator>(config, test_support::TestFrameSource);
    emulator_->SetHandSource(ScriptedHand);
    emulator_->Start();
    hw_config_.port = config.link_path;
    backend_ = std::make_unique<HardwareBackend>(hw_config_, kUnits, "test_20");
    actuator_ = std::make_unique<HardwareActuator>(*backend_, hw_config_);
    backend_->Start();
    actuator_->Start();
    hand_sensor_ = std::make_unique<SerialHandSensor>(backend_->link());
    loop_ = std::make_unique<controller::ControlLoop>(*backend_, *hand_sensor_, controller_, *actuator_,
                                                      layout_, sensor::PaperCalibration(kUnits),
                                                      controller::ControlLoopConfig{});
  }

  // Ticks the loop on the wall clock until `frames` frames went through it.
  void TickFrames(uint64_t frames) {
    const auto start = std::chrono::steady_clock::now();
    ASSERT_TRUE(WaitFor([&] {
      backend_->link()->WaitForFrame(backend_->link()->published(), 0.002);
      loop_->Tick(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      return loop_->counters().frames >= frames;
    }));
  }

  void TearDown() override {
    loop_.reset();
    hand_sensor_.reset();
    actuator_.reset();
    backend_.reset();
    emulator_.reset();
  }

  const sensor::Layout layout_ = sensor::LoadLayout(sensor::DefaultLayoutPath());
  HardwareConfig hw_config_;
  RecordingController controller_;
  std::unique_ptr<DeviceEmulator> emulator_;
  std::unique_ptr<HardwareBackend> backend_;
  std::unique_ptr<HardwareActuator> actuator_;
  std::unique_ptr<SerialHandSensor> hand_sensor_;
  std::unique_ptr<controller::ControlLoop> loop_;
};

TEST_F(HandLinkTest, AVersionTwoDeviceIsSelectedAndItsHandReachesTheController) {
  Start(/*device_version=*/2);
  TickFrames(200);
  // Read once frames flow: the HELLO that sets it is answered on the link's thread, after Start.
  EXPECT_EQ(backend_->link()->protocol_version(), 2);
  const hand::HandState& hand = controller_.last_hand;
  ASSERT_EQ(hand.digit_count, 2);
  EXPECT_GE(hand.time_s, 0.0);
  const hand::DigitState& index = hand.digits[0];
  ASSERT_TRUE(index.position_known && index.velocity_known && index.current_known && index.stops_known);
  EXPECT_EQ(index.joint_count, 2);
  // The sample's own device time is not carried to the loop; its values satisfy the script's relation.
  const double t = (index.joint_position[0] - 0.4) / 0.1;
  EXPECT_GT(t, 0.0);
  EXPECT_NEAR(index.joint_position[1], 0.2 + 0.05 * t, 2 * kWireTol);
  EXPECT_NEAR(index.joint_velocity[0], 0.1, kWireTol);
  EXPECT_NEAR(index.motor_current_a, 0.3, kWireTol);
  EXPECT_NEAR(index.stall_current_a, 1.0, kWireTol);
  const hand::DigitState& thumb = hand.digits[1];
  EXPECT_EQ(thumb.joint_count, 1);
  EXPECT_NEAR(thumb.joint_position[0], 0.25, kWireTol);
  EXPECT_FALSE(thumb.current_known);
  EXPECT_FALSE(thumb.stops_known);
  EXPECT_GT(loop_->counters().hand_readings, 100u);
  const EmulatorStats stats = emulator_->stats();
  EXPECT_GE(stats.selects, 1u);
  EXPECT_GT(stats.hand_sent, 100u);
  EXPECT_EQ(stats.host_unknown, 0u);
  const HandCounters counters = backend_->link()->hand_counters();
  EXPECT_GT(counters.messages, 100u);
  EXPECT_EQ(counters.malformed, 0u);
  EXPECT_EQ(backend_->counters().corrupt, 0u);
  EXPECT_EQ(backend_->counters().unknown_packets, 0u);
}

TEST_F(HandLinkTest, AVersionOneDeviceIsNegotiatedDownAndTheControllerSeesUnknownNeverZero) {
  Start(/*device_version=*/1);
  TickFrames(200);
  // Read once frames flow: the HELLO that sets it is answered on the link's thread, after Start.
  EXPECT_EQ(backend_->link()->protocol_version(), 1);
  const hand::HandState& hand = controller_.last_hand;
  EXPECT_EQ(hand.digit_count, 0);
  EXPECT_FALSE(hand.any_known());
  EXPECT_LT(hand.time_s, 0.0);
  for (const hand::DigitState& digit : hand.digits) {
    EXPECT_FALSE(digit.position_known || digit.velocity_known || digit.current_known || digit.stops_known);
  }
  EXPECT_EQ(loop_->counters().hand_readings, 0u);
  // The frames went on as from any version-1 device: no PROTOCOL_SELECT sent, no HAND received.
  const EmulatorStats stats = emulator_->stats();
  EXPECT_EQ(stats.selects, 0u);
  EXPECT_EQ(stats.host_unknown, 0u);
  EXPECT_EQ(stats.hand_sent, 0u);
  EXPECT_EQ(backend_->link()->hand_counters().messages, 0u);
  EXPECT_EQ(backend_->counters().unknown_packets, 0u);
  EXPECT_EQ(backend_->counters().corrupt, 0u);
}

TEST_F(HandLinkTest, CorruptDroppedAndMalformedHandsAreCountedAndTheLinkGoesOn) {
  Start(/*device_version=*/2);
  ASSERT_TRUE(WaitFor([&] { return backend_->link()->hand_counters().messages > 20; }));
  const uint64_t corrupt0 = backend_->counters().corrupt;
  const HandCounters hand0 = backend_->link()->hand_counters();
  const EmulatorStats emu0 = emulator_->stats();
  emulator_->CorruptHand(2);
  emulator_->DropHand(3);
  emulator_->InjectMalformedHand(1);
  ASSERT_TRUE(WaitFor([&] {
    const EmulatorStats stats = emulator_->stats();
    return stats.hand_corrupted - emu0.hand_corrupted == 2 &&
           stats.hand_malformed - emu0.hand_malformed == 1 && stats.hand_dropped - emu0.hand_dropped == 3;
  }));
  const uint64_t messages = backend_->link()->hand_counters().messages;
  ASSERT_TRUE(WaitFor([&] { return backend_->link()->hand_counters().messages > messages + 5; }));
  const HandCounters hand = backend_->link()->hand_counters();
  EXPECT_EQ(backend_->counters().corrupt - corrupt0, 3u);  // 2 CRC/COBS + 1 digit count
  EXPECT_EQ(hand.malformed - hand0.malformed, 1u);
  const uint64_t overflowed = emulator_->stats().hand_overflowed - emu0.hand_overflowed;
  EXPECT_EQ(hand.dropped - hand0.dropped, 2u + 3u + 1u + overflowed);
  EXPECT_EQ(hand.late, 0u);
  EXPECT_EQ(backend_->counters().sessions, 1u);
  EXPECT_TRUE(backend_->link()->connected());
}

}  // namespace
}  // namespace graspbed::hardware
