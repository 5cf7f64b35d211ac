#include "testbed/dataset.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>

#include "common/config_error.h"
#include "common/npz.h"
#include "common/signal_log.h"
#include "controller/grip_slip_controller.h"
#include "controller/slip_detector.h"
#include "controller/slip_features.h"
#include "testbed/run_outputs.h"
#include "testbed/schedule.h"

namespace graspbed::testbed {
namespace {

namespace fs = std::filesystem;
using common::MakeNpyArray;
using common::NpyArray;

// Every realistic readout chain with either sensitivity source: the scorecard's sensors.
const std::vector<std::string> kRealisticProfiles = {"divider_12bit/paper", "inamp_16bit/paper", "bridge_24bit/paper",
                                                     "divider_12bit/fea",   "inamp_16bit/fea",   "bridge_24bit/fea"};
constexpr double kContactN = 0.05;  // the finger touches the object above this true force [N]

// FNV-1a, 64 bit: stable across machines and builds.
uint64_t Fnv1a(const std::string& text, uint64_t hash = 1469598103934665603ull) {
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  return hash;
}

/// What one run contributes: its ticks' columns, row-major per unit.
struct RunTicks {
  size_t ticks = 0;
  int units = 0;
  std::vector<double> time_s;
  std::vector<float> fn, ft, total_fn, shear_axial, shear_circ, effort, features, slip_speed, slip_distance;
  std::vector<float> hand;  ///< the hand state's columns per tick (HandColumnNames), NaN unknown
  std::vector<float> handtuned_score;
  std::vector<float> replayed_score;
  std::vector<uint8_t> replayed_flag;
  std::vector<uint8_t> validity, stale, holding, controller_flag;
  TickLabels labels;
  int gross_events = 0;
  bool has_handtuned = false;
  bool completed = false;  ///< the run ran to its end
};

/// The log's column `name`, or nullopt.
std::optional<size_t> FindColumn(const common::SignalLog& log, const std::string& name) {
  const auto& columns = log.numeric_columns();
  const auto found = std::find(columns.begin(), columns.end(), name);
  if (found == columns.end()) return std::nullopt;
  return static_cast<size_t>(found - columns.begin());
}

int UnitCount(const common::SignalLog& log) {
  int units = 0;
  while (FindColumn(log, "fn_est_n_" + std::to_string(units))) ++units;
  return units;
}

/// The state the controller saw at `row`, from the columns signals.csv logs of it.
void StateAt(const common::SignalLog& log, size_t row, const std::vector<size_t>& unit_columns, int units,
             sensor::TactileState& state) {
  state.unit_count = units;
  state.time_s = log.At(row, log.Column("frame_time_s"));
  state.sequence = static_cast<uint32_t>(log.At(row, log.Column("frame_seq")));
  state.stale = log.At(row, log.Column("stale")) != 0.0;
  state.valid_count = static_cast<int>(log.At(row, log.Column("valid_units")));
  state.contact_count = static_cast<int>(log.At(row, log.Column("contact_units")));
  state.total_fn_n = log.At(row, log.Column("est_total_fn_n"));
  state.total_shear_axial_n = log.At(row, log.Column("est_shear_axial_n"));
  state.total_shear_circumferential_n = log.At(row, log.Column("est_shear_circumferential_n"));
  for (int u = 0; u < units; ++u) {
    const size_t i = static_cast<size_t>(u);
    state.fn_n[i] = log.At(row, unit_columns[3 * i]);
    state.ft_n[i] = log.At(row, unit_columns[3 * i + 1]);
    state.validity[i] = static_cast<sensor::UnitValidity>(static_cast<int>(log.At(row, unit_columns[3 * i + 2])));
  }
}

/// The reference's hand-tuned cues as one continuous statistic: the largest of each cue's statistic
/// over its threshold, 0 before the cues are armed; nullopt for a controller without those channels.
std::optional<float> HandTunedScore(const common::SignalLog& log, size_t row) {
  static const char* const kPairs[][2] = {{"ctl_load_ratio", "ctl_ratio_threshold"},
                                          {"ctl_vibration_rms_n", "ctl_vibration_threshold_n"},
                                          {"ctl_centroid_shift_pitch", "ctl_centroid_shift_threshold_pitch"},
                                          {"ctl_centroid_drift_pitch", "ctl_centroid_drift_threshold_pitch"}};
  const auto settled = FindColumn(log, "ctl_settled");
  if (!settled) return std::nullopt;
  if (log.At(row, *settled) == 0.0) return 0.0f;
  double score = 0.0;
  for (const auto& pair : kPairs) {
    const auto value = FindColumn(log, pair[0]);
    const auto threshold = FindColumn(log, pair[1]);
    if (!value || !threshold || !(log.At(row, *threshold) > 0.0)) continue;
    score = std::max(score, log.At(row, *value) / log.At(row, *threshold));
  }
  return static_cast<float>(score);
}

/// The reference's hand-tuned cues (SlipDetector with grip_slip's default settings) replayed over the
/// states a run logged, whatever controller ran it, so they are scored on every tick the learned cue
/// is: armed from 3 frames of unit contact until 0.1 s without (grip_slip's contact_confirm_frames and
/// contact_lost_s), its friction at grip_slip's friction_initial (the reference learns it at slips),
/// the grip its 2 ms low-pass of total_fn_n. The log has no readout noise figures
/// (TactileState::noise_known), so the noise-scaled thresholds fall back to their fixed floors.
class HandTunedReplay {
 public:
  explicit HandTunedReplay(double rate_hz) : config_(Config(rate_hz)), detector_(config_.slip),
        grip_(config_.grip_filter_s, 1.0 / rate_hz), rate_hz_(rate_hz) {}

