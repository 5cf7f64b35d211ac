#include "testbed/metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace graspbed::testbed {
namespace {

std::string Format(double value, const char* unit, int precision = 3) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*g%s%s", precision, value, unit[0] ? " " : "", unit);
  return buffer;
}

ExpectationOutcome Outcome(const std::string& name, const std::string& limit) {
  ExpectationOutcome outcome;
  outcome.name = name;
  outcome.limit = limit;
  return outcome;
}

// grasped_on_sensor: a held object the units did not feel makes every other verdict of the run
// about the grasp, not the controller.
ExpectationOutcome GraspedOnSensor(const Metrics& m, const MetricsConfig& config) {
  ExpectationOutcome o = Outcome("grasped_on_sensor", "true");
  if (m.held_s <= 0.0) {
    o.value_text = "never held";
    o.passed = true;
    o.note = "nothing was held to sense (not_dropped speaks for that)";
    return o;
  }
  const double share = m.sensed_grip_share.value_or(0.0);
  o.value = share;
  o.value_text = "sensed share " + Format(share, "") + ", unsensed " + Format(m.unsensed_held_s, "s") + " of " +
                 Format(m.held_s, "s") + " held";
  const bool unsensed = m.unsensed_held_s > config.max_unsensed_held_s;
  const bool light = share < config.min_sensed_grip_share;
  o.passed = !unsensed && !light;
  if (unsensed) {
    o.note = "held for " + Format(m.unsensed_held_s, "s") + " with no unit loaded (limit " +
             Format(config.max_unsensed_held_s, "s") + "): the object is not on the sensorised pad";
  } else if (light) {
    o.note = "the units carried " + Format(share, "") + " of the finger's squeeze (floor " +
             Format(config.min_sensed_grip_share, "") + "): the squeeze goes through the finger beside the pad";
  }
  return o;
}

}  // namespace

MetricsTracker::MetricsTracker(const MetricsConfig& config, double crush_limit_n, double contact_threshold_n)
    : config_(config), crush_limit_n_(crush_limit_n), contact_threshold_n_(contact_threshold_n) {}

void MetricsTracker::OpenEvent(double time_s, double onset_s) {
  event_open_ = true;
  current_ = SlipEvent{};
  current_.onset_s = onset_s;
  current_.end_s = time_s;
  last_above_s_ = time_s;
  // A flag still raised at the onset detects it if it rose within the early window (the controller
  // reports slip as it starts); a flag left up since long before says nothing about this slip.
  if (previous_flag_ && last_rise_s_ >= onset_s - config_.early_detection_window_s) {
    current_.detected = true;
    current_.latency_s = std::max(0.0, last_rise_s_ - onset_s);
  }
  // A flag shortly before the onset detected the slip early (incipient slip); one since the onset of
  // a creep (opened only once it had crept far enough) detected it that much after the onset.
  const double window_start = onset_s - config_.early_detection_window_s;
  for (int i = 0; i < pending_count_; ++i) {
    if (pending_flags_[i].time_s >= window_start) {
      const double latency_s = std::max(0.0, pending_flags_[i].time_s - onset_s);
      if (!current_.detected || latency_s < current_.latency_s) {
        current_.detected = true;
        current_.latency_s = latency_s;
      }
    } else {
      JudgeUnmatchedFlag(pending_flags_[i]);  // older than the window: it matched nothing
    }
  }
  pending_count_ = 0;
}

void MetricsTracker::NoteEventTick(const TickSample& sample, double digit_speed_m_s) {
  const sim::GroundTruth& truth = *sample.truth;
  current_.finger_slid = current_.finger_slid || truth.finger_sliding_speed_m_s > digit_speed_m_s;
  current_.thumb_slid = current_.thumb_slid || truth.thumb_sliding_speed_m_s > digit_speed_m_s;
  for (size_t u = 0; u < sample.true_loads.size() && !current_.sensed; ++u)
    current_.sensed = sample.true_loads[u].fn_n >= contact_threshold_n_;
}

