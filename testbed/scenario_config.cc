#include "testbed/scenario_config.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "common/data_dir.h"
#include "controller/plugin_loader.h"
#include "sensor/fea/fea_config.h"
#include "sensor/fea/unit_analysis.h"
#include "sensor/layout.h"
#include "sensor/sensor_profile.h"

namespace graspbed::testbed {
namespace {

using common::ConfigError;
using common::FormatNumber;
using common::NumberRule;
using common::YamlMap;

constexpr double kMaxDurationS = 3600.0;   // one simulated hour: beyond that a scenario is a mistake
constexpr double kMaxRateHz = 10000.0;     // sensor sampling and control rates [Hz]
constexpr double kMaxSpeedMS = 10.0;       // metric speed thresholds [m/s]
constexpr double kMaxStaleTimeoutS = 1.0;  // data older than a second is stale for any grasp [s]
// Signals a run may keep in memory (common::SignalLog reserves them before the run) [bytes].
constexpr double kMaxSignalBytes = 2e9;
constexpr double kMaxLatencyS = 1.0;  // sensor latency in total, file plus add_latency actions [s]
const NumberRule kDuration = NumberRule::Between(0.0, kMaxDurationS);
const NumberRule kPositiveDuration{0.0, kMaxDurationS, true};
constexpr double kMaxSeed = 9007199254740992.0;  // 2^53: every integer up to here is exact in YAML

struct ActionEntry {
  ActionKind kind;
  const char* name;
};

constexpr ActionEntry kActions[] = {
    {ActionKind::kClose, "close"},
    {ActionKind::kOpen, "open"},
    {ActionKind::kIdle, "idle"},
    {ActionKind::kMove, "move"},
    {ActionKind::kLift, "lift"},
    {ActionKind::kShake, "shake"},
    {ActionKind::kAddMass, "add_mass"},
    {ActionKind::kPull, "pull"},
    {ActionKind::kSetFriction, "set_friction"},
    {ActionKind::kDeadUnit, "dead_unit"},
    {ActionKind::kShortUnit, "short_unit"},
    {ActionKind::kRestoreUnit, "restore_unit"},
    {ActionKind::kBias, "bias"},
    {ActionKind::kNoiseBurst, "noise_burst"},
    {ActionKind::kDropFrames, "drop_frames"},
    {ActionKind::kAddLatency, "add_latency"},
};

struct EventEntry {
  ScriptEvent event;
  const char* name;
};

constexpr EventEntry kEvents[] = {
    {ScriptEvent::kGrasped, "grasped"},
    {ScriptEvent::kStable, "stable"},
    {ScriptEvent::kSlipFlagged, "slip_flagged"},
    {ScriptEvent::kReleased, "released"},
};

ScriptEvent EventFromName(const std::string& name) {
  for (const EventEntry& entry : kEvents) {
    if (name == entry.name) return entry.event;
  }
  throw std::logic_error("unvalidated event name " + name);
}

std::string FileStem(const std::string& path) {
  std::filesystem::path p(path);
  return p.stem().string();
}

std::string Join(const std::vector<std::string>& items) {
  std::string joined;
  for (const auto& item : items) joined += (joined.empty() ? "" : ", ") + item;
  return joined;
}

ActionKind ActionFromName(const std::string& name) {
  for (const ActionEntry& entry : kActions) {
    if (name == entry.name) return entry.kind;
  }
  throw std::logic_error("unvalidated action name " + name);
}

Profile ReadProfile(const YamlMap& map) {
  const std::string text = map.GetString("profile", "minimum_jerk", {"minimum_jerk", "linear"});
  return text == "linear" ? Profile::kLinear : Profile::kMinimumJerk;
}

// A YAML list of exactly three finite numbers within `rule`.
std::array<double, 3> ReadVector(const YamlMap& map, std::string_view key, std::array<double, 3> fallback,
                                 bool required, NumberRule rule = {}) {
  if (required && !map.Has(key)) map.Fail(key, "missing required key (a list of 3 numbers)");
  const std::vector<double> values =
      map.GetNumberList(key, std::vector<double>(fallback.begin(), fallback.end()), 3, rule);
  return {values[0], values[1], values[2]};
}

Action LoadAction(const YamlMap& map, const ScenarioConfig& config, int unit_count) {
  Action action;
  action.line = map.line();
  const std::string name = map.RequireString("action", ActionNames());
  action.kind = ActionFromName(name);
  // When: a fixed time or an event (docs/scenarios.md, "Waiting for the grasp").
  if (map.Has("at_s") && map.Has("after")) {
    map.Fail("after", "give either at_s (a fixed time) or after (an event), not both");
  }
  if (map.Has("after")) {
    action.after = EventFromName(map.RequireString("after", EventNames()));
    action.delay_s = map.GetNumber("delay_s", 0.0, NumberRule::Between(0.0, config.duration_s));
    if (!map.Has("timeout_s")) {
      map.Fail("timeout_s",
               "missing required key: an action after an event needs timeout_s > 0, the longest "
               "wait for the event [s]");
    }
    action.timeout_s = map.RequireNumber("timeout_s", kPositiveDuration);
  } else {
    for (const char* key : {"delay_s", "timeout_s"}) {
      if (map.Has(key)) map.Fail(key, "only with after: <event>; a fixed-time action fires at at_s");
    }
    if (!map.Has("at_s")) map.Fail("at_s", "missing required key: give at_s [s] or after: <event>");
    action.at_s = map.RequireNumber("at_s", NumberRule::Between(0.0, config.duration_s));
  }
  const auto unit_index = [&] { return map.RequireInt("unit", 0, unit_count - 1); };
  switch (action.kind) {
    case ActionKind::kClose:
    case ActionKind::kOpen:
    case ActionKind::kIdle:
      break;
    case ActionKind::kMove: {
      const bool absolute = map.Has("position_m");
      const bool offset = map.Has("offset_m");
      if (absolute == offset) map.FailHere("move needs exactly one of position_m (absolute) or offset_m");
      action.relative = offset;
      action.vector = ReadVector(map, absolute ? "position_m" : "offset_m", {0, 0, 0}, true,
                                 NumberRule::Between(-sim::kMaxPositionM, sim::kMaxPositionM));
      action.duration_s = map.GetNumber("duration_s", 1.0, kDuration);
      action.profile = ReadProfile(map);
      break;
    }
    case ActionKind::kLift:
      action.height_m = map.RequireNumber("height_m", NumberRule::Between(-1.0, 1.0));
      action.duration_s = map.GetNumber("duration_s", 1.0, kDuration);
      action.profile = ReadProfile(map);
      break;
    case ActionKind::kShake: {
      action.frequency_hz = map.RequireNumber("frequency_hz", NumberRule{0.0, 100.0, true});
      action.amplitude_m = map.RequireNumber("amplitude_m", NumberRule{0.0, 0.1, true});
      action.duration_s = map.RequireNumber("duration_s", kPositiveDuration);
      action.vector = ReadVector(map, "axis", {0, 0, 1}, false, NumberRule::Between(-1e3, 1e3));
      const double norm = std::hypot(action.vector[0], action.vector[1], action.vector[2]);
      if (!(norm > 1e-9)) map.Fail("axis", "must not be the zero vector");
      for (double& component : action.vector) component /= norm;
      // An arm starts and stops shaking smoothly; one period in and out unless the file says.
      action.ramp_s =
          map.GetNumber("ramp_s", std::min(1.0 / action.frequency_hz, 0.5 * action.duration_s), kDuration);
      if (action.ramp_s > 0.5 * action.duration_s) map.Fail("ramp_s", "must be <= duration_s / 2");
      break;
    }
    case ActionKind::kAddMass:
      action.mass_kg =
          map.RequireNumber("mass_kg", NumberRule::Between(-sim::kMaxObjectMassKg, sim::kMaxObjectMassKg));
      if (action.mass_kg == 0.0) map.Fail("mass_kg", "must not be 0");
      action.ramp_s = map.GetNumber("ramp_s", 0.0, kDuration);
      action.profile = ReadProfile(map);
      break;
    case ActionKind::kPull:
      action.vector = ReadVector(map, "force_n", {0, 0, 0}, true);
      for (double component : action.vector) {
        if (std::abs(component) > sim::kMaxForceN)
          map.Fail("force_n", "each component must be within +-1000 N");
      }
      action.ramp_s = map.GetNumber("ramp_s", 0.0, kDuration);
      action.duration_s = map.GetNumber("duration_s", 0.0, kDuration);
      action.profile = ReadProfile(map);
      break;
    case ActionKind::kSetFriction:
      action.friction = map.RequireNumber("friction", NumberRule{0.0, sim::kMaxFriction, true});
      action.ramp_s = map.GetNumber("ramp_s", 0.0, kDuration);
      action.profile = ReadProfile(map);
      break;
    case ActionKind::kDeadUnit:
    case ActionKind::kShortUnit:
    case ActionKind::kRestoreUnit:
      action.unit = unit_index();
      break;
    case ActionKind::kBias:
      action.unit = unit_index();
      action.r1_bias_ohm = map.GetNumber("r1_ohm", 0.0, NumberRule::Between(-1e5, 1e5));
      action.r2_bias_ohm = map.GetNumber("r2_ohm", 0.0, NumberRule::Between(-1e5, 1e5));
      break;
    case ActionKind::kNoiseBurst:
      action.noise_scale = map.GetNumber("scale", 10.0, NumberRule::Between(0.0, 1e4));
      action.duration_s = map.RequireNumber("duration_s", kPositiveDuration);
      if (config.sensor.strain_model.noise_ohm <= 0.0) {
        map.Fail("action", "noise_burst scales sensor.strain_model.noise_ohm, which is 0; set it > 0");
      }
      break;
    case ActionKind::kDropFrames:
      action.duration_s = map.RequireNumber("duration_s", kPositiveDuration);
      action.probability = map.GetNumber("probability", 1.0, NumberRule::Between(0.0, 1.0));
      break;
    case ActionKind::kAddLatency:
      action.latency_s = map.RequireNumber("latency_s", NumberRule::Between(0.0, 1.0));
      break;
  }
  map.RejectUnknownKeys();
  return action;
}

Expectations LoadExpectations(const YamlMap& map, const ScenarioConfig& config) {
  Expectations e;
  ExpectationsFields().Load(map, &e);
  // Needs the scene: the one rule the table cannot state.
  if (e.not_crushed.value_or(false) && config.scene.object.crush_limit_n <= 0.0) {
    map.Fail("not_crushed", "needs object.crush_limit_n > 0 (the object is not fragile)");
  }
  return e;
}

MetricsConfig LoadMetricsConfig(const YamlMap& map) {
  MetricsConfig m;
  MetricsConfigFields().Load(map, &m);
  // The one cross-field rule, checked here rather than in the table: the message names the key the
  // file actually set (an absent one would print its default).
  if (m.slip_speed_m_s < m.creep_speed_m_s) {
    if (map.Has("slip_speed_m_s")) {
      map.Fail("slip_speed_m_s", "must be >= creep_speed_m_s (" + FormatNumber(m.creep_speed_m_s) + ")");
    }
    map.Fail("creep_speed_m_s", "must be <= slip_speed_m_s (default " + FormatNumber(m.slip_speed_m_s) + ")");
  }
  return m;
}

// A check that runs after loading (ScenarioConfig::Validate) throws ConfigError with a key path
// relative to `map`; this puts it at that key's line in the file.
template <typename Fn>
void AtMap(const YamlMap& map, Fn&& fn) {
  try {
    fn();
  } catch (const ConfigError& error) {
    if (!error.file().empty()) throw;
    map.FailAt(error);
  }
}

// Whether `path` names an existing file. A name the file system refuses to look up (a component
// over NAME_MAX, no permission on a directory) names none either: bad input, refused at its key,
// where std::filesystem::exists(path) would throw filesystem_error (exit 1, no file, line or key).
bool Exists(const std::filesystem::path& path) {
  std::error_code error;
  return std::filesystem::exists(path, error);
}

std::string ShippedLayoutPath(const std::string& name) {
  return common::DataPath("sensor/layouts/" + name + ".yaml");
}

bool IsShippedLayout(const std::string& name) {
  return name.find('/') == std::string::npos && name.find(".yaml") == std::string::npos &&
         Exists(ShippedLayoutPath(name));
}

// kn and kt of the unit `config` describes, analysed once per process and unit: suites, sweeps and
// the scorecard load the same unit many times, and an analysis takes about 0.1 s (over 10 s in a
// sanitizer build). Keyed by the config's resolved values, so a file edited between loads is
// analysed again and two files describing one unit share the result.
fea::Sensitivities CachedSensitivities(const fea::FeaConfig& config) {
  static std::mutex mutex;
  static std::map<std::string, fea::Sensitivities> analysed;
  constexpr size_t kCapacity = 16;  // units per process; beyond, the cache starts over
  const std::string key = fea::FeaConfigFields().EmitYaml(config);
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (const auto found = analysed.find(key); found != analysed.end()) return found->second;
  }
  const fea::Sensitivities sensitivities = fea::ComputeSensitivities(config);
  std::lock_guard<std::mutex> lock(mutex);
  if (analysed.size() >= kCapacity) analysed.clear();
  analysed.emplace(key, sensitivities);
  return sensitivities;
}

SensorOptions LoadSensorOptions(const YamlMap& map, const std::string& scenario_file, int* unit_count) {
  SensorOptions s;
  // The plain fields (numbers, names, paths as written); the paths, the profile and the three
  // sections are resolved below.
  SensorOptionsFields().Load(map, &s);
  if (!IsShippedLayout(s.layout)) {
    std::filesystem::path path(s.layout);
    if (path.is_relative()) path = std::filesystem::path(scenario_file).parent_path() / path;
    if (!Exists(path)) {
      map.Fail("layout",
               "no such layout: give default_20, paper_3x3 or a layout file path (relative to "
               "the scenario file)");
    }
    s.layout = std::filesystem::absolute(path).lexically_normal().string();
  }
  const std::string layout_path = IsShippedLayout(s.layout) ? ShippedLayoutPath(s.layout) : s.layout;
  *unit_count = sensor::LoadLayout(layout_path).unit_count();
  // Nominal constants first (explicit keys, then the FEA's kn and kt), then the profile resolved
  // against them, then every explicit key again on top of the profile.
  if (auto sub = map.GetMap("strain_model")) {
    s.strain_model = sensor::LoadStrainModelConfig(*sub, *unit_count);
  }
  if (!s.fea_config.empty()) {
    std::filesystem::path path(s.fea_config);
    if (path.is_relative()) path = std::filesystem::path(scenario_file).parent_path() / path;
    if (!Exists(path)) map.Fail("fea_config", "no such file");
    s.fea_config = std::filesystem::absolute(path).lexically_normal().string();
  }
  if (s.sensitivities == "fea") {
    // Two sources for one number would leave the user guessing which one ran.
    if (auto sub = map.GetMap("strain_model")) {
      for (const char* key : {"kn_per_n", "kt_per_n"}) {
        if (sub->Has(key)) sub->Fail(key, "set by the FEA with sensitivities: fea; remove one of the two");
      }
    }
    // The unit's geometry and material decide kn and kt (about 0.1 s of analysis, once per unit).
    const fea::Sensitivities analysed = CachedSensitivities(
        fea::LoadFeaConfigFile(s.fea_config.empty() ? fea::DefaultFeaConfigPath() : s.fea_config));
    if (!(analysed.kn_per_n > 0.0) || !(analysed.kt_per_n > 0.0)) {
      std::ostringstream reason;
      reason << "the unit in " << (s.fea_config.empty() ? fea::DefaultFeaConfigPath() : s.fea_config)
             << " analyses to kn_per_n = " << analysed.kn_per_n << ", kt_per_n = " << analysed.kt_per_n
             << " /N; both must be > 0 for the gauge to sense normal force and shear (see graspbed fea)";
      map.Fail("sensitivities", reason.str());
    }
    s.strain_model.nominal.kn_per_n = analysed.kn_per_n;
    s.strain_model.nominal.kt_per_n = analysed.kt_per_n;
  }
  const sensor::SensorProfile& profile = sensor::FindSensorProfile(s.profile);
  sensor::ReadoutConfig readout_defaults;
  if (!profile.ideal) {
    const sensor::StrainModelConfig profiled = sensor::ProfileStrainModel(profile, s.strain_model.nominal);
    s.strain_model = profiled;
    if (auto sub = map.GetMap("strain_model")) {
      s.strain_model = sensor::LoadStrainModelConfig(*sub, *unit_count, profiled);
      s.strain_model.nominal.kn_per_n = profiled.nominal.kn_per_n;
      s.strain_model.nominal.kt_per_n = profiled.nominal.kt_per_n;
    }
    // The readout is told the ADC window the strain model ends up with (a profile's or the
    // scenario's own), so a clipped channel reads out of range.
    readout_defaults.adc_full_scale_ohm =
        s.strain_model.adc_bits > 0 ? s.strain_model.adc_full_scale_ohm : 0.0;
    readout_defaults.adc_min_ohm = s.strain_model.adc_bits > 0 ? s.strain_model.adc_min_ohm : 0.0;
  }
  if (auto sub = map.GetMap("readout")) {
    s.readout = sensor::LoadReadoutConfig(*sub, readout_defaults);
  } else {
    s.readout = readout_defaults;
  }
  if (auto sub = map.GetMap("inversion")) s.inversion = sensor::LoadInversionConfig(*sub);
  return s;
}

}  // namespace

