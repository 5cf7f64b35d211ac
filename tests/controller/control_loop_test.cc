// ControlLoop with a backend that replays scripted frames and an actuator that records: taring,
// inversion of loaded frames, staleness when frames stop, re-tare on a new device session, actuator
// failures counted, refusal of a unit-count mismatch, and no allocation per tick.
#include "controller/control_loop.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "controller/grip_slip_controller.h"
#include "sensor/strain_model.h"
#include "tests/support/allocation_counter.h"

namespace graspbed::controller {
namespace {

using ::testing::HasSubstr;

constexpr double kForceTolN = 1e-6;
constexpr double kTickS = 1e-3;
constexpr int kTareFrames = 10;

/// Replays what the test queues: one frame per Read() while any is queued, then kNoNewFrame (or
/// the status the test forces).
class ScriptedBackend final : public sensor::TactileBackend {
 public:
  explicit ScriptedBackend(int unit_count) : unit_count_(unit_count) {}

  void Queue(const sensor::RawFrame& frame) { queue_.push_back(frame); }
  void ForceStatus(sensor::ReadStatus status) { forced_ = status; }
  void NewSession() { ++session_; }

  sensor::ReadStatus Read(sensor::RawFrame* frame) override {
    if (forced_ != sensor::ReadStatus::kOk) return forced_;
    if (next_ >= queue_.size()) return sensor::ReadStatus::kNoNewFrame;
    *frame = queue_[next_++];
    return sensor::ReadStatus::kOk;
  }
  int unit_count() const override { return unit_count_; }
  double nominal_r0_ohm() const override { return sensor::UnitConstants{}.r0_ohm; }
  uint64_t session() const override { return session_; }
  std::string name() const override { return "scripted"; }

 private:
  int unit_count_;
  std::vector<sensor::RawFrame> queue_;
  size_t next_ = 0;
  sensor::ReadStatus forced_ = sensor::ReadStatus::kOk;
  uint64_t session_ = 0;
};

/// Records every command; can be told to report a disconnected motor.
class RecordingActuator final : public hand::HandActuator {
 public:
  hand::WriteStatus Write(const hand::HandCommand& command) override {
    last = command;
    ++writes;
    return disconnected ? hand::WriteStatus::kDisconnected : hand::WriteStatus::kOk;
  }
  std::string name() const override { return "recording"; }

  hand::HandCommand last;
  int writes = 0;
  bool disconnected = false;
};

/// Remembers what the loop showed it.
class RecordingController final : public GraspController {
 public:
  void Reset() override {}
  void SetIntent(GraspIntent) override {}
  hand::HandCommand Update(const sensor::TactileState& state, const hand::HandState&, double) override {
    last_stale = state.stale;
    last_total_fn_n = state.total_fn_n;
    ++updates;
    hand::HandCommand command;
    command.grip_effort = 0.25;
    return command;
  }
  void SetGripCeiling(double) override {}
  ControllerTelemetry telemetry() const override { return {}; }
  std::string name() const override { return "recording"; }

  bool last_stale = false;
  double last_total_fn_n = 0.0;
  int updates = 0;
};

/// A frame of `layout` with `fn_n` / `ft_n` on unit `loaded` (paper constants) and every other unit at
/// rest; all gauges share the nominal R0 (`r0_scale` x nominal, to model a rebooted device).
sensor::RawFrame Frame(const sensor::Layout& layout, uint32_t sequence, int loaded, double fn_n, double ft_n,
                       double r0_scale = 1.0) {
  sensor::UnitConstants constants;
  constants.r0_ohm *= r0_scale;
  sensor::RawFrame frame;
  frame.sequence = sequence;
  frame.time_s = sequence * kTickS;
  frame.unit_count = layout.unit_count();
  for (int i = 0; i < layout.unit_count(); ++i) {
    const sensor::GaugeResistances r =
        sensor::IdealGaugeResistances(constants, i == loaded ? fn_n : 0.0, i == loaded ? ft_n : 0.0);
    frame.r1_ohm[static_cast<size_t>(i)] = r.r1_ohm;
    frame.r2_ohm[static_cast<size_t>(i)] = r.r2_ohm;
  }
  return frame;
}

class ControlLoopTest : public ::testing::Test {
 protected:
  ControlLoopTest() : backend_(layout_.unit_count()) {
    config_.readout.baseline_frames = kTareFrames;
    config_.stale_timeout_s = 0.0205;  // between two 1 ms ticks, clear of round-off
  }
  /// Queues the tare frames (no load) and ticks through them.
  void Tare(ControlLoop& loop) {
    for (int i = 0; i < kTareFrames; ++i) {
      backend_.Queue(Frame(layout_, ++sequence_, 0, 0.0, 0.0));
      loop.Tick(Now());
    }
  }
  double Now() { return (++ticks_) * kTickS; }