void MetricsTracker::CloseEvent() {
  event_open_ = false;
  current_.gross = current_.ends_in_drop || current_.distance_m >= config_.gross_slip_m;
  const size_t slip_class = current_.gross ? 1 : 0;
  ++class_events_[slip_class];
  if (current_.detected) {
    worst_latency_s_ = std::max(worst_latency_s_, current_.latency_s);
    ++class_detected_[slip_class];
    class_worst_latency_s_[slip_class] = std::max(class_worst_latency_s_[slip_class], current_.latency_s);
  } else {
    ++missed_;
    if (!current_.sensed) ++missed_unsensed_;
    if (current_.thumb_slid && !current_.finger_slid) ++missed_thumb_only_;
  }
  if (event_count_ < kMaxEvents) events_[event_count_] = current_;
  ++event_count_;
}

void MetricsTracker::OnControllerFlag(double time_s, const char* cues) {
  ++flags_;
  if (event_open_) {
    if (!current_.detected) {
      current_.detected = true;
      current_.latency_s = std::max(0.0, time_s - current_.onset_s);
    }
    return;  // a repeated flag during an event is no false alarm
  }
  if (pending_count_ == static_cast<int>(pending_flags_.size())) {
    JudgeUnmatchedFlag(pending_flags_[0]);  // window full of flags: the oldest cannot all be early detections
    std::copy(pending_flags_.begin() + 1, pending_flags_.end(), pending_flags_.begin());
    --pending_count_;
  }
  pending_flags_[pending_count_++] = {time_s, last_sliding_s_ >= time_s - config_.early_detection_window_s,
                                      cues != nullptr ? cues : ""};
}

void MetricsTracker::JudgeUnmatchedFlag(const PendingFlag& flag) {
  if (flag.after_sliding) {
    ++incipient_flags_;
    return;
  }
  ++false_flags_;
  for (int i = 0; i < cue_labels_; ++i) {
    if (std::strcmp(false_by_cue_[static_cast<size_t>(i)].cues, flag.cues) == 0) {
      ++false_by_cue_[static_cast<size_t>(i)].false_flags;
      return;
    }
  }
  if (cue_labels_ < kMaxCueLabels) {
    false_by_cue_[static_cast<size_t>(cue_labels_++)] = {flag.cues, 1};
  } else {
    ++false_other_cues_;
  }
}

void MetricsTracker::Update(const TickSample& sample) {
  const sim::GroundTruth& truth = *sample.truth;
  const double t = sample.time_s;
  // Time never runs backwards here (the run ends at a physics fault); if it did, nothing accrues.
  const double dt = last_time_s_ < 0.0 ? 0.0 : std::max(0.0, t - last_time_s_);
  last_time_s_ = t;

  peak_grip_n_ = std::max(peak_grip_n_, truth.object_squeeze_n);
  UpdateGrasp(sample, dt);
  UpdateSlip(sample, dt);
  UpdateEstimationError(sample);
  UpdateStableGrasp(truth.object_squeeze_n, t);
}

void MetricsTracker::UpdateGrasp(const TickSample& sample, double dt) {
  const sim::GroundTruth& truth = *sample.truth;
  const double t = sample.time_s;
  // Grasp state: acquired from the digits' first touch until established (UpdateAcquisition) after a
  // close; lost (for scoring) when the intent changes.
  const bool closing = sample.intent == controller::GraspIntent::kClose;
  if (closing_ && !closing && !grasped_) ++ungrasped_closes_;
  if (closing && !closing_) {
    for (int k = 0; k < 3; ++k) close_offset_m_[k] = truth.object_position_m[k] - truth.wrist_position_m[k];
  }
  closing_ = closing;
  if (!closing) {
    if (holding_ && event_open_) CloseEvent();
    grasped_ = false;
    holding_ = false;
    touching_ = false;
  } else if (!grasped_) {
    UpdateAcquisition(sample);
  }
  const bool was_holding = holding_;
  holding_ = closing && grasped_ && !dropped_;
  if (was_holding) held_s_ += dt;

  if (was_holding) held_grip_integral_n_s_ += truth.object_squeeze_n * dt;
  if (was_holding) UpdateSensorContact(sample, dt);
  if (holding_) {
    peak_load_bound_grip_n_ = std::max(peak_load_bound_grip_n_, truth.load_bound_grip_n);
    double squared = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double d = truth.object_position_m[k] - truth.wrist_position_m[k] - reference_offset_m_[k];
      squared += d * d;
    }
    if (std::sqrt(squared) > config_.drop_distance_m) {
      dropped_ = true;
      drop_time_s_ = t;
      // A drop is the grossest slip: the open event ends in it, or it is an event of its own, which
      // closes at once (the object is no longer held, so nothing else would close it).
      const bool own_event = !event_open_;
      if (own_event) OpenEvent(t, t);
      current_.ends_in_drop = true;
      NoteEventTick(sample, config_.creep_speed_m_s);
      if (own_event) CloseEvent();
    }
  }
}

