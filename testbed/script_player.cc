#include "testbed/script_player.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

namespace graspbed::testbed {
namespace {

// Distinct stream for frame drops so that adding a drop action does not shift the sensor noise.
constexpr uint64_t kDropStreamSalt = 0x5ce7a110d20f5ull;
// Times are sums of physics steps; this absorbs their rounding when comparing them [s].
constexpr double kTickEpsS = 1e-9;

std::string FormatSeconds(double value_s) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f s", value_s);
  return text;
}

// "lift after grasped (line 12)": how a message names an event action.
std::string EventActionName(const Action& action) {
  std::string name = std::string(ActionName(action.kind)) + " after " + EventName(action.after);
  if (action.line > 0) name += " (line " + std::to_string(action.line) + ")";
  return name;
}

}  // namespace

double ProfileProgress(Profile profile, double s) {
  s = std::clamp(s, 0.0, 1.0);
  if (profile == Profile::kLinear) return s;
  return s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
}

double ScriptPlayer::Ramp::At(double time_s) const {
  if (!active) return to;
  if (duration_s <= 0.0) return to;
  return from + (to - from) * ProfileProgress(profile, (time_s - start_s) / duration_s);
}

ScriptPlayer::ScriptPlayer(const ScenarioConfig& config)
    : script_(config.script),
      sensor_(config.sensor),
      grip_ceiling_n_(config.controller.grip_ceiling_n),
      timings_(config.script.size()),
      monitor_(config.metrics, config.controller.rate_hz),
      drop_rng_(config.seed ^ kDropStreamSalt) {
  for (size_t i = 0; i < script_.size(); ++i) {
    (script_[i].after == ScriptEvent::kNone ? fixed_actions_ : event_actions_).push_back(i);
  }
  // ScenarioConfig keeps them so; a script built in code may not.
  std::stable_sort(fixed_actions_.begin(), fixed_actions_.end(),
                   [&](size_t a, size_t b) { return script_[a].at_s < script_[b].at_s; });
}

void ScriptPlayer::Start(sim::SimRig& rig) {
  base_target_ = rig.simulation().wrist_target();
  const double mass = rig.simulation().object_mass_kg();
  mass_ = Ramp{mass, mass, 0.0, 0.0, Profile::kLinear, false};
  const double friction = rig.simulation().scene().object.friction;
  friction_ = Ramp{friction, friction, 0.0, 0.0, Profile::kLinear, false};
  if (grip_ceiling_n_ > 0.0) rig.controller().SetGripCeiling(grip_ceiling_n_);
  rig.controller().SetIntent(intent_);
}

void ScriptPlayer::Fire(const Action& action, double time_s, sim::SimRig& rig) {
  switch (action.kind) {
    case ActionKind::kClose:
    case ActionKind::kOpen:
    case ActionKind::kIdle:
      intent_ = action.kind == ActionKind::kClose  ? controller::GraspIntent::kClose
                : action.kind == ActionKind::kOpen ? controller::GraspIntent::kOpen
                                                   : controller::GraspIntent::kIdle;
      if (action.kind == ActionKind::kClose && first_close_time_s_ < 0.0) first_close_time_s_ = time_s;
      rig.controller().SetIntent(intent_);
      break;
    case ActionKind::kMove:
    case ActionKind::kLift: {
      // A new move starts where the wrist target is now (an unfinished move is cut short).
      move_from_ = base_target_;
      if (action.kind == ActionKind::kLift) {
        move_to_ = {base_target_[0], base_target_[1], base_target_[2] + action.height_m};
      } else if (action.relative) {
        for (int k = 0; k < 3; ++k) move_to_[k] = base_target_[k] + action.vector[k];
      } else {
        move_to_ = action.vector;
      }
      move_start_s_ = time_s;
      move_duration_s_ = action.duration_s;
      move_profile_ = action.profile;
      moving_ = true;
      break;
    }
    case ActionKind::kShake:
      shake_axis_ = action.vector;
      shake_start_s_ = time_s;
      shake_end_s_ = time_s + action.duration_s;
      shake_frequency_hz_ = action.frequency_hz;
      shake_amplitude_m_ = action.amplitude_m;
      shake_ramp_s_ = action.ramp_s;
      break;
    case ActionKind::kAddMass: {
      // From the mass now to the previous target plus this step: overlapping ramps add up.
      const double now = mass_.At(time_s);
      // The total stays within the bounds of object.mass_kg (an empty cup keeps its own mass).
      const double target =
          std::clamp(mass_.to + action.mass_kg, sim::kMinObjectMassKg, sim::kMaxObjectMassKg);
      mass_ = Ramp{now, target, time_s, action.ramp_s, action.profile, true};
      break;
    }
    case ActionKind::kSetFriction:
      friction_ = Ramp{friction_.At(time_s), action.friction, time_s, action.ramp_s, action.profile, true};
      break;
    case ActionKind::kPull:
      for (int k = 0; k < 3; ++k) {
        force_[k] = Ramp{force_now_[k], action.vector[k], time_s, action.ramp_s, action.profile, true};
      }
      force_release_s_ = action.duration_s > 0.0 ? time_s + action.ramp_s + action.duration_s : -1.0;
      break;
    case ActionKind::kDeadUnit:
      rig.backend().strain_model().SetUnitFault(action.unit, sensor::UnitFault::kOpen);
      break;
    case ActionKind::kShortUnit:
      rig.backend().strain_model().SetUnitFault(action.unit, sensor::UnitFault::kShort);
      break;
    case ActionKind::kRestoreUnit:
      rig.backend().strain_model().SetUnitFault(action.unit, sensor::UnitFault::kNone);
      break;
    case ActionKind::kBias:
      rig.backend().strain_model().SetBiasOhm(action.unit, action.r1_bias_ohm, action.r2_bias_ohm);
      break;
    case ActionKind::kNoiseBurst:
      rig.backend().strain_model().SetNoiseScale(action.noise_scale);
      noise_end_s_ = time_s + action.duration_s;
      break;
    case ActionKind::kDropFrames:
      drop_start_s_ = time_s;
      drop_end_s_ = time_s + action.duration_s;
      drop_probability_ = action.probability;
      next_drop_sample_ = static_cast<int64_t>(std::ceil(time_s * sensor_.sample_rate_hz - 1e-9));
      break;
    case ActionKind::kAddLatency:
      added_latency_s_ += action.latency_s;
      rig.backend().SetLatency(sensor_.latency_s + added_latency_s_);
      break;
  }
}

