#pragma once
/// EmulatedHand: the simulated hand behind `graspbed emulate`'s device callbacks, so a host's control
/// loop (`graspbed run --backend serial`, `graspbed hw`) closes over the wire against physics. The
/// scenario's script moves the wrist and the object; grasp intent belongs to the host's controller, so
/// close/open actions are not played (ScriptPlayer gives them to a controller nobody ticks).
/// Simulated time starts with the first stream start and advances one sensor period per Frame(). The
/// outcome is scored as `graspbed run` scores it (MetricsTracker on the ground truth, once per frame)
/// while the host is in control, and frozen when the host first stops streaming.
/// Frame() and Motor() run on the emulator's thread; the accessors may be called from any thread.

#include <atomic>
#include <chrono>
#include <mutex>

#include <nlohmann/json.hpp>

#include "hand/hand_command.h"
#include "hand/hand_state.h"
#include "sensor/layout.h"
#include "sensor/raw_frame.h"
#include "sensor/tactile_state.h"
#include "sim/sim_rig.h"
#include "testbed/metrics.h"
#include "testbed/scenario_config.h"
#include "testbed/script_player.h"

namespace graspbed::testbed {

class EmulatedHand {
 public:
  /// Builds the rig of `config` (RigConfigFor, without simulated frame drops: link faults are the
  /// emulator's business). Throws std::invalid_argument as SimRig does.
  EmulatedHand(const ScenarioConfig& config, const sensor::Layout& layout);
  EmulatedHand(const EmulatedHand&) = delete;
  EmulatedHand& operator=(const EmulatedHand&) = delete;

  /// Advances the simulation by one sensor period once streaming has begun, and fills `frame`'s
  /// flags and resistances (frame->unit_count units) with the newest simulated sample (nominal R0
  /// before the first).
  void Frame(bool streaming, sensor::RawFrame* frame);
  /// The hand's proprioception (the rig's simulated encoders and motor current, the scenario's
  /// `proprioception:` profile) as of the newest Frame(): false before the first sample or when the
  /// profile is disabled. Emulator thread.
  bool Hand(hand::HandState* state) const;
  /// The motor state the device drives. A closing effort counts as the host's close, an opening
  /// one as its open (the motor going off is no decision of the host's).
  void Motor(const hand::HandCommand& command);

  /// Ground truth and the metrics of `graspbed run` (same keys, without those only the host's
  /// controller can score) as the host left the hand.
  nlohmann::json Summary() const;
  bool started() const { return started_.load(); }
  /// True once a host that streamed has stopped (the outcome is frozen).
  bool host_done() const { return host_done_.load(); }
  /// Simulated time [s].
  double sim_time_s() const;

 private:
  ScenarioConfig config_;
  sim::SimRig rig_;
  ScriptPlayer player_;
  MetricsTracker tracker_;
  sensor::TactileState no_estimate_;
  double period_s_;
  std::chrono::steady_clock::time_point wall_start_;
  double target_s_ = 0.0;
  std::atomic<bool> started_{false};
  std::atomic<bool> host_done_{false};
  controller::GraspIntent host_intent_ = controller::GraspIntent::kIdle;  ///< emulator thread only
  sensor::RawFrame latest_;
  hand::HandState latest_hand_;  ///< emulator thread only
  double initial_object_z_m_ = 0.0;
  mutable std::mutex mutex_;  // guards the values below, read by other threads
  double sim_time_s_ = 0.0;
  double outcome_time_s_ = 0.0;
  double outcome_wall_s_ = 0.0;
  double peak_squeeze_n_ = 0.0;
  double host_close_s_ = -1.0;  // simulated time of the host's first closing command; < 0 none
  sim::GroundTruth last_truth_;
  sim::PhysicsFault physics_fault_;
};

}  // namespace graspbed::testbed