const common::FieldTable<Expectations>& ExpectationsFields() {
  using Table = common::FieldTable<Expectations>;
  using C = Expectations;
  static const Table table(
      "expectations",
      {
          Table::OptionalBool("not_dropped", &C::not_dropped,
                              "passes when `true`: the object was grasped and never left the hand while held "
                              "(`false` asks for a drop)"),
          Table::OptionalNumber("max_slip_mm", &C::max_slip_mm, NumberRule::NonNegative(), "mm",
                                "passes when `max_slip_mm` <= limit"),
          Table::OptionalNumber("max_peak_grip_n", &C::max_peak_grip_n, NumberRule::Positive(), "N",
                                "passes when `peak_grip_n` <= limit"),
          Table::OptionalBool("not_crushed", &C::not_crushed, "passes when `peak_grip_n` <= crush limit")
              .Note("true needs `object.crush_limit_n` > 0"),
          Table::OptionalNumber(
              "slip_detected_within_ms", &C::slip_detected_within_ms, NumberRule::NonNegative(), "ms",
              "passes when every gross slip event (>= `metrics.gross_slip_m` or a drop) was flagged by the "
              "controller, the latest within the limit; no gross slip passes (note \"no gross slip event "
              "occurred\")"),
          Table::OptionalNumber("micro_slip_detected_within_ms", &C::micro_slip_detected_within_ms,
                                NumberRule::NonNegative(), "ms",
                                "the same for the micro-slip events (below `metrics.gross_slip_m`)"),
          Table::OptionalNumber("max_grip_efficiency", &C::max_grip_efficiency, NumberRule::Positive(), "-",
                                "passes when `grip_efficiency` (mean grip held / the oracle grip) <= limit; the "
                                "run computes the oracle grip; fails without one"),
          Table::OptionalNumber(
              "max_estimation_error_n", &C::max_estimation_error_n, NumberRule::NonNegative(), "N",
              "passes when max(`fn_rmse_n`, `ft_rmse_n`) <= limit; fails when no unit was ever in contact"),
          Table::OptionalNumber("stable_within_s", &C::stable_within_s, NumberRule::NonNegative(), "s",
                                "passes when `time_to_stable_s` exists and <= limit"),
          Table::OptionalNumber("max_false_slip_per_min", &C::max_false_slip_per_min,
                                NumberRule::NonNegative(), "1/min",
                                "passes when `false_slip_per_min` <= limit"),
          Table::OptionalBool("grasped_on_sensor", &C::grasped_on_sensor,
                              "checked in every run unless `false`: passes when the held object was on the "
                              "sensorised pad (`unsensed_held_s` <= `metrics.max_unsensed_held_s` and "
                              "`sensed_grip_share` >= `metrics.min_sensed_grip_share`); a run never held "
                              "passes it (not_dropped speaks for that)"),
      });
  return table;
}