namespace {

double Distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

}  // namespace

void MetricsTracker::UpdateAcquisition(const TickSample& sample) {
  const sim::GroundTruth& truth = *sample.truth;
  const double t = sample.time_s;
  std::array<double, 3> offset{};
  for (int k = 0; k < 3; ++k) offset[k] = truth.object_position_m[k] - truth.wrist_position_m[k];
  if (!touching_) {
    if (truth.finger_contacts == 0 || truth.thumb_contacts == 0 ||
        truth.finger_normal_force_n < config_.grasp_force_n)
      return;
    touching_ = true;
    if (contact_time_s_ < 0.0) contact_time_s_ = t;
    contact_start_s_ = t;
    touch_offset_m_ = offset;
    touch_wrist_m_ = truth.wrist_position_m;
    settle_offset_m_ = offset;
    settle_start_s_ = t;
  }
  const double shift_m = Distance(offset, touch_offset_m_);
  acquisition_shift_m_ = std::max(acquisition_shift_m_, shift_m);
  if (Distance(offset, close_offset_m_) > config_.drop_distance_m) {
    // Pushed out, knocked over, or left behind by a wrist that moved on before the digits closed:
    // a failed grasp, and a drop of the run (timed at the first).
    pushed_out_ = true;
    if (!dropped_) drop_time_s_ = t;
    dropped_ = true;
    return;
  }
  if (Distance(offset, settle_offset_m_) > config_.acquisition_settle_m) {
    settle_offset_m_ = offset;
    settle_start_s_ = t;
  }
  // Established once the hand carries the object's weight, the digits have seated on it, the wrist
  // loads the grasp or the time is up: whatever the object did before (pushed along the table,
  // turned onto a pad) is acquisition.
  const bool lifted = truth.object_height_above_table_m >= config_.acquisition_lift_m;
  const bool settled = t - settle_start_s_ >= config_.acquisition_settle_s;
  const bool wrist_moved = Distance(truth.wrist_position_m, touch_wrist_m_) >= config_.acquisition_wrist_m;
  const bool time_up = t - contact_start_s_ >= config_.acquisition_max_s;
  if (!lifted && !settled && !wrist_moved && !time_up) return;
  grasped_ = true;
  grasp_start_s_ = t;
  if (!grasped_ever_) grasp_time_s_ = t;
  grasped_ever_ = true;
  reference_offset_m_ = offset;
}

void MetricsTracker::UpdateSensorContact(const TickSample& sample, double dt) {
  const sim::GroundTruth& truth = *sample.truth;
  sensed_integral_n_s_ += truth.sensed_object_normal_force_n * dt;
  finger_integral_n_s_ += truth.finger_object_normal_force_n * dt;
  bool loaded = false;
  const size_t units = std::min(sample.true_loads.size(), unit_integral_n_s_.size());
  for (size_t u = 0; u < units; ++u) {
    const double fn = sample.true_loads[u].fn_n;
    loaded = loaded || fn >= contact_threshold_n_;
    unit_integral_n_s_[u] += std::max(fn, 0.0) * dt;
  }
  // An object sliding out of the hand leaves the pad on its way: the slip event and the drop speak
  // for that time, not grasped_on_sensor.
  if (!loaded && !event_open_) unsensed_held_s_ += dt;
}