void ScriptPlayer::Observe(double time_s, const sensor::TactileState& state, bool slip_flag) {
  if (event_actions_.empty()) return;  // nothing waits: no need to decide events
  tick_events_ = monitor_.Update(time_s, intent_, state, slip_flag);
  tick_time_s_ = time_s;
}

void ScriptPlayer::UpdateEventActions(double time_s, sim::SimRig& rig) {
  for (const size_t i : event_actions_) {
    const Action& action = script_[i];
    ActionTiming& timing = timings_[i];
    if (timing.fired_s >= 0.0 || timing.timed_out_s >= 0.0) continue;
    if (timing.armed_s < 0.0) {
      const double before_fired_s = i == 0 ? 0.0 : timings_[i - 1].fired_s;
      if (before_fired_s < 0.0) continue;
      timing.armed_s = before_fired_s;
    }
    if (timing.event_s < 0.0) {
      // The latest tick counts when it is not older than the arming (a chain fires in one call).
      if (tick_time_s_ >= timing.armed_s - kTickEpsS && (tick_events_ & EventBit(action.after)) != 0) {
        timing.event_s = tick_time_s_;
      } else {
        if (time_s >= timing.armed_s + action.timeout_s - kTickEpsS) timing.timed_out_s = time_s;
        continue;
      }
    }
    if (time_s >= timing.event_s + action.delay_s - kTickEpsS) {
      Fire(action, time_s, rig);
      timing.fired_s = time_s;
      ++fired_count_;
    }
  }
}