  /// The statistic (largest cue statistic over its threshold, 0 unarmed) and flag at this tick.
  std::pair<float, uint8_t> Update(const sensor::TactileState& state) {
    const double grip_n = grip_.Update(state.total_fn_n);
    const controller::SlipSignals& previous = detector_.signals();
    const bool touching = previous.contact_units >= 1;
    contact_frames_ = touching ? contact_frames_ + 1 : 0;
    quiet_frames_ = touching ? 0 : quiet_frames_ + 1;
    if (!armed_ && contact_frames_ >= config_.contact_confirm_frames) {
      armed_ = true;
      detector_.RestartContact();
    } else if (armed_ && quiet_frames_ >= config_.contact_lost_s * rate_hz_) {
      armed_ = false;
    }
    const controller::SlipSignals& s = detector_.Update(state, grip_n, config_.friction_initial, armed_, true);
    double score = 0.0;
    if (s.settled && armed_) {
      const double pairs[][2] = {{s.load_ratio, s.ratio_threshold},
                                 {s.vibration_rms_n, s.vibration_threshold_n},
                                 {s.centroid_shift_units, s.centroid_shift_threshold},
                                 {s.centroid_drift_units, s.centroid_drift_threshold}};
      for (const auto& pair : pairs) {
        if (pair[1] > 0.0) score = std::max(score, pair[0] / pair[1]);
      }
    }
    return {static_cast<float>(score), static_cast<uint8_t>(armed_ && s.any() ? 1 : 0)};
  }