void MetricsTracker::UpdateSlip(const TickSample& sample, double dt) {
  const sim::GroundTruth& truth = *sample.truth;
  const double t = sample.time_s;
  // Slip distance, slip events and the controller's flags, all while held.
  const bool flag = sample.controller_slip;
  const bool rising_flag = flag && !previous_flag_;
  if (rising_flag) last_rise_s_ = t;
  previous_flag_ = flag;
  if (holding_) {
    // Slip needs the sliding contacts to carry a share of the digit's force; a contact at the edge of
    // the patch sliding alone is partial slip, which only makes a flag then incipient (below).
    const double sliding = truth.sliding_speed_m_s;
    const bool partial = truth.sliding_load_share < config_.slip_min_load_share;
    const double speed = partial ? 0.0 : sliding;
    if (partial && sliding > config_.creep_speed_m_s) partial_slip_distance_m_ += sliding * dt;
    if (speed > config_.creep_speed_m_s) {
      slip_distance_m_ += speed * dt;
      if (event_open_) current_.distance_m += speed * dt;
    }
    // The pads seating on the object right after the grasp is acquisition, not the held object
    // slipping: it opens no event and flags then match nothing (nor count as false).
    const bool seating = t < grasp_start_s_ + config_.seating_s;
    // A creep: sliding above creep speed, with gaps shorter than slip_event_gap_s, from its start.
    const bool creeping = !seating && speed > config_.creep_speed_m_s;
    if (creep_start_s_ >= 0.0 && !creeping && t - creep_last_s_ >= config_.slip_event_gap_s)
      creep_start_s_ = -1.0;
    if (creeping) {
      if (creep_start_s_ < 0.0) {
        creep_start_s_ = t;
        creep_distance_m_ = 0.0;
      }
      creep_distance_m_ += speed * dt;
      creep_last_s_ = t;
    }
    const bool creep_event =
        config_.creep_event_m > 0.0 && creep_start_s_ >= 0.0 && creep_distance_m_ >= config_.creep_event_m;
    if (seating) {
      if (rising_flag) ++flags_;
    } else if (speed > config_.slip_speed_m_s || (creep_event && creeping)) {
      if (!event_open_) {
        const bool fast = speed > config_.slip_speed_m_s;
        OpenEvent(t, fast ? t : creep_start_s_);
        if (!fast) current_.distance_m = creep_distance_m_;  // from its back-dated onset
      }
      last_above_s_ = t;
      current_.end_s = t;
      current_.peak_speed_m_s = std::max(current_.peak_speed_m_s, speed);
      NoteEventTick(sample, speed > config_.slip_speed_m_s ? config_.slip_speed_m_s : config_.creep_speed_m_s);
    } else if (event_open_ && t - last_above_s_ >= config_.slip_event_gap_s) {
      CloseEvent();
      // Sliding that goes on after the event is a creep of its own from here, not one that began
      // before the event and would open a second event with an earlier onset.
      creep_start_s_ = -1.0;
    }
    // A contact sliding at the friction limit up to early_detection_window_s before a flag, too
    // slowly for an event, makes it an incipient-slip flag rather than a false one. Sliding after
    // the flag does not: the controller's own response (a grip step rolling the pad) could cause it.
    if (!seating && sliding > config_.creep_speed_m_s) last_sliding_s_ = t;
    if (rising_flag && !seating) OnControllerFlag(t, sample.controller_cues);
    if (flag && !seating && !event_open_) false_flag_s_ += dt;
    // Flags that fell out of the early window can no longer match an event, unless a creep that may
    // still become one began after them.
    double keep_from_s = t - config_.early_detection_window_s;
    if (config_.creep_event_m > 0.0 && creep_start_s_ >= 0.0 && !event_open_) {
      keep_from_s = std::min(keep_from_s, creep_start_s_ - config_.early_detection_window_s);
    }
    int kept = 0;
    for (int i = 0; i < pending_count_; ++i) {
      if (pending_flags_[i].time_s >= keep_from_s) {
        pending_flags_[kept++] = pending_flags_[i];
      } else {
        JudgeUnmatchedFlag(pending_flags_[i]);
      }
    }
    pending_count_ = kept;
  } else {
    creep_start_s_ = -1.0;  // a creep belongs to the grasp it happened in
    // A slip that ended in a drop closes with it: the object is no longer held.
    if (event_open_ && dropped_) CloseEvent();
  }
}

void MetricsTracker::UpdateEstimationError(const TickSample& sample) {
  // Estimation error over (tick, unit) pairs in contact, valid and fresh.
  const sensor::TactileState& state = *sample.state;
  if (!state.stale) {
    const int units = std::min<int>(state.unit_count, static_cast<int>(sample.true_loads.size()));
    for (int u = 0; u < units; ++u) {
      if (state.validity[u] != sensor::UnitValidity::kValid) continue;
      const sensor::UnitLoad& load = sample.true_loads[u];
      if (load.fn_n <= contact_threshold_n_ && state.fn_n[u] <= contact_threshold_n_) continue;
      const double fn_error = state.fn_n[u] - load.fn_n;
      const double ft_error = state.ft_n[u] - load.ft_n;
      fn_square_sum_ += fn_error * fn_error;
      ft_square_sum_ += ft_error * ft_error;
      ++estimation_samples_;
    }
  }
}