const common::FieldTable<MetricsConfig>& MetricsConfigFields() {
  using Table = common::FieldTable<MetricsConfig>;
  using C = MetricsConfig;
  static const Table table(
      "metrics",
      {
          Table::Number("sliding_friction_fraction", &C::sliding_friction_fraction, {0.0, 1.0, true}, "",
                        "a contact slides (slip) when its friction force is at least this fraction of mu x "
                        "its normal force; motion inside the cone is the soft contact's give"),
          Table::Number("slip_min_load_share", &C::slip_min_load_share, {0.0, 1.0, false}, "-",
                        "slip also needs the sliding contacts to carry this share of their digit's normal "
                        "force; below it is partial slip (partial_slip_mm), no slip event; 0 = any share"),
          Table::Number("creep_speed_m_s", &C::creep_speed_m_s, {0.0, kMaxSpeedMS, true}, "m/s",
                        "sliding speed below which motion is creep, not slip"),
          Table::Number("slip_speed_m_s", &C::slip_speed_m_s, {0.0, kMaxSpeedMS, true}, "m/s",
                        "sliding speed above which a slip event starts")
              .Note(">= `creep_speed_m_s`"),
          Table::Number("creep_event_m", &C::creep_event_m, NumberRule::Between(0.0, 0.1), "m",
                        "a slower slide (above creep_speed_m_s) is a slip event once it has slid this far; "
                        "0: only slip_speed_m_s opens events"),
          Table::Number("slip_event_gap_s", &C::slip_event_gap_s, kDuration, "s",
                        "a slip event ends after the speed stays below slip_speed_m_s this long"),
          Table::Number("early_detection_window_s", &C::early_detection_window_s, kDuration, "s",
                        "a controller slip flag up to this long before a ground-truth onset detects it"),
          Table::Number("gross_slip_m", &C::gross_slip_m, NumberRule::Between(0.0, 0.1), "m",
                        "a slip event that slides at least this far (or ends in a drop) is gross; smaller "
                        "ones are micro-slips"),
          Table::Number("grasp_force_n", &C::grasp_force_n, {0.0, sim::kMaxForceN, true}, "N",
                        "finger normal force above which the object counts as grasped"),
          Table::Number("seating_s", &C::seating_s, kDuration, "s",
                        "after a grasp is established the pads settle this long: motion opens no slip "
                        "event, flags are not false"),
          Table::Number("drop_distance_m", &C::drop_distance_m, {0.0, sim::kMaxPositionM, true}, "m",
                        "object displacement relative to the wrist, from where it was grasped, that counts "
                        "as dropped; from where it was at the close command, before the grasp is "
                        "established, as pushed out"),
          Table::Number("acquisition_lift_m", &C::acquisition_lift_m, NumberRule::Between(0.0, 0.1), "m",
                        "the grasp is established (both digits touching) once the object's lowest point is "
                        "this far above the table, the hand carrying its weight ..."),
          Table::Number("acquisition_settle_s", &C::acquisition_settle_s, kDuration, "s",
                        "... or once the object has stayed within `acquisition_settle_m` of one place "
                        "relative to the wrist this long ...; before it, its motion is acquisition_shift_mm"),
          Table::Number("acquisition_settle_m", &C::acquisition_settle_m, NumberRule::Between(0.0, 0.01), "m",
                        "the band of `acquisition_settle_s`"),
          Table::Number("acquisition_wrist_m", &C::acquisition_wrist_m, NumberRule::Between(0.0, 0.1), "m",
                        "... or once the wrist has moved this far since the first touch (an action loads the "
                        "grasp) ..."),
          Table::Number("acquisition_max_s", &C::acquisition_max_s, kDuration, "s",
                        "... or this long after the first touch, whatever the object does"),
          Table::Number("max_unsensed_held_s", &C::max_unsensed_held_s, kDuration, "s",
                        "grasped_on_sensor: the longest time held with no unit loaded at or above the "
                        "contact threshold"),
          Table::Number("min_sensed_grip_share", &C::min_sensed_grip_share, {0.0, 1.0, true}, "-",
                        "grasped_on_sensor: the least share of the finger's normal force the mesas carry "
                        "over the held time"),
          Table::Number("stable_window_s", &C::stable_window_s, kPositiveDuration, "s",
                        "stable grasp: no slip event and the squeeze within the band over this window"),
          Table::Number("stable_force_band", &C::stable_force_band, {0.0, 1.0, true}, "-",
                        "relative band for the stable squeeze"),
      });
  return table;
}