 private:
  static controller::GripSlipConfig Config(double rate_hz) {
    controller::GripSlipConfig config;
    config.slip.sample_rate_hz = rate_hz;
    return config;
  }
  controller::GripSlipConfig config_;
  controller::SlipDetector detector_;
  controller::LowPassFilter grip_;
  double rate_hz_;
  bool armed_ = false;
  int contact_frames_ = 0;
  int quiet_frames_ = 0;
};

/// Copies what the controller saw, its features and the truth columns out of the run's log.
RunTicks ExtractRun(const common::SignalLog& log, const ScenarioConfig& config) {
  RunTicks run;
  run.units = UnitCount(log);
  run.ticks = log.rows();
  const int units = run.units;
  std::vector<size_t> unit_columns;
  for (int u = 0; u < units; ++u) {
    for (const char* stem : {"fn_est_n_", "ft_est_n_", "validity_"}) unit_columns.push_back(log.Column(stem + std::to_string(u)));
  }
  controller::SlipFeatureExtractor extractor(controller::SlipFeatureLayoutFor(units), 1.0 / config.controller.rate_hz);
  HandTunedReplay replay(config.controller.rate_hz);
  sensor::TactileState state;
  std::array<double, controller::kSlipFeatureCount> features{};
  run.features.reserve(run.ticks * features.size());
  const size_t time = log.Column("time_s"), effort = log.Column("grip_effort"), flag = log.Column("slip_flag");
  const size_t speed = log.Column("sliding_speed_mm_s"), distance = log.Column("slip_distance_mm");
  const size_t holding = log.Column("holding");
  std::vector<size_t> hand_columns;
  for (const char* name : internal::HandColumnNames()) hand_columns.push_back(log.Column(name));
  for (size_t row = 0; row < run.ticks; ++row) {
    StateAt(log, row, unit_columns, units, state);
    const double t = log.At(row, time);
    extractor.Update(state, t, features);
    run.time_s.push_back(t);
    for (int u = 0; u < units; ++u) {
      run.fn.push_back(static_cast<float>(state.fn_n[static_cast<size_t>(u)]));
      run.ft.push_back(static_cast<float>(state.ft_n[static_cast<size_t>(u)]));
      run.validity.push_back(static_cast<uint8_t>(state.validity[static_cast<size_t>(u)]));
    }
    for (double value : features) run.features.push_back(static_cast<float>(value));
    run.stale.push_back(state.stale ? 1 : 0);
    run.total_fn.push_back(static_cast<float>(state.total_fn_n));
    run.shear_axial.push_back(static_cast<float>(state.total_shear_axial_n));
    run.shear_circ.push_back(static_cast<float>(state.total_shear_circumferential_n));
    run.effort.push_back(static_cast<float>(log.At(row, effort)));
    for (const size_t column : hand_columns) run.hand.push_back(static_cast<float>(log.At(row, column)));
    run.controller_flag.push_back(log.At(row, flag) != 0.0 ? 1 : 0);
    run.slip_speed.push_back(static_cast<float>(log.At(row, speed)));
    run.slip_distance.push_back(static_cast<float>(log.At(row, distance)));
    run.holding.push_back(log.At(row, holding) != 0.0 ? 1 : 0);
    const std::optional<float> handtuned = HandTunedScore(log, row);
    run.has_handtuned = handtuned.has_value();
    run.handtuned_score.push_back(handtuned.value_or(std::numeric_limits<float>::quiet_NaN()));
    const auto [replayed_score, replayed_flag] = replay.Update(state);
    run.replayed_score.push_back(replayed_score);
    run.replayed_flag.push_back(replayed_flag);
  }
  return run;
}

/// Runs `config` (nothing written) and takes its ticks and labels.
RunTicks RunAndExtract(const ScenarioConfig& config, const DatasetOptions& options) {
  RunOptions run_options;
  run_options.stop = options.stop;
  run_options.write_plots = false;
  run_options.oracle = OracleMode::kNever;
  RunTicks part;
  std::vector<double> time, finger_fn, sliding, slip_event;
  run_options.on_signals = [&](const common::SignalLog& log) {
    part = ExtractRun(log, config);
    time = log.ColumnValues("time_s");
    finger_fn = log.ColumnValues("true_finger_fn_n");
    sliding = log.ColumnValues("sliding_speed_mm_s");
    slip_event = log.ColumnValues("slip_event");
  };
  const RunResult result = RunScenario(config, run_options);
  part.completed = result.completed;
  // The labels need the run's slip events (gross or not), known once it has ended.
  part.labels = LabelTicks(time, finger_fn, sliding, slip_event, result.metrics.events, options.horizons_ms, kContactN,
                           config.metrics.creep_speed_m_s * 1e3);
  part.gross_events = static_cast<int>(std::count_if(result.metrics.events.begin(), result.metrics.events.end(),
                                                     [](const SlipEvent& e) { return e.gross; }));
  return part;
}

/// Appends `part` to `whole`.
template <typename T>
void Append(std::vector<T>& whole, const std::vector<T>& part) {
  whole.insert(whole.end(), part.begin(), part.end());
}

}  // namespace

TickLabels LabelTicks(const std::vector<double>& time_s, const std::vector<double>& finger_fn_n,
                      const std::vector<double>& sliding_mm_s, const std::vector<double>& slip_event,
                      const std::vector<SlipEvent>& events, const std::vector<int>& horizons_ms,
                      double contact_n, double creep_mm_s) {
  const size_t n = time_s.size();
  TickLabels labels;
  labels.contact_state.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const double t = time_s[i];
    const bool gross = std::any_of(events.begin(), events.end(),
                                   [t](const SlipEvent& e) { return e.gross && t >= e.onset_s && t <= e.end_s; });
    if (gross) {
      labels.contact_state[i] = 3;
    } else if (finger_fn_n[i] > contact_n) {
      labels.contact_state[i] = slip_event[i] != 0.0 || sliding_mm_s[i] > creep_mm_s ? 2 : 1;
    }
  }
  // Time of the first gross tick at or after each tick (+inf: none).
  std::vector<double> next_gross(n + 1, std::numeric_limits<double>::infinity());
  for (size_t i = n; i-- > 0;) next_gross[i] = labels.contact_state[i] == 3 ? time_s[i] : next_gross[i + 1];
  constexpr double kEpsS = 1e-9;
  for (int horizon_ms : horizons_ms) {
    const double h = horizon_ms * 1e-3;
    std::vector<uint8_t> within(n, 0), onset(n, 0);
    for (size_t i = 0; i < n; ++i) {
      within[i] = next_gross[i] - time_s[i] <= h + kEpsS ? 1 : 0;
      for (const SlipEvent& e : events) {
        if (e.gross && e.onset_s >= time_s[i] - kEpsS && e.onset_s - time_s[i] <= h + kEpsS) onset[i] = 1;
      }
    }
    labels.gross_within.push_back(std::move(within));
    labels.onset_within.push_back(std::move(onset));
  }
  return labels;
}