void MetricsTracker::UpdateStableGrasp(double squeeze, double t) {
  // Stable grasp: restart the candidate window whenever the squeeze leaves the band or slip occurs.
  if (stable_found_s_ < 0.0) {
    if (!holding_ || event_open_) {
      stable_start_s_ = -1.0;
    } else if (stable_start_s_ < 0.0) {
      stable_start_s_ = t;
      stable_min_n_ = stable_max_n_ = squeeze;
    } else {
      const double low = std::min(stable_min_n_, squeeze);
      const double high = std::max(stable_max_n_, squeeze);
      const double mid = 0.5 * (low + high);
      if (high - low > 2.0 * config_.stable_force_band * mid) {
        stable_start_s_ = t;
        stable_min_n_ = stable_max_n_ = squeeze;
      } else {
        stable_min_n_ = low;
        stable_max_n_ = high;
        if (t - stable_start_s_ >= config_.stable_window_s) stable_found_s_ = stable_start_s_;
      }
    }
  }
}

Metrics MetricsTracker::Finish(double sim_s, double wall_s, double first_close_time_s) const {
  MetricsTracker copy = *this;  // closing the open event must not change the live tracker
  if (copy.event_open_) copy.CloseEvent();
  for (int i = 0; i < copy.pending_count_; ++i) copy.JudgeUnmatchedFlag(copy.pending_flags_[i]);
  copy.pending_count_ = 0;

  Metrics m;
  m.grasped = copy.grasped_ever_;
  m.grasp_time_s = copy.grasp_time_s_;
  m.contact_time_s = copy.contact_time_s_;
  m.acquisition_shift_mm = copy.acquisition_shift_m_ * 1e3;
  m.pushed_out = copy.pushed_out_;
  m.dropped = copy.dropped_ || (first_close_time_s >= 0.0 && !copy.grasped_ever_);
  if (copy.finger_integral_n_s_ > 0.0) m.sensed_grip_share = copy.sensed_integral_n_s_ / copy.finger_integral_n_s_;
  m.unsensed_held_s = copy.unsensed_held_s_;
  const auto heaviest = std::max_element(copy.unit_integral_n_s_.begin(), copy.unit_integral_n_s_.end());
  if (*heaviest > 0.0) m.contact_unit = static_cast<int>(heaviest - copy.unit_integral_n_s_.begin());
  m.ungrasped_closes = copy.ungrasped_closes_ + (copy.closing_ && !copy.grasped_ ? 1 : 0);
  m.drop_time_s = copy.drop_time_s_;
  m.max_slip_mm = copy.slip_distance_m_ * 1e3;
  m.partial_slip_mm = copy.partial_slip_distance_m_ * 1e3;
  m.peak_grip_n = copy.peak_grip_n_;
  m.mean_held_grip_n = copy.held_s_ > 0.0 ? copy.held_grip_integral_n_s_ / copy.held_s_ : 0.0;
  m.peak_load_bound_grip_n = copy.peak_load_bound_grip_n_;
  m.crushed = copy.crush_limit_n_ > 0.0 && copy.peak_grip_n_ > copy.crush_limit_n_;
  m.slip_events = copy.event_count_;
  m.missed_slip_events = copy.missed_;
  m.missed_unsensed_slip_events = copy.missed_unsensed_;
  m.missed_thumb_only_slip_events = copy.missed_thumb_only_;
  if (copy.event_count_ > 0 && copy.worst_latency_s_ >= 0.0)
    m.slip_detect_latency_ms = copy.worst_latency_s_ * 1e3;
  SlipClassCounts* classes[2] = {&m.micro, &m.gross};
  for (size_t c = 0; c < 2; ++c) {
    classes[c]->events = copy.class_events_[c];
    classes[c]->detected = copy.class_detected_[c];
    if (copy.class_worst_latency_s_[c] >= 0.0) classes[c]->worst_latency_ms = copy.class_worst_latency_s_[c] * 1e3;
  }
  m.controller_slip_flags = copy.flags_;
  m.false_slip_flags = copy.false_flags_;
  for (int i = 0; i < copy.cue_labels_; ++i) {
    const CueCount& count = copy.false_by_cue_[static_cast<size_t>(i)];
    m.false_slip_flags_by_cue[count.cues[0] != '\0' ? count.cues : "(none)"] += count.false_flags;
  }
  if (copy.false_other_cues_ > 0) m.false_slip_flags_by_cue["(other)"] = copy.false_other_cues_;
  m.incipient_slip_flags = copy.incipient_flags_;
  m.held_s = copy.held_s_;
  m.false_slip_per_min = copy.held_s_ > 0.0 ? copy.false_flags_ / (copy.held_s_ / 60.0) : 0.0;
  m.false_slip_flag_s = copy.false_flag_s_;
  m.false_slip_flag_pct = copy.held_s_ > 0.0 ? 100.0 * copy.false_flag_s_ / copy.held_s_ : 0.0;
  if (copy.estimation_samples_ > 0) {
    m.fn_rmse_n = std::sqrt(copy.fn_square_sum_ / static_cast<double>(copy.estimation_samples_));
    m.ft_rmse_n = std::sqrt(copy.ft_square_sum_ / static_cast<double>(copy.estimation_samples_));
  }
  m.estimation_samples = copy.estimation_samples_;
  if (copy.stable_found_s_ >= 0.0 && first_close_time_s >= 0.0) {
    m.time_to_stable_s = copy.stable_found_s_ - first_close_time_s;
  }
  m.sim_s = sim_s;
  m.wall_s = wall_s;
  const int stored = std::min(copy.event_count_, kMaxEvents);
  m.events.assign(copy.events_.begin(), copy.events_.begin() + stored);
  return m;
}