const common::FieldTable<SensorOptions>& SensorOptionsFields() {
  using Table = common::FieldTable<SensorOptions>;
  using C = SensorOptions;
  static const Table table(
      "sensor",
      {
          Table::Text("layout", &C::layout, {}, "sensing units; unit indices in actions refer to it")
              .Note("`default_20`, `paper_3x3` or a layout file path (relative to the scenario file)"),
          Table::Number("sample_rate_hz", &C::sample_rate_hz, NumberRule::Between(1.0, kMaxRateHz), "Hz",
                        "sensor frames per second")
              .Note("simulated: <= the larger of 1 / `physics.timestep_s` and `controller.rate_hz`"),
          Table::Number("latency_s", &C::latency_s, NumberRule::Between(0.0, kMaxLatencyS), "s",
                        "sampling to delivery")
              .Note("with the `add_latency` actions at most 1 in total"),
          Table::Number("drop_probability", &C::drop_probability, NumberRule::Between(0.0, 1.0), "-",
                        "chance each frame is lost on the link (seeded)"),
          Table::Text(
              "sensitivities", &C::sensitivities, {"paper", "fea"},
              "where kn, kt come from: `strain_model.kn_per_n/kt_per_n`, or graspbed's FEA of the unit "
              "(docs/fea.md; setting `kn_per_n`/`kt_per_n` as well is refused; the resolved "
              "config.yaml shows the analysed values as a comment). The host's inversion uses the "
              "same nominal constants"),
          Table::Text("fea_config", &C::fea_config, {},
                      "FEA config for `sensitivities: fea` (relative to the scenario file); \"\" = the "
                      "shipped unit"),
          Table::Text("profile", &C::profile, sensor::SensorProfileNames(),
                      "a whole readout chain (docs/sensor.md, \"Sensor profiles\"), resolved against the "
                      "sensitivities above; it sets `strain_model` and `readout` values, keys given there "
                      "explicitly override it"),
          Table::Custom("strain_model", "", "ideal paper unit", "section", "below"),
          Table::Custom("readout", "", "the profile's", "section", "below"),
          Table::Custom("inversion", "", "paper unit", "section", "below"),
      });
  return table;
}