std::vector<DatasetRun> ExpandDataset(const std::vector<SweepSpec>& specs, const DatasetOptions& options) {
  if (options.validation_fraction < 0.0 || options.test_fraction < 0.0 ||
      options.validation_fraction + options.test_fraction >= 1.0) {
    throw std::invalid_argument("dataset: validation and test fractions must be >= 0 and sum to less than 1");
  }
  const std::vector<std::string>& profiles = options.profiles.empty() ? kRealisticProfiles : options.profiles;
  struct Group {
    uint64_t hash;
    int index;
  };
  std::vector<Group> groups;
  std::vector<DatasetRun> runs;
  for (size_t s = 0; s < specs.size(); ++s) {
    for (const SweepRun& sweep_run : ExpandSweep(specs[s])) {
      const int group = static_cast<int>(groups.size());
      groups.push_back({Fnv1a(specs[s].fingerprint + ":" + std::to_string(sweep_run.index) + ":" +
                              std::to_string(options.split_seed)),
                        group});
      for (const std::string& profile : profiles) {
        DatasetRun run{static_cast<int>(runs.size()), static_cast<int>(s), sweep_run.index, profile,
                       sweep_run.overrides, group, 0};
        const size_t slash = profile.find('/');
        run.overrides.push_back({"sensor.profile", profile.substr(0, slash)});
        if (slash != std::string::npos) run.overrides.push_back({"sensor.sensitivities", profile.substr(slash + 1)});
        runs.push_back(std::move(run));
      }
    }
  }
  std::sort(groups.begin(), groups.end(),
            [](const Group& a, const Group& b) { return a.hash != b.hash ? a.hash < b.hash : a.index < b.index; });
  const size_t count = groups.size();
  const auto share = [count](double fraction) {
    const auto n = static_cast<size_t>(std::llround(fraction * static_cast<double>(count)));
    return fraction > 0.0 && count >= 3 ? std::max<size_t>(n, 1) : n;
  };
  const size_t test = share(options.test_fraction), validation = share(options.validation_fraction);
  std::vector<int> split_of(count, 0);
  for (size_t rank = 0; rank < count; ++rank) {
    split_of[static_cast<size_t>(groups[rank].index)] = rank < test ? 2 : rank < test + validation ? 1 : 0;
  }
  for (DatasetRun& run : runs) run.split = split_of[static_cast<size_t>(run.group)];
  return runs;
}