std::vector<ExpectationOutcome> EvaluateExpectations(const Expectations& e, const Metrics& m,
                                                     const MetricsConfig& config) {
  std::vector<ExpectationOutcome> outcomes;
  if (e.not_dropped) {
    ExpectationOutcome o = Outcome("not_dropped", *e.not_dropped ? "true" : "false");
    o.value = m.dropped ? 1.0 : 0.0;
    o.value_text = m.pushed_out ? "pushed out at " + Format(m.drop_time_s, "s")
                   : !m.grasped ? "never grasped"
                   : m.dropped  ? "dropped at " + Format(m.drop_time_s, "s")
                                : "held";
    o.passed = *e.not_dropped ? !m.dropped : m.dropped;
    if (m.pushed_out) {
      o.note = "the object moved more than the drop distance relative to the wrist between the close and an "
               "established grasp (pushed out, knocked over, or left behind)";
    } else if (!m.grasped) {
      o.note = "the object was never grasped";
    }
    outcomes.push_back(o);
  }
  if (e.max_slip_mm) {
    ExpectationOutcome o = Outcome("max_slip_mm", "<= " + Format(*e.max_slip_mm, "mm"));
    o.value = m.max_slip_mm;
    o.value_text = Format(m.max_slip_mm, "mm");
    o.passed = m.max_slip_mm <= *e.max_slip_mm;
    outcomes.push_back(o);
  }
  if (e.max_peak_grip_n) {
    ExpectationOutcome o = Outcome("max_peak_grip_n", "<= " + Format(*e.max_peak_grip_n, "N"));
    o.value = m.peak_grip_n;
    o.value_text = Format(m.peak_grip_n, "N");
    o.passed = m.peak_grip_n <= *e.max_peak_grip_n;
    outcomes.push_back(o);
  }
  if (e.not_crushed) {
    ExpectationOutcome o = Outcome("not_crushed", *e.not_crushed ? "true" : "false");
    o.value = m.crushed ? 1.0 : 0.0;
    o.value_text = m.crushed ? "crushed (" + Format(m.peak_grip_n, "N") + ")" : "intact";
    o.passed = *e.not_crushed ? !m.crushed : m.crushed;
    outcomes.push_back(o);
  }
  const auto detection = [&](const char* name, double limit_ms, const SlipClassCounts& counts,
                              const char* what) {
    ExpectationOutcome o = Outcome(name, "<= " + Format(limit_ms, "ms"));
    if (counts.events == 0) {
      o.value_text = std::string("no ") + what;
      o.passed = true;
      o.note = std::string("no ") + what + " event occurred, nothing to detect";
    } else if (counts.detected < counts.events) {
      o.value = counts.worst_latency_ms;
      o.value_text = std::to_string(counts.events - counts.detected) + " of " + std::to_string(counts.events) +
                     " missed";
      o.passed = false;
      o.note = std::string(what) + " events the controller never flagged";
    } else {
      o.value = counts.worst_latency_ms;
      o.value_text = Format(*counts.worst_latency_ms, "ms");
      o.passed = *counts.worst_latency_ms <= limit_ms;
    }
    outcomes.push_back(o);
  };
  if (e.slip_detected_within_ms) detection("slip_detected_within_ms", *e.slip_detected_within_ms, m.gross, "gross slip");
  if (e.micro_slip_detected_within_ms)
    detection("micro_slip_detected_within_ms", *e.micro_slip_detected_within_ms, m.micro, "micro-slip");
  if (e.max_grip_efficiency) {
    ExpectationOutcome o = Outcome("max_grip_efficiency", "<= " + Format(*e.max_grip_efficiency, ""));
    if (m.grip_efficiency) {
      o.value = m.grip_efficiency;
      o.value_text = Format(*m.grip_efficiency, "") + " (mean " + Format(m.mean_held_grip_n, "N") + " / oracle " +
                     Format(*m.oracle->grip_n, "N") + ")";
      o.passed = *m.grip_efficiency <= *e.max_grip_efficiency;
    } else {
      o.value_text = "none";
      o.passed = false;
      o.note = !m.oracle                 ? "the run computed no oracle grip"
               : !m.oracle->grip_n       ? "no oracle grip: " + m.oracle->reason
                                         : "the object was never held";
    }
    outcomes.push_back(o);
  }
  if (e.max_estimation_error_n) {
    ExpectationOutcome o = Outcome("max_estimation_error_n", "<= " + Format(*e.max_estimation_error_n, "N"));
    if (!m.fn_rmse_n) {
      o.value_text = "no contact";
      o.passed = false;
      o.note = "no valid unit was ever in contact, so the estimate could not be scored";
    } else {
      const double worst = std::max(*m.fn_rmse_n, *m.ft_rmse_n);
      o.value = worst;
      o.value_text = "Fn " + Format(*m.fn_rmse_n, "N") + ", Ft " + Format(*m.ft_rmse_n, "N");
      o.passed = worst <= *e.max_estimation_error_n;
    }
    outcomes.push_back(o);
  }
  if (e.stable_within_s) {
    ExpectationOutcome o = Outcome("stable_within_s", "<= " + Format(*e.stable_within_s, "s"));
    o.value = m.time_to_stable_s;
    o.value_text = m.time_to_stable_s ? Format(*m.time_to_stable_s, "s") : "never";
    o.passed = m.time_to_stable_s && *m.time_to_stable_s <= *e.stable_within_s;
    outcomes.push_back(o);
  }
  if (e.max_false_slip_per_min) {
    ExpectationOutcome o =
        Outcome("max_false_slip_per_min", "<= " + Format(*e.max_false_slip_per_min, "/min"));
    o.value = m.false_slip_per_min;
    o.value_text = Format(m.false_slip_per_min, "/min") + " (" + std::to_string(m.false_slip_flags) + ")";
    o.passed = m.false_slip_per_min <= *e.max_false_slip_per_min;
    outcomes.push_back(o);
  }
  if (e.grasped_on_sensor.value_or(true)) outcomes.push_back(GraspedOnSensor(m, config));
  ExpectationOutcome physics = Outcome("no_physics_fault", "true");
  physics.value = m.physics_fault ? 1.0 : 0.0;
  physics.value_text = m.physics_fault ? m.physics_fault_cause : "ok";
  physics.passed = !m.physics_fault;
  if (m.physics_fault) physics.note = "at t = " + Format(m.physics_fault_time_s, "s");
  outcomes.push_back(physics);
  return outcomes;
}

void ApplyOracle(const OracleGrip& oracle, Metrics& metrics) {
  metrics.oracle = oracle;
  metrics.grip_efficiency.reset();
  metrics.peak_grip_ratio.reset();
  if (!oracle.grip_n || *oracle.grip_n <= 0.0) return;
  metrics.peak_grip_ratio = metrics.peak_grip_n / *oracle.grip_n;
  if (metrics.held_s > 0.0) metrics.grip_efficiency = metrics.mean_held_grip_n / *oracle.grip_n;
}

}  // namespace graspbed::testbed