const common::FieldTable<ControllerOptions>& ControllerOptionsFields() {
  using Table = common::FieldTable<ControllerOptions>;
  using C = ControllerOptions;
  static const Table table(
      "controller",
      {
          Table::Custom("name", "", "`open_loop`", "`open_loop`, `grip_slip`, or `plugin:LIBRARY`",
                        "the controller under test (docs/controllers.md for plugins)"),
          Table::Custom("plugin", "", "none",
                        "a library path (relative to this file) or a bare name on the plugin "
                        "search path",
                        "the same as `name: plugin:LIBRARY`; not together with `name`"),
          Table::Custom("params", "", "the controller's defaults",
                        "the controller's declared parameters and ranges",
                        "`open_loop`: `close_effort` 0.5, `open_effort` 0.5 (0 .. 1); `grip_slip`: "
                        "docs/controller.md, \"Parameters\""),
          Table::Number("grip_ceiling_n", &C::grip_ceiling_n, NumberRule::Between(0.0, sim::kMaxForceN), "N",
                        "task grip ceiling handed to the controller (fragile objects); 0 = none"),
          Table::Number("rate_hz", &C::rate_hz, NumberRule::Between(1.0, kMaxRateHz), "Hz",
                        "control ticks per second")
              .Note("simulated: faster than the physics steps ticks between them, on the last step's state"),
          Table::Number("stale_timeout_s", &C::stale_timeout_s, {0.0, kMaxStaleTimeoutS, true}, "s",
                        "no frame for this long: state stale, the controller holds")
              .Note(">= 1 / `sensor.sample_rate_hz`"),
      });
  return table;
}

ControllerOptions LoadControllerOptions(const YamlMap& map, const std::string& default_name) {
  ControllerOptions c;
  // `plugin: LIBRARY` is `name: plugin:LIBRARY`; a relative library path is relative to this file.
  const char* name_key = map.Has("plugin") ? "plugin" : "name";
  if (map.Has("plugin")) {
    if (map.Has("name")) map.Fail("plugin", "give either name or plugin, not both");
    c.name = std::string(controller::kPluginPrefix) + map.RequireString("plugin");
  } else {
    c.name = map.GetString("name", default_name);
    if (!controller::IsPluginName(c.name))
      c.name = map.GetString("name", default_name, controller::ControllerNames());
  }
  c.name = controller::ResolvePluginName(c.name, std::filesystem::path(map.file()).parent_path().string());
  std::vector<controller::ControllerParameter> declared;
  try {
    declared = controller::ControllerParameters(c.name);
  } catch (const std::invalid_argument& error) {
    map.Fail(name_key, error.what());
  } catch (const std::filesystem::filesystem_error& error) {
    // The plugin loader's look-up of a library name the file system refuses (e.g. too long).
    map.Fail(name_key, std::string("cannot look up the plugin library: ") + error.code().message() + ": " +
                           error.path1().string());
  }
  for (const auto& parameter : declared) c.params[parameter.name] = parameter.default_value;
  if (auto params = map.GetMap("params")) {
    std::vector<std::string> valid;
    for (const auto& parameter : declared) valid.push_back(parameter.name);
    for (const std::string& key : params->Keys()) {
      const auto match =
          std::find_if(declared.begin(), declared.end(), [&](const auto& p) { return p.name == key; });
      if (match == declared.end()) {
        params->Fail(key, "controller '" + c.name + "' has no such parameter; valid parameters: " +
                              (valid.empty() ? std::string("(none)") : Join(valid)));
      }
      c.params[key] =
          params->GetNumber(key, match->default_value, NumberRule::Between(match->min, match->max));
    }
  }
  ControllerOptionsFields().Load(map, &c);
  // Each value is in its range; what is left are the controller's cross-field checks (e.g. min_grip_n
  // <= max_grip_n). Build it once and blame the parameter the error names, as data: the built-in
  // controllers throw a ConfigError keyed by the parameter. A plugin's own std::invalid_argument
  // names no key, so its parameters as a whole are blamed.
  try {
    controller::MakeController(c.name, c.params);
  } catch (const ConfigError& error) {
    const auto params = map.GetMap("params");
    if (params && !error.key().empty() && params->Has(error.key()))
      params->Fail(error.key(), error.message());
    map.Fail(params ? "params" : name_key, error.what());
  } catch (const std::invalid_argument& error) {
    map.Fail(map.GetMap("params") ? "params" : name_key, error.what());
  }
  return c;
}