namespace {

/// The per-tick arrays of ticks.npz, runs in dataset order.
std::vector<NpyArray> TickArrays(const std::vector<DatasetRun>& runs, const std::vector<RunTicks>& ticks,
                                 const std::vector<int>& sensor_index, const DatasetOptions& options) {
  RunTicks all;
  std::vector<int32_t> run_column;
  std::vector<uint8_t> split, sensor;
  std::vector<std::vector<uint8_t>> within(options.horizons_ms.size()), onset(options.horizons_ms.size());
  int units = 0;
  for (size_t r = 0; r < runs.size(); ++r) {
    const RunTicks& part = ticks[r];
    if (part.ticks == 0) continue;
    units = part.units;
    for (std::vector<float> RunTicks::*field : {&RunTicks::fn, &RunTicks::ft, &RunTicks::total_fn, &RunTicks::shear_axial,
                        &RunTicks::shear_circ, &RunTicks::effort, &RunTicks::hand, &RunTicks::features, &RunTicks::slip_speed,
                        &RunTicks::slip_distance, &RunTicks::handtuned_score,
                                                 &RunTicks::replayed_score})
      Append(all.*field, part.*field);
    for (std::vector<uint8_t> RunTicks::*field : {&RunTicks::validity, &RunTicks::stale, &RunTicks::holding,
                                                   &RunTicks::controller_flag, &RunTicks::replayed_flag})
      Append(all.*field, part.*field);
    Append(all.time_s, part.time_s);
    Append(all.labels.contact_state, part.labels.contact_state);
    for (size_t h = 0; h < within.size(); ++h) {
      Append(within[h], part.labels.gross_within[h]);
      Append(onset[h], part.labels.onset_within[h]);
    }
    run_column.insert(run_column.end(), part.ticks, runs[r].index);
    split.insert(split.end(), part.ticks, static_cast<uint8_t>(runs[r].split));
    sensor.insert(sensor.end(), part.ticks, static_cast<uint8_t>(sensor_index[r]));
  }
  const size_t n = all.time_s.size(), u = static_cast<size_t>(units);
  std::vector<NpyArray> arrays = {
      MakeNpyArray("run", run_column, {n}), MakeNpyArray("split", split, {n}), MakeNpyArray("sensor", sensor, {n}),
      MakeNpyArray("time_s", all.time_s, {n}),
      // The inputs, in kDatasetInputs order.
      MakeNpyArray("fn_n", all.fn, {n, u}), MakeNpyArray("ft_n", all.ft, {n, u}),
      MakeNpyArray("validity", all.validity, {n, u}), MakeNpyArray("stale", all.stale, {n}),
      MakeNpyArray("total_fn_n", all.total_fn, {n}), MakeNpyArray("shear_axial_n", all.shear_axial, {n}),
      MakeNpyArray("shear_circumferential_n", all.shear_circ, {n}), MakeNpyArray("grip_effort", all.effort, {n}),
      MakeNpyArray("hand", all.hand, {n, internal::HandColumnNames().size()}),
      MakeNpyArray("features", all.features, {n, controller::kSlipFeatureCount}),
      MakeNpyArray("controller_slip_flag", all.controller_flag, {n}),
      MakeNpyArray("handtuned_score", all.handtuned_score, {n}),
      MakeNpyArray("handtuned_replayed_score", all.replayed_score, {n}),
      MakeNpyArray("handtuned_replayed_flag", all.replayed_flag, {n}), MakeNpyArray("holding", all.holding, {n}),
      MakeNpyArray("contact_state", all.labels.contact_state, {n}),
      MakeNpyArray("slip_speed_mm_s", all.slip_speed, {n}), MakeNpyArray("slip_distance_mm", all.slip_distance, {n})};
  static_assert(std::size(kDatasetInputs) == 9, "kDatasetInputs and the arrays written here must match");
  for (size_t h = 0; h < within.size(); ++h) {
    const std::string suffix = std::to_string(options.horizons_ms[h]) + "ms";
    arrays.push_back(MakeNpyArray("gross_within_" + suffix, within[h], {n}));
    arrays.push_back(MakeNpyArray("onset_within_" + suffix, onset[h], {n}));
  }
  return arrays;
}


/// The manifest: what the dataset is, how it was made and what it holds.
nlohmann::json Manifest(const std::vector<SweepSpec>& specs, const std::vector<DatasetRun>& all,
                        const std::vector<DatasetRun>& runs, const std::vector<ScenarioConfig>& configs,
                        const std::vector<RunTicks>& ticks, const std::vector<std::string>& errors,
                        const std::vector<std::string>& sensors, const DatasetOptions& options) {
  nlohmann::json spec_list = nlohmann::json::array();
  for (const SweepSpec& spec : specs) {
    spec_list.push_back({{"file", spec.source_file}, {"scenario", spec.scenario_path}, {"fingerprint", spec.fingerprint},
                         {"mode", spec.random ? "random" : "grid"}, {"seed", spec.seed}, {"samples", spec.samples}});
  }
  nlohmann::json features = nlohmann::json::array();
  for (const auto& feature : controller::kSlipFeatures) features.push_back({{"name", feature.name}, {"doc", feature.doc}});
  nlohmann::json inputs = nlohmann::json::array();
  for (const DatasetInput& input : kDatasetInputs)
    inputs.push_back({{"array", input.array}, {"doc", input.doc}, {"per_unit", input.per_unit}});
  nlohmann::json hand_columns = nlohmann::json::array();
  for (const char* name : internal::HandColumnNames()) hand_columns.push_back(name);
  nlohmann::json run_list = nlohmann::json::array();
  nlohmann::json counts = nlohmann::json::object();
  for (const char* split : kSplitNames) {
    counts[split] = {{"runs", 0}, {"ticks", 0}, {"held_ticks", 0}, {"gross_slip_events", 0}};
    for (const char* state : kContactStateNames) counts[split]["contact_state"][state] = 0;
  }
  int64_t first_tick = 0;
  for (size_t r = 0; r < runs.size(); ++r) {
    const DatasetRun& run = runs[r];
    const RunTicks& part = ticks[r];
    nlohmann::json overrides = nlohmann::json::array();  // in order: `graspbed run --set` each to rerun it
    for (const Override& o : run.overrides) overrides.push_back({o.key, o.value});
    nlohmann::json row = {{"run", run.index}, {"spec", run.spec}, {"sweep_run", run.sweep_run}, {"group", run.group},
                          {"split", kSplitNames[run.split]}, {"scenario", configs[r].name},
                          {"controller", configs[r].controller.name}, {"profile", run.profile},
                          {"sensor", configs[r].sensor.profile + "/" + configs[r].sensor.sensitivities},
                          {"seed", configs[r].seed}, {"overrides", overrides}, {"first_tick", first_tick},
                          {"ticks", part.ticks}, {"gross_slip_events", part.gross_events}};
    if (!errors[r].empty()) row["error"] = errors[r];
    run_list.push_back(row);
    first_tick += static_cast<int64_t>(part.ticks);
    nlohmann::json& c = counts[kSplitNames[run.split]];
    c["runs"] = c["runs"].get<int>() + 1;
    c["ticks"] = c["ticks"].get<int64_t>() + static_cast<int64_t>(part.ticks);
    c["held_ticks"] = c["held_ticks"].get<int64_t>() + std::count(part.holding.begin(), part.holding.end(), 1);
    c["gross_slip_events"] = c["gross_slip_events"].get<int>() + part.gross_events;
    for (size_t s = 0; s < std::size(kContactStateNames); ++s) {
      nlohmann::json& cell = c["contact_state"][kContactStateNames[s]];
      cell = cell.get<int64_t>() + std::count(part.labels.contact_state.begin(), part.labels.contact_state.end(), s);
    }
  }
  const ScenarioConfig& first = configs.front();
  return {{"format", kDatasetFormat}, {"version", kDatasetVersion}, {"graspbed_version", GRASPBED_VERSION},
          {"specs", spec_list}, {"profiles", options.profiles.empty() ? kRealisticProfiles : options.profiles},
          {"sensors", sensors},
          {"layout", {{"name", first.sensor.layout}, {"units", ticks.empty() ? 0 : ticks.front().units},
                      {"columns", controller::SlipFeatureLayoutFor(ticks.empty() ? 0 : ticks.front().units).columns}}},
          {"tick_period_s", 1.0 / first.controller.rate_hz}, {"feature_set", controller::kSlipFeatureSet},
          {"features", features}, {"inputs", inputs}, {"hand_columns", hand_columns}, {"horizons_ms", options.horizons_ms},
          {"contact_states", kContactStateNames},
          {"split", {{"by", "run group: one sweep run (scenario, seed, drawn parameters) under every profile"},
                     {"seed", options.split_seed}, {"validation_fraction", options.validation_fraction},
                     {"test_fraction", options.test_fraction}}},
          {"shard", std::to_string(options.shard.index) + "/" + std::to_string(options.shard.count)},
          {"total_runs", all.size()}, {"counts", counts}, {"runs", run_list}};
}

/// Loads every run's scenario; refuses a dataset whose runs differ in layout or control rate.
std::vector<ScenarioConfig> LoadRuns(const std::vector<SweepSpec>& specs, const std::vector<DatasetRun>& runs) {
  std::vector<ScenarioConfig> configs;
  for (const DatasetRun& run : runs) {
    const SweepSpec& spec = specs[static_cast<size_t>(run.spec)];
    try {
      configs.push_back(LoadScenario(spec.scenario_path, run.overrides));
    } catch (const common::ConfigError& error) {
      throw error.WithContext(spec.source_file + ": run " + std::to_string(run.sweep_run));
    }
    const ScenarioConfig& config = configs.back();
    const ScenarioConfig& first = configs.front();
    if (config.sensor.layout != first.sensor.layout || config.controller.rate_hz != first.controller.rate_hz) {
      throw common::ConfigError(spec.source_file + ": run " + std::to_string(run.sweep_run) + ": sensor.layout " +
                                config.sensor.layout + " at " + std::to_string(config.controller.rate_hz) +
                                " Hz: a dataset holds one layout and control rate (the first run has " +
                                first.sensor.layout + " at " + std::to_string(first.controller.rate_hz) + " Hz)");
    }
    if (config.backend != Backend::kSim)
      throw common::ConfigError(spec.source_file + ": a dataset needs the simulation's ground truth (backend: sim)");
  }
  return configs;
}

}  // namespace