  const sensor::Layout layout_ = sensor::LoadLayout(sensor::DefaultLayoutPath());
  const sensor::Calibration calibration_ = sensor::PaperCalibration(layout_.unit_count());
  ControlLoopConfig config_;
  ScriptedBackend backend_;
  RecordingActuator actuator_;
  RecordingController controller_;
  uint32_t sequence_ = 0;
  int ticks_ = 0;
};

TEST_F(ControlLoopTest, StateIsStaleUntilTheFirstFrameAndTheCommandStillGoesOut) {
  ControlLoop loop(backend_, controller_, actuator_, layout_, calibration_, config_);
  EXPECT_TRUE(loop.state().stale);
  EXPECT_EQ(loop.Tick(Now()), sensor::ReadStatus::kNoNewFrame);
  EXPECT_TRUE(controller_.last_stale);
  EXPECT_EQ(actuator_.writes, 1);
  EXPECT_DOUBLE_EQ(actuator_.last.grip_effort, 0.25);
  EXPECT_EQ(loop.counters().stale_ticks, 1u);
}

TEST_F(ControlLoopTest, TaredFramesInvertToTheLoadOnTheUnit) {
  ControlLoop loop(backend_, controller_, actuator_, layout_, calibration_, config_);
  Tare(loop);
  backend_.Queue(Frame(layout_, ++sequence_, 6, 4.0, 1.5));
  EXPECT_EQ(loop.Tick(Now()), sensor::ReadStatus::kOk);
  EXPECT_FALSE(loop.state().stale);
  EXPECT_NEAR(loop.state().fn_n[6], 4.0, kForceTolN);
  EXPECT_NEAR(loop.state().ft_n[6], 1.5, kForceTolN);
  EXPECT_NEAR(loop.state().fn_n[5], 0.0, kForceTolN);
  EXPECT_NEAR(controller_.last_total_fn_n, 4.0, kForceTolN);
  EXPECT_EQ(loop.counters().frames, static_cast<uint64_t>(kTareFrames + 1));
}

TEST_F(ControlLoopTest, FramesStoppingMakeTheStateStaleAndFreshFramesClearIt) {
  ControlLoop loop(backend_, controller_, actuator_, layout_, calibration_, config_);
  Tare(loop);
  // 20 ms without a frame is still fresh; 21 ms is stale.
  for (int i = 0; i < 20; ++i) loop.Tick(Now());
  EXPECT_FALSE(controller_.last_stale);
  loop.Tick(Now());
  EXPECT_TRUE(controller_.last_stale);
  const uint64_t stale_ticks = loop.counters().stale_ticks;
  backend_.Queue(Frame(layout_, ++sequence_, 0, 0.0, 0.0));
  loop.Tick(Now());
  EXPECT_FALSE(controller_.last_stale);
  EXPECT_EQ(loop.counters().stale_ticks, stale_ticks);
}

TEST_F(ControlLoopTest, StaleAndDisconnectedBackendsAreStaleAtOnce) {
  ControlLoop loop(backend_, controller_, actuator_, layout_, calibration_, config_);
  Tare(loop);
  backend_.ForceStatus(sensor::ReadStatus::kDisconnected);
  EXPECT_EQ(loop.Tick(Now()), sensor::ReadStatus::kDisconnected);
  EXPECT_TRUE(controller_.last_stale);
  EXPECT_EQ(loop.counters().disconnected_ticks, 1u);
  backend_.ForceStatus(sensor::ReadStatus::kStale);
  loop.Tick(Now());
  EXPECT_TRUE(controller_.last_stale);
}

TEST_F(ControlLoopTest, ANewDeviceSessionRetaresOnItsOwnFrames) {
  ControlLoop loop(backend_, controller_, actuator_, layout_, calibration_, config_);
  Tare(loop);
  // The device reboots with gauges 2 % higher at rest: without a re-tare that reads as load.
  backend_.NewSession();
  for (int i = 0; i < kTareFrames; ++i) {
    backend_.Queue(Frame(layout_, ++sequence_, 0, 0.0, 0.0, 1.02));
    loop.Tick(Now());
  }
  EXPECT_EQ(loop.counters().retares, 1u);
  backend_.Queue(Frame(layout_, ++sequence_, 3, 2.0, 0.0, 1.02));
  loop.Tick(Now());
  EXPECT_NEAR(loop.state().fn_n[3], 2.0, 1e-3);
  EXPECT_NEAR(loop.state().fn_n[4], 0.0, 1e-3);
}

TEST_F(ControlLoopTest, ActuatorFailuresAreCountedNotThrown) {
  ControlLoop loop(backend_, controller_, actuator_, layout_, calibration_, config_);
  actuator_.disconnected = true;
  loop.Tick(Now());
  loop.Tick(Now());
  EXPECT_EQ(loop.counters().actuator_failures, 2u);
  EXPECT_EQ(loop.counters().ticks, 2u);
}

TEST_F(ControlLoopTest, UnitCountMismatchAndBadConfigAreRefused) {
  ScriptedBackend nine_units(9);
  try {
    ControlLoop loop(nine_units, controller_, actuator_, layout_, calibration_, config_);
    FAIL() << "a 9-unit backend was accepted for a 20-unit layout";
  } catch (const std::invalid_argument& error) {
    EXPECT_THAT(error.what(), HasSubstr("backend 'scripted' delivers 9 units"));
    EXPECT_THAT(error.what(), HasSubstr("has 20"));
  }
  ControlLoopConfig bad = config_;
  bad.stale_timeout_s = -1.0;
  try {
    ControlLoop loop(backend_, controller_, actuator_, layout_, calibration_, bad);
    FAIL() << "a negative stale timeout was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_THAT(error.what(), HasSubstr("stale_timeout_s = -1"));
  }
}

TEST_F(ControlLoopTest, TickAllocatesNothingWithTheReferenceController) {
  GripSlipController grip_slip{GripSlipConfig{}};
  grip_slip.SetIntent(GraspIntent::kClose);
  ControlLoop loop(backend_, grip_slip, actuator_, layout_, calibration_, config_);
  Tare(loop);
  for (int i = 0; i < 200; ++i) backend_.Queue(Frame(layout_, ++sequence_, 6, 0.01 * i, 0.0));
  const long before = graspbed::test_support::AllocationCount();
  for (int i = 0; i < 300; ++i) loop.Tick(Now());  // frames, then 100 ticks going stale
  EXPECT_EQ(graspbed::test_support::AllocationCount() - before, 0);
  EXPECT_GT(loop.counters().stale_ticks, 0u);
}

}  // namespace
}  // namespace graspbed::controller