namespace {

ScenarioConfig LoadFromRoot(const YAML::Node& root, const std::string& file) {
  const YamlMap map(root, file, "");
  ScenarioConfig config;
  config.source_file = file;
  config.name = map.GetString("name", FileStem(file));
  config.description = map.GetString("description", "");
  const double seed = map.GetNumber("seed", 1.0, NumberRule::Between(0.0, kMaxSeed));
  if (seed != std::floor(seed)) map.Fail("seed", "expected a whole number");
  config.seed = static_cast<uint64_t>(seed);
  config.duration_s = map.GetNumber("duration_s", config.duration_s, NumberRule{0.0, kMaxDurationS, true});

  // The scene sections go to the sim loader as one map; their nodes keep their file positions.
  YAML::Node scene_node(YAML::NodeType::Map);
  for (const char* key : {"object", "hand", "physics"}) {
    const YAML::Node section = map.Raw(key);  // marks the key valid even when absent
    if (section.IsDefined()) scene_node[key] = section;
  }
  const YamlMap scene_map(scene_node, file, "");
  AtMap(scene_map, [&] { config.scene = sim::LoadSceneConfig(scene_map); });

  int unit_count = sensor::kMaxUnits;
  if (auto sensor_map = map.GetMap("sensor")) {
    config.sensor = LoadSensorOptions(*sensor_map, file, &unit_count);
  } else {
    YAML::Node empty(YAML::NodeType::Map);
    config.sensor = LoadSensorOptions(YamlMap(empty, file, "sensor"), file, &unit_count);
  }
  if (auto proprioception_map = map.GetMap("proprioception")) {
    config.proprioception = sim::LoadProprioceptionConfig(*proprioception_map);
  }
  if (auto controller_map = map.GetMap("controller")) {
    config.controller = LoadControllerOptions(*controller_map);
  } else {
    YAML::Node empty(YAML::NodeType::Map);
    config.controller = LoadControllerOptions(YamlMap(empty, file, "controller"));
  }
  // Sorted by time; an event action takes the sort time of the action before it in the file, so
  // it stays right behind that action (equal keys keep file order).
  std::vector<std::pair<double, Action>> keyed;
  for (const YamlMap& action_map : map.GetMapList("script")) {
    const Action action = LoadAction(action_map, config, unit_count);
    const double key =
        action.after != ScriptEvent::kNone ? (keyed.empty() ? 0.0 : keyed.back().first) : action.at_s;
    keyed.emplace_back(key, action);
  }
  std::stable_sort(keyed.begin(), keyed.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [key, action] : keyed) config.script.push_back(action);
  if (auto metrics_map = map.GetMap("metrics")) config.metrics = LoadMetricsConfig(*metrics_map);
  if (auto expectations_map = map.GetMap("expectations")) {
    config.expectations = LoadExpectations(*expectations_map, config);
  }
  const std::string backend = map.GetString("backend", "sim", {"sim", "serial", "replay"});
  config.backend = backend == "serial"   ? Backend::kSerial
                   : backend == "replay" ? Backend::kReplay
                                         : Backend::kSim;
  if (auto serial_map = map.GetMap("serial")) config.serial = hardware::LoadHardwareConfig(*serial_map);
  config.log = map.GetString("log", "");
  if (config.backend == Backend::kReplay && config.log.empty()) {
    map.Fail("backend", "replay needs the recording to replay: log: PATH (or graspbed run --log PATH)");
  }
  if (config.backend == Backend::kSerial && config.serial.port.empty()) {
    map.Fail("backend", "serial needs a port: serial: {port: PATH} (or graspbed run --port PATH)");
  }
  map.RejectUnknownKeys();
  AtMap(map, [&] { config.Validate(); });
  double latency_s = config.sensor.latency_s;
  for (const Action& action : config.script) {
    if (action.kind != ActionKind::kAddLatency) continue;
    latency_s += action.latency_s;
    if (latency_s > kMaxLatencyS) {
      throw ConfigError(
          file + ":" + std::to_string(action.line) + ": add_latency at_s = " + FormatNumber(action.at_s) +
          ": sensor.latency_s plus the add_latency actions up to here = " + FormatNumber(latency_s) +
          " s: must be <= " + FormatNumber(kMaxLatencyS) + " s");
    }
  }
  // The signals are reserved before the run (one row per control tick, at most one per step).
  const double ticks_per_s = std::min(config.controller.rate_hz, 1.0 / config.scene.physics.timestep_s);
  const double row_bytes =
      8.0 * (static_cast<double>(kSignalBoundFixedColumns + controller::kMaxDiagnosticChannels) +
             static_cast<double>(kSignalBoundColumnsPerUnit) * unit_count);
  const double signal_bytes = std::ceil(config.duration_s * ticks_per_s) * row_bytes;
  if (signal_bytes > kMaxSignalBytes) {
    map.Fail("duration_s", "with controller.rate_hz = " + FormatNumber(config.controller.rate_hz) +
                               " the run keeps " + FormatNumber(std::round(signal_bytes / 1e6)) +
                               " MB of signals (at most " + FormatNumber(kMaxSignalBytes / 1e6) +
                               " MB): shorten duration_s or lower controller.rate_hz");
  }
  return config;
}

YAML::Node ParseRoot(const std::string& text, const std::string& source_name) {
  try {
    YAML::Node root = YAML::Load(text);
    if (!root.IsNull() && !root.IsMap()) {
      throw ConfigError(common::Where(source_name, root) + "expected a mapping of keys at the top level");
    }
    if (root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
    return root;
  } catch (const YAML::Exception& error) {
    throw ConfigError(source_name + ":" + std::to_string(error.mark.line + 1) +
                      ": YAML syntax error: " + error.msg);
  }
}

// A copy of `node` built from scratch, so no position of the --set text can pose as a file line.
YAML::Node WithoutMarks(const YAML::Node& node) {
  if (node.IsScalar()) return YAML::Node(node.Scalar());
  if (node.IsSequence()) {
    YAML::Node copy(YAML::NodeType::Sequence);
    for (const auto& item : node) copy.push_back(WithoutMarks(item));
    return copy;
  }
  if (node.IsMap()) {
    YAML::Node copy(YAML::NodeType::Map);
    for (const auto& entry : node) copy[entry.first.Scalar()] = WithoutMarks(entry.second);
    return copy;
  }
  return YAML::Node(YAML::NodeType::Null);
}

// One step of a dotted key path: a map key, optionally followed by [index] parts.
struct PathStep {
  std::string key;
  std::vector<int> indices;
};

std::vector<PathStep> ParsePath(const std::string& key) {
  std::vector<PathStep> steps;
  std::stringstream stream(key);
  std::string part;
  while (std::getline(stream, part, '.')) {
    PathStep step;
    const size_t bracket = part.find('[');
    step.key = part.substr(0, bracket);
    if (step.key.empty()) throw ConfigError("--set " + key + ": empty key in the path");
    size_t position = bracket;
    while (position != std::string::npos) {
      const size_t close = part.find(']', position);
      if (close == std::string::npos) throw ConfigError("--set " + key + ": missing ']'");
      const std::string digits = part.substr(position + 1, close - position - 1);
      int index = 0;
      const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), index);
      if (error != std::errc() || end != digits.data() + digits.size() || digits.empty() || index < 0) {
        throw ConfigError("--set " + key + ": bad list index '" + digits + "'");
      }
      step.indices.push_back(index);
      position = close + 1 < part.size() ? close + 1 : std::string::npos;
      if (position != std::string::npos && part[position] != '[') {
        throw ConfigError("--set " + key + ": unexpected text after ']'");
      }
    }
    steps.push_back(step);
  }
  if (steps.empty()) throw ConfigError("--set: empty key");
  return steps;
}

void EnsureMap(YAML::Node& node, const std::string& what) {
  if (!node.IsDefined() || node.IsNull()) {
    node = YAML::Node(YAML::NodeType::Map);
  } else if (!node.IsMap()) {
    throw ConfigError("--set " + what + ": not a mapping in the scenario");
  }
}

void EmitNumber(YAML::Emitter& out, const char* key, double value) {
  out << YAML::Key << key << YAML::Value << FormatNumber(value);
}

template <size_t N>
void EmitVector(YAML::Emitter& out, const char* key, const std::array<double, N>& values) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (double value : values) out << FormatNumber(value);
  out << YAML::EndSeq;
}

void EmitSensor(YAML::Emitter& out, const SensorOptions& s) {
  out << YAML::Key << "sensor" << YAML::Value << YAML::BeginMap;
  SensorOptionsFields().Emit(s, out);
  const sensor::StrainModelConfig& m = s.strain_model;
  out << YAML::Key << "strain_model" << YAML::Value << YAML::BeginMap;
  if (s.sensitivities == "fea") {
    // Derived, not set: reloading this file runs the analysis again (and refuses explicit values).
    out << YAML::Comment("kn_per_n " + FormatNumber(m.nominal.kn_per_n) + ", kt_per_n " +
                         FormatNumber(m.nominal.kt_per_n) + " /N from the FEA");
    sensor::EmitStrainModelConfig(m, out, {"kn_per_n", "kt_per_n"});
  } else {
    sensor::EmitStrainModelConfig(m, out);
  }
  out << YAML::EndMap;
  out << YAML::Key << "readout" << YAML::Value << YAML::BeginMap;
  sensor::ReadoutConfigFields().Emit(s.readout, out);
  out << YAML::EndMap;
  out << YAML::Key << "inversion" << YAML::Value << YAML::BeginMap;
  sensor::InversionConfigFields().Emit(s.inversion, out);
  out << YAML::EndMap;
  out << YAML::EndMap;
}

