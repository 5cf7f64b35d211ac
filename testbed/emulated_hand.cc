#include "testbed/emulated_hand.h"

#include <algorithm>

#include "controller/grasp_controller.h"
#include "sensor/calibration.h"
#include "testbed/runner.h"

namespace graspbed::testbed {
namespace {

sim::SimRigConfig EmulatorRigConfig(const ScenarioConfig& config) {
  sim::SimRigConfig rig = RigConfigFor(config);
  rig.backend.drop_probability = 0.0;  // link faults are the emulator's business here
  return rig;
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

EmulatedHand::EmulatedHand(const ScenarioConfig& config, const sensor::Layout& layout)
    : config_(config),
      rig_(layout, sensor::PaperCalibration(layout.unit_count()), EmulatorRigConfig(config),
           controller::MakeController("open_loop", {})),
      player_(config),
      tracker_(config.metrics, config.scene.object.crush_limit_n,
               config.sensor.inversion.contact_threshold_n),
      period_s_(1.0 / config.sensor.sample_rate_hz),
      wall_start_(std::chrono::steady_clock::now()) {
  player_.Start(rig_);
  rig_.simulation().set_sliding_friction_fraction(config.metrics.sliding_friction_fraction);
  initial_object_z_m_ = rig_.simulation().truth().object_position_m[2];
  // The tracker sees no estimates (the host has them): a stale state keeps it to ground truth.
  no_estimate_.stale = true;
}

void EmulatedHand::Frame(bool streaming, sensor::RawFrame* frame) {
  if (streaming) started_ = true;
  if (started_ && !streaming) host_done_ = true;
  if (started_) {
    target_s_ += period_s_;
    sim::Simulation& simulation = rig_.simulation();
    // The physics steps that end by the frame's time; a physics step longer than the frame period
    // leaves the frame sampling the last step's state (zero-order hold), as SimRig::Step does.
    const double slack_s = 1e-6 * period_s_;
    while (simulation.time_s() + simulation.timestep_s() <= target_s_ + slack_s) {
      player_.Update(simulation.time_s(), rig_);
      simulation.Step();
    }
    rig_.backend().Poll(target_s_);
    rig_.hand_sensor().Poll(target_s_);
    const sim::GroundTruth truth = simulation.truth();
    std::lock_guard lock(mutex_);
    sim_time_s_ = simulation.time_s();
    if (!host_done_) {
      TickSample sample;
      sample.time_s = sim_time_s_;
      sample.intent = host_intent_;  // the host's controller closes and opens, not the script
      sample.truth = &truth;
      sample.state = &no_estimate_;
      tracker_.Update(sample);
      outcome_time_s_ = sim_time_s_;
      outcome_wall_s_ = SecondsSince(wall_start_);
      peak_squeeze_n_ = std::max(peak_squeeze_n_, truth.object_squeeze_n);
      last_truth_ = truth;
      physics_fault_ = rig_.simulation().fault();
    }
  }
  sensor::RawFrame fresh;
  while (rig_.backend().Read(&fresh) == sensor::ReadStatus::kOk) latest_ = fresh;
  if (started_) rig_.hand_sensor().Read(target_s_, &latest_hand_);
  if (latest_.unit_count == 0) {  // nothing sampled yet: unloaded gauges
    latest_.unit_count = frame->unit_count;
    latest_.r1_ohm.fill(rig_.backend().nominal_r0_ohm());
    latest_.r2_ohm.fill(rig_.backend().nominal_r0_ohm());
  }
  frame->flags = latest_.flags;
  std::copy_n(latest_.r1_ohm.begin(), frame->unit_count, frame->r1_ohm.begin());
  std::copy_n(latest_.r2_ohm.begin(), frame->unit_count, frame->r2_ohm.begin());
}

bool EmulatedHand::Hand(hand::HandState* state) const {
  if (latest_hand_.digit_count == 0) return false;
  *state = latest_hand_;
  return true;
}

void EmulatedHand::Motor(const hand::HandCommand& command) {
  rig_.actuator().Write(command);
  if (command.enable && command.grip_effort > 0.0) host_intent_ = controller::GraspIntent::kClose;
  if (command.enable && command.grip_effort < 0.0) host_intent_ = controller::GraspIntent::kOpen;
  if (host_intent_ == controller::GraspIntent::kClose) {
    std::lock_guard lock(mutex_);
    if (host_close_s_ < 0.0) host_close_s_ = rig_.simulation().time_s();
  }
}

double EmulatedHand::sim_time_s() const {
  std::lock_guard lock(mutex_);
  return sim_time_s_;
}

nlohmann::json EmulatedHand::Summary() const {
  std::lock_guard lock(mutex_);
  RunResult result;
  result.config = config_;
  result.metrics = tracker_.Finish(outcome_time_s_, outcome_wall_s_, player_.first_close_time_s());
  result.metrics.physics_fault = physics_fault_.occurred;
  result.metrics.physics_fault_cause = physics_fault_.occurred ? physics_fault_.cause_text() : "";
  result.metrics.physics_fault_time_s = physics_fault_.time_s;
  nlohmann::json metrics = SummaryJson(result)["metrics"];
  // The host's controller, not the emulator, sees slip flags and estimates: leave out what it
  // cannot score.
  for (const char* key :
       {"slip_detect_latency_ms", "false_slip_per_min", "fn_rmse_n", "ft_rmse_n", "missed_slip_events",
        "missed_unsensed_slip_events", "missed_thumb_only_slip_events", "controller_slip_flags",
        "false_slip_flags", "false_slip_flags_by_cue", "incipient_slip_flags", "false_slip_flag_s",
        "false_slip_flag_pct", "estimation_samples", "gross_slip_detected", "gross_detect_latency_ms",
        "micro_slip_detected", "micro_detect_latency_ms"}) {
    metrics.erase(key);
  }
  return {
      {"sim_time_s", outcome_time_s_},
      {"host_close_time_s", host_close_s_ >= 0.0 ? nlohmann::json(host_close_s_) : nlohmann::json(nullptr)},
      {"object_lift_m", last_truth_.object_position_m[2] - initial_object_z_m_},
      {"object_height_above_table_m", last_truth_.object_height_above_table_m},
      {"peak_squeeze_n", peak_squeeze_n_},
      {"final_squeeze_n", last_truth_.object_squeeze_n},
      {"finger_contacts", last_truth_.finger_contacts},
      {"thumb_contacts", last_truth_.thumb_contacts},
      {"metrics", metrics},
  };
}

}  // namespace graspbed::testbed