void ScriptPlayer::Update(double time_s, sim::SimRig& rig) {
  while (next_fixed_ < fixed_actions_.size() && script_[fixed_actions_[next_fixed_]].at_s <= time_s) {
    const size_t i = fixed_actions_[next_fixed_];
    Fire(script_[i], time_s, rig);
    timings_[i].fired_s = time_s;
    ++fired_count_;
    ++next_fixed_;
  }
  if (!event_actions_.empty()) UpdateEventActions(time_s, rig);

  // Wrist: trajectory plus shake.
  if (moving_) {
    const double s = move_duration_s_ > 0.0 ? (time_s - move_start_s_) / move_duration_s_ : 1.0;
    const double progress = ProfileProgress(move_profile_, s);
    for (int k = 0; k < 3; ++k) base_target_[k] = move_from_[k] + (move_to_[k] - move_from_[k]) * progress;
    if (s >= 1.0) moving_ = false;
  }
  std::array<double, 3> target = base_target_;
  if (time_s < shake_end_s_) {
    // Faded in and out by a raised cosine: position and velocity start and end at
    // the trajectory's. A sine switched on at full speed (0.2 m/s at 4 Hz, +-8 mm) jerked the wrist
    // in one step, a blow no arm delivers.
    const double since_s = time_s - shake_start_s_;
    const double edge_s = std::min(since_s, shake_end_s_ - time_s);
    const double envelope =
        edge_s >= shake_ramp_s_
            ? 1.0
            : 0.5 * (1.0 - std::cos(std::numbers::pi * std::max(edge_s, 0.0) / shake_ramp_s_));
    const double offset =
        envelope * shake_amplitude_m_ * std::sin(2.0 * std::numbers::pi * shake_frequency_hz_ * since_s);
    for (int k = 0; k < 3; ++k) target[k] += offset * shake_axis_[k];
  }
  rig.simulation().SetWristTarget(target);

  // Object.
  if (mass_.active) {
    rig.simulation().SetObjectMass(mass_.At(time_s));
    if (time_s >= mass_.start_s + mass_.duration_s) mass_.active = false;
  }
  if (friction_.active) {
    rig.simulation().SetObjectFriction(friction_.At(time_s));
    if (time_s >= friction_.start_s + friction_.duration_s) friction_.active = false;
  }
  if (force_release_s_ >= 0.0 && time_s >= force_release_s_) {
    for (Ramp& ramp : force_) ramp = Ramp{0.0, 0.0, time_s, 0.0, Profile::kLinear, true};
    force_release_s_ = -1.0;
  }
  bool force_changing = false;
  for (int k = 0; k < 3; ++k) {
    if (!force_[k].active) continue;
    force_now_[k] = force_[k].At(time_s);
    force_changing = true;
    if (time_s >= force_[k].start_s + force_[k].duration_s) force_[k].active = false;
  }
  if (force_changing) rig.simulation().SetObjectExternalForce(force_now_);

  // Sensor faults that end.
  if (noise_end_s_ >= 0.0 && time_s >= noise_end_s_) {
    rig.backend().strain_model().SetNoiseScale(1.0);
    noise_end_s_ = -1.0;
  }
  if (drop_end_s_ >= 0.0) {
    // One draw per sensor sample in the window; a drawn loss drops the next sampled frame.
    while (static_cast<double>(next_drop_sample_) / sensor_.sample_rate_hz <= time_s) {
      const double sample_time_s = static_cast<double>(next_drop_sample_) / sensor_.sample_rate_hz;
      if (sample_time_s >= drop_end_s_) {
        drop_end_s_ = -1.0;
        break;
      }
      if (sample_time_s >= drop_start_s_ && uniform_(drop_rng_) < drop_probability_) {
        rig.backend().DropNextFrames(1);
      }
      ++next_drop_sample_;
    }
  }
}

std::vector<ExpectationOutcome> ScriptPlayer::EventOutcomes(double end_s) const {
  std::vector<ExpectationOutcome> outcomes;
  for (const size_t i : event_actions_) {
    const Action& action = script_[i];
    const ActionTiming& timing = timings_[i];
    ExpectationOutcome outcome;
    outcome.name = "script: " + EventActionName(action);
    outcome.limit = std::string(EventName(action.after)) + " within " + FormatSeconds(action.timeout_s);
    if (timing.event_s >= 0.0) outcome.value = timing.event_s - timing.armed_s;
    if (timing.fired_s >= 0.0) {
      outcome.passed = true;
      outcome.value_text = "after " + FormatSeconds(timing.event_s - timing.armed_s);
      outcome.note = "armed at " + FormatSeconds(timing.armed_s) + ", event at " +
                     FormatSeconds(timing.event_s) + ", fired at " + FormatSeconds(timing.fired_s);
    } else if (timing.timed_out_s >= 0.0) {
      outcome.value_text = "none by " + FormatSeconds(timing.timed_out_s);
      outcome.note = "timed out: no " + std::string(EventName(action.after)) + " within " +
                     FormatSeconds(action.timeout_s) + " of arming at " + FormatSeconds(timing.armed_s) +
                     "; the action did not run";
    } else if (timing.armed_s < 0.0) {
      outcome.value_text = "not armed";
      outcome.note = "the action before it in the script never ran, so this one did not either";
    } else if (timing.event_s < 0.0) {
      outcome.value_text = "none by " + FormatSeconds(end_s);
      outcome.note = "the run ended " + FormatSeconds(end_s - timing.armed_s) + " after arming at " +
                     FormatSeconds(timing.armed_s) + ", before the event; the action did not run";
    } else {
      outcome.value_text = "after " + FormatSeconds(timing.event_s - timing.armed_s);
      outcome.note = "event at " + FormatSeconds(timing.event_s) +
                     ", but the run ended before its delay of " + FormatSeconds(action.delay_s) +
                     " passed; the action did not run";
    }
    outcomes.push_back(outcome);
  }
  return outcomes;
}

}  // namespace graspbed::testbed