void EmitAction(YAML::Emitter& out, const Action& a) {
  out << YAML::BeginMap;
  if (a.after != ScriptEvent::kNone) {
    out << YAML::Key << "after" << YAML::Value << EventName(a.after);
    EmitNumber(out, "delay_s", a.delay_s);
    EmitNumber(out, "timeout_s", a.timeout_s);
  } else {
    EmitNumber(out, "at_s", a.at_s);
  }
  out << YAML::Key << "action" << YAML::Value << ActionName(a.kind);
  const auto profile = [&] { out << YAML::Key << "profile" << YAML::Value << ToString(a.profile); };
  switch (a.kind) {
    case ActionKind::kClose:
    case ActionKind::kOpen:
    case ActionKind::kIdle:
      break;
    case ActionKind::kMove:
      EmitVector(out, a.relative ? "offset_m" : "position_m", a.vector);
      EmitNumber(out, "duration_s", a.duration_s);
      profile();
      break;
    case ActionKind::kLift:
      EmitNumber(out, "height_m", a.height_m);
      EmitNumber(out, "duration_s", a.duration_s);
      profile();
      break;
    case ActionKind::kShake:
      EmitNumber(out, "frequency_hz", a.frequency_hz);
      EmitNumber(out, "amplitude_m", a.amplitude_m);
      EmitNumber(out, "duration_s", a.duration_s);
      EmitVector(out, "axis", a.vector);
      EmitNumber(out, "ramp_s", a.ramp_s);
      break;
    case ActionKind::kAddMass:
      EmitNumber(out, "mass_kg", a.mass_kg);
      EmitNumber(out, "ramp_s", a.ramp_s);
      profile();
      break;
    case ActionKind::kPull:
      EmitVector(out, "force_n", a.vector);
      EmitNumber(out, "ramp_s", a.ramp_s);
      EmitNumber(out, "duration_s", a.duration_s);
      profile();
      break;
    case ActionKind::kSetFriction:
      EmitNumber(out, "friction", a.friction);
      EmitNumber(out, "ramp_s", a.ramp_s);
      profile();
      break;
    case ActionKind::kDeadUnit:
    case ActionKind::kShortUnit:
    case ActionKind::kRestoreUnit:
      out << YAML::Key << "unit" << YAML::Value << a.unit;
      break;
    case ActionKind::kBias:
      out << YAML::Key << "unit" << YAML::Value << a.unit;
      EmitNumber(out, "r1_ohm", a.r1_bias_ohm);
      EmitNumber(out, "r2_ohm", a.r2_bias_ohm);
      break;
    case ActionKind::kNoiseBurst:
      EmitNumber(out, "scale", a.noise_scale);
      EmitNumber(out, "duration_s", a.duration_s);
      break;
    case ActionKind::kDropFrames:
      EmitNumber(out, "duration_s", a.duration_s);
      EmitNumber(out, "probability", a.probability);
      break;
    case ActionKind::kAddLatency:
      EmitNumber(out, "latency_s", a.latency_s);
      break;
  }
  out << YAML::EndMap;
}

}  // namespace

const char* ActionName(ActionKind kind) {
  for (const ActionEntry& entry : kActions) {
    if (entry.kind == kind) return entry.name;
  }
  return "?";
}

std::vector<std::string> ActionNames() {
  std::vector<std::string> names;
  for (const ActionEntry& entry : kActions) names.emplace_back(entry.name);
  return names;
}

const char* EventName(ScriptEvent event) {
  for (const EventEntry& entry : kEvents) {
    if (entry.event == event) return entry.name;
  }
  return "";
}

std::vector<std::string> EventNames() {
  std::vector<std::string> names;
  for (const EventEntry& entry : kEvents) names.emplace_back(entry.name);
  return names;
}

const char* ToString(Profile profile) { return profile == Profile::kLinear ? "linear" : "minimum_jerk"; }

bool Expectations::empty() const {
  return !not_dropped && !max_slip_mm && !max_peak_grip_n && !not_crushed && !slip_detected_within_ms &&
         !micro_slip_detected_within_ms && !max_grip_efficiency && !max_estimation_error_n && !stable_within_s &&
         !max_false_slip_per_min;
}

void ScenarioConfig::Validate() const {
  if (!(duration_s > 0.0) || !std::isfinite(duration_s)) {
    throw ConfigError("", 0, "duration_s", FormatNumber(duration_s), "must be > 0");
  }
  // The sections' own checks name their keys relative to the section; here they get its path.
  const auto in_section = [](const std::string& path, auto&& check) {
    try {
      check();
    } catch (const ConfigError& error) {
      // Validate() prefixed its table's name ("scene.", "strain_model."); the file path replaces it.
      const std::string key = error.key();
      const size_t dot = key.find('.');
      throw ConfigError("", 0, path.empty() ? key.substr(dot + 1) : path + key.substr(dot), error.value(),
                        error.message());
    }
  };
  in_section("", [&] { scene.Validate(); });
  in_section("sensor.strain_model", [&] { sensor.strain_model.Validate(); });
  in_section("sensor.readout", [&] { sensor.readout.Validate(); });
  in_section("sensor.inversion", [&] { sensor.inversion.Validate(); });
  in_section("proprioception", [&] { proprioception.Validate(); });
  if (controller.stale_timeout_s < 1.0 / sensor.sample_rate_hz) {
    throw ConfigError("", 0, "controller.stale_timeout_s", FormatNumber(controller.stale_timeout_s),
                      "must be >= one sensor period (1 / sensor.sample_rate_hz = " +
                          FormatNumber(1.0 / sensor.sample_rate_hz) + " s)");
  }
  // The simulated sensor samples when the rig's clock moves: at every physics step's end and every
  // control tick (between steps when the step is the longer). A faster sensor would silently run slower.
  if (backend == Backend::kSim) {
    const double clock_rate_hz = std::max(1.0 / scene.physics.timestep_s, controller.rate_hz);
    if (sensor.sample_rate_hz > clock_rate_hz * (1.0 + 1e-9)) {
      throw ConfigError("", 0, "sensor.sample_rate_hz", FormatNumber(sensor.sample_rate_hz),
                        "must be <= the larger of 1 / physics.timestep_s and controller.rate_hz = " +
                            FormatNumber(clock_rate_hz) +
                            " Hz (samples are taken at physics steps and control ticks)");
    }
  }
  for (const Action& action : script) {
    // The script is sorted by time, so an action is named by its kind and located by its own line.
    const std::string key = "script action '" + std::string(ActionName(action.kind)) + "' ";
    const auto fail = [&](const std::string& field, double value, const std::string& message) {
      throw ConfigError(action.line > 0 ? source_file : "", action.line, key + field, FormatNumber(value),
                        message);
    };
    if (action.after != ScriptEvent::kNone) {
      // Built in code: the loader's checks again.
      if (!(action.delay_s >= 0.0) || !std::isfinite(action.delay_s))
        fail("delay_s", action.delay_s, "must be >= 0");
      if (!(action.timeout_s > 0.0) || !std::isfinite(action.timeout_s)) {
        fail("timeout_s", action.timeout_s, "must be > 0");
      }
      continue;
    }
    if (action.at_s > duration_s) fail("at_s", action.at_s, "after duration_s");
  }
}

/// How the user gave `override_value`, for an error's context.
static std::string OverrideOrigin(const Override& override_value) {
  return override_value.origin.empty() ? "--set " + override_value.key + "=" + override_value.value
                                       : override_value.origin;
}