DatasetOutcome BuildDataset(const std::vector<SweepSpec>& specs, const DatasetOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (specs.empty()) throw std::invalid_argument("dataset: no sweep spec given");
  const std::vector<DatasetRun> all = ExpandDataset(specs, options);
  std::vector<DatasetRun> runs;
  for (const DatasetRun& run : all)
    if (run.index % options.shard.count == options.shard.index - 1) runs.push_back(run);
  if (runs.empty()) throw std::invalid_argument("dataset: shard " + std::to_string(options.shard.index) + "/" +
                                                std::to_string(options.shard.count) + " holds no runs");
  const std::vector<ScenarioConfig> configs = LoadRuns(specs, runs);
  std::vector<std::string> sensors;
  std::vector<int> sensor_index;
  for (const ScenarioConfig& config : configs) {
    const std::string label = config.sensor.profile + "/" + config.sensor.sensitivities;
    auto found = std::find(sensors.begin(), sensors.end(), label);
    if (found == sensors.end()) found = sensors.insert(sensors.end(), label);
    sensor_index.push_back(static_cast<int>(found - sensors.begin()));
  }

  fs::create_directories(options.out_dir);
  for (const char* name : {"ticks.npz", "manifest.json"}) fs::remove(fs::path(options.out_dir) / name);
  std::vector<RunTicks> ticks(runs.size());
  std::vector<std::string> errors(runs.size());
  DatasetOutcome outcome;
  outcome.runs = static_cast<int>(runs.size());
  std::mutex mutex;
  const std::vector<size_t> order = LongestFirst(configs);
  std::atomic<size_t> next{0};
  const auto worker = [&] {
    while (!(options.stop != nullptr && options.stop->load())) {
      const size_t position = next.fetch_add(1);
      if (position >= order.size()) return;
      const size_t i = order[position];
      RunTicks part;
      std::string error;
      try {
        part = RunAndExtract(configs[i], options);
      } catch (const std::exception& e) {
        error = e.what();
        part = RunTicks{};
      }
      if (!part.completed && error.empty()) return;  // interrupted: not a result
      std::lock_guard<std::mutex> lock(mutex);
      ticks[i] = std::move(part);
      errors[i] = error;
      ++outcome.finished;
      if (!error.empty()) ++outcome.errors;
      outcome.ticks += static_cast<int64_t>(ticks[i].ticks);
      if (options.on_finished) options.on_finished(outcome.finished, outcome.runs);
    }
  };
  std::vector<std::thread> threads;
  const int thread_count = std::max(1, std::min<int>(options.jobs, static_cast<int>(runs.size())));
  for (int t = 0; t < thread_count; ++t) threads.emplace_back(worker);
  for (std::thread& thread : threads) thread.join();

  outcome.completed = outcome.finished == outcome.runs;
  nlohmann::json manifest = Manifest(specs, all, runs, configs, ticks, errors, sensors, options);
  if (outcome.completed) {
    const std::vector<NpyArray> arrays = TickArrays(runs, ticks, sensor_index, options);
    common::WriteNpz(options.out_dir + "/ticks.npz", arrays);
  }
  outcome.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  manifest["completed"] = outcome.completed;
  manifest["finished_runs"] = outcome.finished;
  manifest["errors"] = outcome.errors;
  manifest["ticks"] = outcome.ticks;
  manifest["wall_s"] = outcome.wall_s;
  manifest["jobs"] = options.jobs;
  // The manifest goes last: its "completed" vouches for ticks.npz.
  common::WriteFileAtomic(options.out_dir + "/manifest.json", manifest.dump(1) + "\n");
  return outcome;
}

}  // namespace graspbed::testbed