Override ParseOverride(const std::string& text) {
  const size_t equals = text.find('=');
  if (equals == std::string::npos || equals == 0) {
    throw ConfigError("--set " + text + ": expected key=value, e.g. object.mass_kg=0.3");
  }
  return {text.substr(0, equals), text.substr(equals + 1)};
}

void ApplyOverride(YAML::Node& root, const Override& override_value) {
  const std::vector<PathStep> steps = ParsePath(override_value.key);
  YAML::Node value;
  try {
    value = WithoutMarks(YAML::Load(override_value.value));
  } catch (const YAML::Exception& error) {
    throw ConfigError("--set " + override_value.key + "=" + override_value.value +
                      ": YAML syntax error: " + error.msg);
  }
  // Walk with explicit node handles; yaml-cpp's operator[] on a non-const node creates entries.
  YAML::Node node;
  node.reset(root);
  for (size_t s = 0; s < steps.size(); ++s) {
    const PathStep& step = steps[s];
    const bool last_step = s + 1 == steps.size();
    EnsureMap(node, override_value.key);
    YAML::Node child = node[step.key];
    if (step.indices.empty()) {
      if (last_step) {
        node[step.key] = value;
        return;
      }
      if (!child.IsDefined() || child.IsNull()) node[step.key] = YAML::Node(YAML::NodeType::Map);
      // reset() rebinds the handle; operator= would overwrite the node it points at.
      node.reset(node[step.key]);
      continue;
    }
    YAML::Node list;
    list.reset(child);
    for (size_t i = 0; i < step.indices.size(); ++i) {
      if (!list.IsSequence() || step.indices[i] >= static_cast<int>(list.size())) {
        throw ConfigError("--set " + override_value.key + ": index " + std::to_string(step.indices[i]) +
                          " out of range (list has " + std::to_string(list.IsSequence() ? list.size() : 0) +
                          " entries)");
      }
      if (last_step && i + 1 == step.indices.size()) {
        list[step.indices[i]] = value;
        return;
      }
      list.reset(list[step.indices[i]]);
    }
    node.reset(list);
  }
}

ScenarioConfig LoadScenarioFromString(const std::string& text, const std::string& source_name,
                                      const std::vector<Override>& overrides) {
  // The file with the first `count` overrides applied.
  const auto root_with = [&](size_t count) {
    YAML::Node root = ParseRoot(text, source_name);
    for (size_t i = 0; i < count; ++i) {
      const Override& o = overrides[i];
      // A different controller does not take the file's parameters of the old one.
      if (o.key == "controller.name" && root["controller"].IsMap() && root["controller"]["params"] &&
          !(root["controller"]["name"] && root["controller"]["name"].IsScalar() &&
            root["controller"]["name"].Scalar() == o.value)) {
        root["controller"].remove("params");
      }
      // ... and a name replaces the file's plugin (the two are one setting).
      if (o.key == "controller.name" && root["controller"].IsMap()) root["controller"].remove("plugin");
      ApplyOverride(root, o);
    }
    return root;
  };
  // Validated with every override applied, so overrides that belong together (backend and port) may
  // come in any order, and a file completed by them (a serial backend given its port) loads. An
  // override that cannot be applied (a bad index or value) says so itself, naming the override.
  const YAML::Node root = root_with(overrides.size());
  try {
    return LoadFromRoot(root, source_name);
  } catch (const ConfigError& full) {
    if (overrides.empty()) throw;
    // Name where the error came in: the file itself (it carries its lines) or the first override
    // after which the same error appears.
    for (size_t count = 0; count < overrides.size(); ++count) {
      const YAML::Node prefix = root_with(count);
      try {
        LoadFromRoot(prefix, source_name);
      } catch (const ConfigError& error) {
        if (std::string(error.what()) != full.what()) continue;
        if (count == 0) throw;
        throw error.WithContext(OverrideOrigin(overrides[count - 1]));
      }
    }
    const Override& last = overrides.back();
    throw full.WithContext(OverrideOrigin(last));
  }
}

ScenarioConfig LoadScenario(const std::string& path, const std::vector<Override>& overrides) {
  std::ifstream stream(path);
  if (!stream) throw ConfigError(path + ": cannot open scenario file");
  std::stringstream text;
  text << stream.rdbuf();
  return LoadScenarioFromString(text.str(), path, overrides);
}

double MaxLatencyS(const ScenarioConfig& config) {
  double latency_s = config.sensor.latency_s;
  for (const Action& action : config.script) {
    if (action.kind == ActionKind::kAddLatency) latency_s += action.latency_s;
  }
  return latency_s;
}

std::string ResolveLayoutPath(const ScenarioConfig& config) {
  return IsShippedLayout(config.sensor.layout) ? ShippedLayoutPath(config.sensor.layout)
                                               : config.sensor.layout;
}

const char* BackendName(Backend backend) {
  switch (backend) {
    case Backend::kSim:
      return "sim";
    case Backend::kSerial:
      return "serial";
    case Backend::kReplay:
      return "replay";
  }
  return "sim";
}

std::string EmitScenarioYaml(const ScenarioConfig& config) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "name" << YAML::Value << config.name;
  out << YAML::Key << "description" << YAML::Value << config.description;
  out << YAML::Key << "seed" << YAML::Value << config.seed;
  EmitNumber(out, "duration_s", config.duration_s);
  out << YAML::Key << "backend" << YAML::Value << BackendName(config.backend);
  if (config.backend == Backend::kSerial) {
    out << YAML::Key << "serial" << YAML::Value << YAML::BeginMap;
    hardware::HardwareConfigFields().Emit(config.serial, out);
    out << YAML::EndMap;
  }
  if (!config.log.empty()) out << YAML::Key << "log" << YAML::Value << config.log;
  sim::EmitSceneConfig(config.scene, out);
  EmitSensor(out, config.sensor);
  out << YAML::Key << "proprioception" << YAML::Value << YAML::BeginMap;
  sim::ProprioceptionConfigFields().Emit(config.proprioception, out);
  out << YAML::EndMap;

  out << YAML::Key << "controller" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "name" << YAML::Value << config.controller.name;
  out << YAML::Key << "params" << YAML::Value << YAML::BeginMap;
  for (const auto& [key, value] : config.controller.params) EmitNumber(out, key.c_str(), value);
  out << YAML::EndMap;
  ControllerOptionsFields().Emit(config.controller, out);
  out << YAML::EndMap;

  out << YAML::Key << "script" << YAML::Value << YAML::BeginSeq;
  for (const Action& action : config.script) EmitAction(out, action);
  out << YAML::EndSeq;

  out << YAML::Key << "expectations" << YAML::Value << YAML::BeginMap;
  ExpectationsFields().Emit(config.expectations, out);
  out << YAML::EndMap;

  out << YAML::Key << "metrics" << YAML::Value << YAML::BeginMap;
  MetricsConfigFields().Emit(config.metrics, out);
  out << YAML::EndMap;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace graspbed::testbed
