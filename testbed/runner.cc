#include "testbed/runner.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "common/plot.h"
#include "common/signal_log.h"
#include "common/yaml_map.h"
#include "controller/grasp_controller.h"
#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "sim/sim_rig.h"
#include "sim/state_log.h"
#include "testbed/oracle.h"
#include "testbed/run_outputs.h"
#include "testbed/script_player.h"

namespace graspbed::testbed {
namespace {

namespace fs = std::filesystem;

using internal::HorizontalLine;
using internal::kIncompleteMarker;
using internal::kLoopColumnCount;
using internal::Line;
using internal::MakeChart;
using internal::PerUnitFnChart;
using internal::PrepareOutputDir;
using internal::ScriptMarkers;
using common::WriteCsvAtomic;
using internal::WriteTaxelMaps;

// Simulated time between progress callbacks [s].
constexpr double kProgressPeriodS = 0.1;

/// True unit loads per control tick in a ring, to look up the truth at a frame's sample time.
class TruthRing {
 public:
  TruthRing(size_t capacity, int units, double rate_hz)
      : capacity_(capacity),
        units_(units),
        rate_hz_(rate_hz),
        times_(capacity, -1.0),
        loads_(capacity * static_cast<size_t>(units)) {}

  std::span<sensor::UnitLoad> Next(double time_s) {
    const size_t slot = count_ % capacity_;
    times_[slot] = time_s;
    ++count_;
    return {loads_.data() + slot * static_cast<size_t>(units_), static_cast<size_t>(units_)};
  }

  /// Loads recorded nearest to `time_s` (the newest when older than the ring).
  std::span<const sensor::UnitLoad> Near(double time_s) const {
    const size_t newest = (count_ - 1) % capacity_;
    // Ticks are evenly spaced: step back by the time difference, then check the neighbours.
    const double back = std::round((times_[newest] - time_s) * rate_hz_);
    size_t steps = back <= 0.0 ? 0 : static_cast<size_t>(back);
    steps = std::min({steps, count_ - 1, capacity_ - 1});
    size_t best = (newest + capacity_ - steps) % capacity_;
    for (int delta : {-1, 1}) {
      const size_t candidate_steps = static_cast<size_t>(static_cast<long>(steps) + delta);
      if (delta < 0 && steps == 0) continue;
      if (candidate_steps >= std::min(count_, capacity_)) continue;
      const size_t candidate = (newest + capacity_ - candidate_steps) % capacity_;
      if (std::abs(times_[candidate] - time_s) < std::abs(times_[best] - time_s)) best = candidate;
    }
    return {loads_.data() + best * static_cast<size_t>(units_), static_cast<size_t>(units_)};
  }

 private:
  size_t capacity_;
  int units_;
  double rate_hz_;
  size_t count_ = 0;
  std::vector<double> times_;
  std::vector<sensor::UnitLoad> loads_;
};

// Column indices of the ground-truth signals, after the loop's columns (internal::LoopColumn).
enum Col : size_t {
  kTrueSensedFn = kLoopColumnCount,
  kTrueFingerFn,
  kTrueThumbFn,
  kTrueSqueeze,
  kSlipSpeed,
  kSlidingSpeed,
  kFingerSlidingSpeed,
  kThumbSlidingSpeed,
  kSlidingShare,
  kLoadBoundGrip,
  kObjectX,
  kObjectY,
  kObjectZ,
  kObjectHeight,
  kWristX,
  kWristY,
  kWristZ,
  kWristTargetZ,
  kGripClosure,
  kObjectMass,
  kForceX,
  kForceY,
  kForceZ,
  kHolding,
  kSlipEvent,
  kSlipDistance,
  kFixedCount
};

constexpr const char* kTruthNames[static_cast<size_t>(kFixedCount) - static_cast<size_t>(kLoopColumnCount)] =
    {"true_sensed_fn_n",   "true_finger_fn_n",   "true_thumb_fn_n",     "true_squeeze_n",
     "slip_speed_mm_s",    "sliding_speed_mm_s", "finger_sliding_mm_s", "thumb_sliding_mm_s",
     "sliding_load_share", "load_bound_grip_n",  "object_x_m",          "object_y_m",
     "object_z_m",         "object_height_m",    "wrist_x_m",           "wrist_y_m",
     "wrist_z_m",          "wrist_target_z_m",   "grip_closure_m",      "object_mass_kg",
     "external_force_x_n", "external_force_y_n", "external_force_z_n",  "holding",
     "slip_event",         "slip_distance_mm"};

// Per-unit columns, in this order per unit.
constexpr const char* kUnitNames[] = {"r1_ohm",    "r2_ohm",    "fn_est_n", "ft_est_n",
                                      "fn_true_n", "ft_true_n", "validity"};
constexpr size_t kPerUnit = std::size(kUnitNames);
static_assert(kFixedCount <= kSignalBoundFixedColumns && kPerUnit <= kSignalBoundColumnsPerUnit,
              "the loader's bound on signal memory must count every column");

std::vector<std::string> NumericColumns(int units) {
  std::vector<std::string> names(internal::kLoopColumnNames, internal::kLoopColumnNames + kLoopColumnCount);
  names.insert(names.end(), std::begin(kTruthNames), std::end(kTruthNames));
  for (int u = 0; u < units; ++u) {
    for (const char* name : kUnitNames) names.push_back(std::string(name) + "_" + std::to_string(u));
  }
  return names;
}

void WritePlots(const RunResult& result, const common::SignalLog& log, const sensor::Layout& layout,
                const std::string& dir) {
  if (log.rows() < 2) return;
  const std::vector<double> time = log.ColumnValues("time_s");
  const int units = layout.unit_count();
  const std::string title = result.config.name + " (" + result.config.controller.name + ")";

  plot::Figure forces;
  forces.title = title + ": forces";
  forces.columns = 1;
  const plot::Chart per_unit = PerUnitFnChart(log, time, units);
  plot::Chart totals = MakeChart("Total normal force", "time [s]", "force [N]");
  totals.series.push_back(Line(log, time, "est_total_fn_n", "estimated (valid units)"));
  totals.series.push_back(Line(log, time, "true_sensed_fn_n", "true, on the mesas", 1.0, true));
  totals.series.push_back(Line(log, time, "true_squeeze_n", "true squeeze on the object", 1.0, true));
  totals.markers = ScriptMarkers(result);
  totals.include_zero_y = true;
  forces.panels = {per_unit, totals};
  plot::WritePng(forces, dir + "/forces.png");

  // Estimate against truth for the unit that carried the most load.
  int busiest = 0;
  double busiest_load = -1.0;
  for (int u = 0; u < units; ++u) {
    const std::vector<double> fn = log.ColumnValues("fn_true_n_" + std::to_string(u));
    const double peak = fn.empty() ? 0.0 : *std::max_element(fn.begin(), fn.end());
    if (peak > busiest_load) {
      busiest_load = peak;
      busiest = u;
    }
  }
  const std::string b = std::to_string(busiest);
  plot::Figure estimate;
  estimate.title = title + ": estimate vs truth";
  plot::Chart fn = MakeChart("Unit " + b + " (most loaded): Fn", "time [s]", "Fn [N]");
  fn.series = {Line(log, time, "fn_est_n_" + b, "estimated"),
               Line(log, time, "fn_true_n_" + b, "true", 1.0, true)};
  fn.include_zero_y = true;
  plot::Chart ft = MakeChart("Unit " + b + " (most loaded): Ft", "time [s]", "Ft [N]");
  ft.series = {Line(log, time, "ft_est_n_" + b, "estimated"),
               Line(log, time, "ft_true_n_" + b, "true", 1.0, true)};
  ft.include_zero_y = true;
  plot::Chart total = MakeChart("Sum over units: Fn", "time [s]", "Fn [N]");
  total.series = {Line(log, time, "est_total_fn_n", "estimated"),
                  Line(log, time, "true_sensed_fn_n", "true", 1.0, true)};
  total.include_zero_y = true;
  estimate.panels = {fn, ft, total};
  plot::WritePng(estimate, dir + "/estimate_vs_truth.png");

  plot::Figure grip;
  grip.title = title + ": grip";
  plot::Chart effort = MakeChart("Grip motor command", "time [s]", "effort [-]");
  effort.series = {Line(log, time, "grip_effort", "effort")};
  effort.markers = ScriptMarkers(result);
  effort.include_zero_y = true;
  plot::Chart force = MakeChart("Grip force", "time [s]", "force [N]");
  force.series = {Line(log, time, "grip_target_n", "controller target"),
                  Line(log, time, "est_total_fn_n", "estimated"),
                  Line(log, time, "true_squeeze_n", "true squeeze", 1.0, true),
                  Line(log, time, "load_bound_grip_n", "load / 2 mu (truth)", 1.0, true)};
  if (result.metrics.oracle && result.metrics.oracle->grip_n) {
    force.series.push_back(
        HorizontalLine("oracle grip (lightest that holds)", time.front(), time.back(), *result.metrics.oracle->grip_n));
  }
  if (result.config.scene.object.crush_limit_n > 0.0) {
    force.series.push_back(
        HorizontalLine("crush limit", time.front(), time.back(), result.config.scene.object.crush_limit_n));
  }
  force.include_zero_y = true;
  grip.panels = {effort, force};
  plot::WritePng(grip, dir + "/grip.png");

  plot::Figure slip;
  slip.title = title + ": slip";
  plot::Chart speed = MakeChart("Relative speed object / fingertips (truth)", "time [s]", "speed [mm/s]");
  speed.series = {Line(log, time, "slip_speed_mm_s", "fastest contact point"),
                  Line(log, time, "sliding_speed_mm_s", "sliding (at the friction limit)")};
  speed.series.push_back(HorizontalLine("slip threshold", time.front(), time.back(),
                                        result.config.metrics.slip_speed_m_s * 1e3));
  for (const SlipEvent& event : result.metrics.events) speed.markers.push_back({event.onset_s, "slip"});
  speed.include_zero_y = true;
  plot::Chart flags = MakeChart("Slip: truth events and controller flags", "time [s]", "flag [-]");
  flags.series = {Line(log, time, "slip_event", "true slip event"),
                  Line(log, time, "slip_flag", "controller slip flag", 1.0, true)};
  plot::Chart distance = MakeChart("Accumulated slip distance", "time [s]", "slip [mm]");
  distance.series = {Line(log, time, "slip_distance_mm", "slip distance")};
  distance.include_zero_y = true;
  slip.panels = {speed, flags, distance};
  plot::WritePng(slip, dir + "/slip.png");

  plot::Figure height;
  height.title = title + ": height";
  plot::Chart z = MakeChart("Object and wrist height", "time [s]", "height [mm]");
  z.series = {Line(log, time, "object_height_m", "object above table", 1e3),
              Line(log, time, "wrist_z_m", "wrist z", 1e3, true)};
  z.markers = ScriptMarkers(result);
  height.panels = {z};
  plot::WritePng(height, dir + "/height.png");

  WriteTaxelMaps(result, log, layout, time, title, dir);
}

}  // namespace

sim::SimRigConfig RigConfigFor(const ScenarioConfig& config) {
  sim::SimRigConfig rig;
  rig.scene = config.scene;
  rig.backend.sample_rate_hz = config.sensor.sample_rate_hz;
  rig.backend.latency_s = config.sensor.latency_s;
  rig.backend.max_latency_s = MaxLatencyS(config);
  rig.backend.drop_probability = config.sensor.drop_probability;
  rig.backend.strain_model = config.sensor.strain_model;
  rig.loop.stale_timeout_s = config.controller.stale_timeout_s;
  rig.loop.readout = config.sensor.readout;
  rig.loop.inversion = config.sensor.inversion;
  rig.control_rate_hz = config.controller.rate_hz;
  rig.seed = config.seed;
  return rig;
}

RunResult RunScenario(const ScenarioConfig& config, const RunOptions& options) {
  if (config.backend != Backend::kSim) return internal::RunOnBench(config, options);
  auto wall_start = std::chrono::steady_clock::now();
  RunResult result;
  result.config = config;
  result.out_dir = options.out_dir;

  const sensor::Layout layout = sensor::LoadLayout(ResolveLayoutPath(config));
  const int units = layout.unit_count();
  const sim::SimRigConfig rig_config = RigConfigFor(config);
  rig_config.Validate();
  // The oracle first: its runs are scenarios of their own, and the run below is scored against it.
  std::optional<OracleGrip> oracle;
  if (options.oracle == OracleMode::kAlways ||
      (options.oracle == OracleMode::kIfExpected && config.expectations.max_grip_efficiency)) {
    OracleOptions oracle_options;
    oracle_options.stop = options.stop;
    const OracleSearch search = FindOracleGrip(config, oracle_options);
    oracle = search.completed ? search.grip : OracleGrip{std::nullopt, "the oracle search was interrupted"};
    wall_start = std::chrono::steady_clock::now();  // the run's own time, not its oracle's
  }

  // The rig first: a scene it refuses (bodies that start inside each other) or a controller whose
  // diagnostic channels cannot be columns leaves no output behind.
  std::unique_ptr<sim::SimRig> rig;
  std::vector<std::string> diagnostic_columns;
  try {
    // The host inverts with the sensor's nominal constants, not with anything the simulation
    // knows per unit (spread, drift): those show up as estimation error, as on hardware.
    rig = std::make_unique<sim::SimRig>(
        layout, sensor::NominalCalibration(config.sensor.strain_model.nominal, units), rig_config,
        options.make_controller
            ? options.make_controller(config.controller)
            : controller::MakeController(config.controller.name, config.controller.params));
    diagnostic_columns = internal::DiagnosticColumns(rig->controller());
  } catch (const std::invalid_argument& error) {
    throw common::ConfigError((config.source_file.empty() ? "" : config.source_file + ": ") + error.what());
  }
  if (!options.out_dir.empty()) {
    PrepareOutputDir(options.out_dir);
    common::WriteFileAtomic(options.out_dir + "/config.yaml", EmitScenarioYaml(config));
  }
  ScriptPlayer player(config);
  player.Start(*rig);
  MetricsTracker tracker(config.metrics, config.scene.object.crush_limit_n,
                         config.sensor.inversion.contact_threshold_n);
  rig->simulation().set_sliding_friction_fraction(config.metrics.sliding_friction_fraction);

  // Everything the loop writes is allocated here.
  // The loop ticks at most once per physics step (the loader bounds this storage, kMaxSignalBytes).
  const double ticks_per_s = std::min(config.controller.rate_hz, 1.0 / config.scene.physics.timestep_s);
  const size_t capacity_rows = static_cast<size_t>(std::ceil(config.duration_s * ticks_per_s)) + 16;
  std::vector<std::string> columns = NumericColumns(units);
  const size_t diagnostics_first = columns.size();
  columns.insert(columns.end(), diagnostic_columns.begin(), diagnostic_columns.end());
  common::SignalLog log(std::move(columns), {"intent", "phase", "slip_cues"}, capacity_rows);
  const size_t ring_capacity =
      static_cast<size_t>(std::ceil((MaxLatencyS(config) + config.controller.stale_timeout_s + 0.05) *
                                    config.controller.rate_hz)) +
      8;
  TruthRing truth_ring(ring_capacity, units, config.controller.rate_hz);
  sim::StateRecorder states(rig->simulation(), options.out_dir.empty() ? 0.0 : config.duration_s);
  size_t next_frame = 0;

  double next_progress_s = 0.0;
  size_t next_instant = 0;
  bool stopped = false;
  // The simulated-time loop: no allocation, no I/O (the progress callback excepted, 10 Hz).
  while (rig->time_s() < config.duration_s - 1e-9) {
    if (options.stop != nullptr && options.stop->load(std::memory_order_relaxed)) {
      stopped = true;
      break;
    }
    player.Update(rig->time_s(), *rig);
    if (options.before_step) options.before_step(*rig);
    const bool ticked = rig->Step();
    // A physics fault ends the run at once; the state MuJoCo reset to is not recorded.
    if (rig->simulation().fault().occurred) break;
    if (!ticked) continue;

    const double t = rig->time_s();
    sim::Simulation& simulation = rig->simulation();
    const std::span<sensor::UnitLoad> tick_loads = truth_ring.Next(t);
    // When the backend sampled this physics state it computed its loads: no second pass over the
    // contacts. (Between physics steps, t is ahead of the state, which holds, as the sensor's does.)
    if (rig->backend().last_loads_time_s() == simulation.time_s()) {
      std::ranges::copy(rig->backend().last_loads(), tick_loads.begin());
    } else {
      simulation.ComputeUnitLoads(tick_loads);
    }
    const sim::GroundTruth truth = simulation.truth();
    const sensor::TactileState& state = rig->loop().state();
    const std::span<const sensor::UnitLoad> true_loads = truth_ring.Near(state.time_s);
    const controller::ControllerTelemetry telemetry = rig->controller().telemetry();

    TickSample sample;
    sample.time_s = t;
    sample.intent = player.intent();
    sample.truth = &truth;
    sample.state = &state;
    sample.true_loads = true_loads;
    sample.controller_slip = telemetry.slip_detected;
    sample.controller_cues = telemetry.slip_cues;
    tracker.Update(sample);
    player.Observe(t, state, telemetry.slip_detected);

    const char** text = nullptr;
    double* row = log.AppendRow(&text);
    if (row != nullptr) {
      text[0] = controller::ToString(player.intent());
      text[1] = telemetry.phase;
      text[2] = telemetry.slip_cues;
      internal::WriteLoopCells(row, t, rig->loop(), telemetry);
      internal::WriteDiagnosticCells(row, diagnostics_first, diagnostic_columns.size(), rig->controller());
      double sensed = 0.0;
      for (const sensor::UnitLoad& load : true_loads) sensed += load.fn_n;
      row[kTrueSensedFn] = sensed;
      row[kTrueFingerFn] = truth.finger_normal_force_n;
      row[kTrueThumbFn] = truth.thumb_normal_force_n;
      row[kTrueSqueeze] = truth.object_squeeze_n;
      row[kSlipSpeed] = truth.slip_speed_m_s * 1e3;
      row[kSlidingSpeed] = truth.sliding_speed_m_s * 1e3;
      row[kFingerSlidingSpeed] = truth.finger_sliding_speed_m_s * 1e3;
      row[kThumbSlidingSpeed] = truth.thumb_sliding_speed_m_s * 1e3;
      row[kSlidingShare] = truth.sliding_load_share;
      row[kLoadBoundGrip] = truth.load_bound_grip_n;
      row[kObjectX] = truth.object_position_m[0];
      row[kObjectY] = truth.object_position_m[1];
      row[kObjectZ] = truth.object_position_m[2];
      row[kObjectHeight] = truth.object_height_above_table_m;
      row[kWristX] = truth.wrist_position_m[0];
      row[kWristY] = truth.wrist_position_m[1];
      row[kWristZ] = truth.wrist_position_m[2];
      row[kWristTargetZ] = simulation.wrist_target()[2];
      row[kGripClosure] = truth.grip_closure_m;
      row[kObjectMass] = simulation.object_mass_kg();
      row[kForceX] = player.external_force_n()[0];
      row[kForceY] = player.external_force_n()[1];
      row[kForceZ] = player.external_force_n()[2];
      row[kHolding] = tracker.holding() ? 1.0 : 0.0;
      row[kSlipEvent] = tracker.in_slip_event() ? 1.0 : 0.0;
      row[kSlipDistance] = tracker.slip_distance_m() * 1e3;
      const sensor::RawFrame& frame = rig->loop().frame();
      for (int u = 0; u < units; ++u) {
        double* cell = row + kFixedCount + static_cast<size_t>(u) * kPerUnit;
        cell[0] = frame.r1_ohm[u];
        cell[1] = frame.r2_ohm[u];
        cell[2] = state.fn_n[u];
        cell[3] = state.ft_n[u];
        cell[4] = true_loads[u].fn_n;
        cell[5] = true_loads[u].ft_n;
        cell[6] = static_cast<double>(state.validity[u]);
      }
    }
    if (options.progress && t >= next_progress_s) {
      options.progress(t, config.duration_s);
      next_progress_s = t + kProgressPeriodS;
    }
    if (!options.out_dir.empty()) states.Record(simulation.time_s(), simulation);
    if (options.on_frame && options.frame_period_s > 0.0 &&
        t >= static_cast<double>(next_frame) * options.frame_period_s - 1e-9) {
      options.on_frame({t, static_cast<double>(next_frame) * options.frame_period_s, *rig, player});
      // One frame per tick: a period shorter than the control period repeats no tick.
      while (static_cast<double>(next_frame) * options.frame_period_s <= t + 1e-9) ++next_frame;
    }
    // Same slack as the rig's control clock, so an instant on a tick is served at that tick.
    while (next_instant < options.instants_s.size() && t >= options.instants_s[next_instant] - 1e-9) {
      if (options.at_instant) options.at_instant(options.instants_s[next_instant], *rig);
      ++next_instant;
    }
    if (options.stop_after_instants && next_instant == options.instants_s.size()) {
      stopped = true;
      break;
    }
  }
  const double sim_s = rig->time_s();
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  result.completed = !stopped;
  result.metrics = tracker.Finish(sim_s, wall_s, player.first_close_time_s());
  if (oracle) ApplyOracle(*oracle, result.metrics);
  const sim::PhysicsFault& fault = rig->simulation().fault();
  result.metrics.physics_fault = fault.occurred;
  result.metrics.physics_fault_cause = fault.occurred ? fault.cause_text() : "";
  result.metrics.physics_fault_time_s = fault.time_s;
  result.outcomes = EvaluateExpectations(config.expectations, result.metrics);
  // An event action that never ran fails the run like an expectation.
  for (ExpectationOutcome& outcome : player.EventOutcomes(sim_s))
    result.outcomes.push_back(std::move(outcome));
  result.script_timings = player.timings();
  result.passed = result.completed && std::all_of(result.outcomes.begin(), result.outcomes.end(),
                                                  [](const ExpectationOutcome& o) { return o.passed; });
  result.real_time_factor = wall_s > 0.0 ? sim_s / wall_s : 0.0;
  const sensor::BackendCounters counters = rig->backend().counters();
  result.frames = counters.frames;
  result.dropped_frames = counters.dropped;
  result.stale_ticks = rig->loop().counters().stale_ticks;
  result.control_ticks = rig->loop().counters().ticks;
  result.signal_rows_lost = log.lost_rows();
  if (options.on_signals) options.on_signals(log);

  if (options.on_finished) options.on_finished(result);
  if (!options.out_dir.empty()) {
    common::WriteCsvAtomic(log, options.out_dir + "/signals.csv");
    states.WriteCsv(options.out_dir + "/states.csv");
    if (options.write_plots) WritePlots(result, log, layout, options.out_dir);
    common::WriteFileAtomic(options.out_dir + "/summary.json", SummaryJson(result).dump(2) + "\n");
    if (result.completed) fs::remove(fs::path(options.out_dir) / kIncompleteMarker);
  }
  return result;
}

nlohmann::json SummaryJson(const RunResult& result) {
  const Metrics& m = result.metrics;
  if (result.config.backend != Backend::kSim) {
    // No ground truth: the bench's own record instead of the simulation's metrics.
    nlohmann::json expectations = nlohmann::json::array();
    for (const ExpectationOutcome& o : result.outcomes) {
      expectations.push_back({{"name", o.name}, {"limit", o.limit}, {"scored", false}, {"note", o.note}});
    }
    nlohmann::json script = nlohmann::json::array();
    for (size_t i = 0; i < result.config.script.size(); ++i) {
      const Action& action = result.config.script[i];
      const double fired_s = i < result.script_timings.size() ? result.script_timings[i].fired_s : -1.0;
      script.push_back({{"action", ActionName(action.kind)},
                        {"line", action.line},
                        {"at_s", action.at_s},
                        {"fired_s", fired_s >= 0.0 ? nlohmann::json(fired_s) : nlohmann::json(nullptr)}});
    }
    return {{"scenario", result.config.name},
            {"source_file", result.config.source_file},
            {"controller", result.config.controller.name},
            {"backend", BackendName(result.config.backend)},
            {"completed", result.completed},
            {"passed", result.passed},
            {"duration_s", m.sim_s},
            {"wall_s", m.wall_s},
            {"bench", result.bench},
            {"expectations", expectations},
            {"script", script},
            {"counters",
             {{"control_ticks", result.control_ticks},
              {"frames", result.frames},
              {"stale_ticks", result.stale_ticks},
              {"signal_rows_lost", result.signal_rows_lost}}}};
  }
  nlohmann::json metrics = {
      {"dropped", m.dropped},
      {"ungrasped_closes", m.ungrasped_closes},
      {"max_slip_mm", m.max_slip_mm},
      {"partial_slip_mm", m.partial_slip_mm},
      {"peak_grip_n", m.peak_grip_n},
      {"mean_held_grip_n", m.mean_held_grip_n},
      {"peak_load_bound_grip_n", m.peak_load_bound_grip_n},
      {"oracle_grip_n", m.oracle ? internal::OptionalJson(m.oracle->grip_n) : nlohmann::json(nullptr)},
      {"oracle_note", !m.oracle                 ? nlohmann::json("not computed (run --oracle)")
                      : m.oracle->grip_n        ? nlohmann::json(nullptr)
                                                : nlohmann::json(m.oracle->reason)},
      {"grip_efficiency", internal::OptionalJson(m.grip_efficiency)},
      {"peak_grip_ratio", internal::OptionalJson(m.peak_grip_ratio)},
      {"crushed", m.crushed},
      {"slip_detect_latency_ms", internal::OptionalJson(m.slip_detect_latency_ms)},
      {"false_slip_per_min", m.false_slip_per_min},
      {"false_slip_flag_s", m.false_slip_flag_s},
      {"false_slip_flag_pct", m.false_slip_flag_pct},
      {"fn_rmse_n", internal::OptionalJson(m.fn_rmse_n)},
      {"ft_rmse_n", internal::OptionalJson(m.ft_rmse_n)},
      {"time_to_stable_s", internal::OptionalJson(m.time_to_stable_s)},
      {"sim_s", m.sim_s},
      {"wall_s", m.wall_s},
      {"grasped", m.grasped},
      {"grasp_time_s", m.grasp_time_s >= 0.0 ? nlohmann::json(m.grasp_time_s) : nlohmann::json(nullptr)},
      {"drop_time_s", m.drop_time_s >= 0.0 ? nlohmann::json(m.drop_time_s) : nlohmann::json(nullptr)},
      {"held_s", m.held_s},
      {"slip_events", m.slip_events},
      {"missed_slip_events", m.missed_slip_events},
      {"gross_slip_events", m.gross.events},
      {"gross_slip_detected", m.gross.detected},
      {"gross_detect_latency_ms", internal::OptionalJson(m.gross.worst_latency_ms)},
      {"micro_slip_events", m.micro.events},
      {"micro_slip_detected", m.micro.detected},
      {"micro_detect_latency_ms", internal::OptionalJson(m.micro.worst_latency_ms)},
      {"missed_unsensed_slip_events", m.missed_unsensed_slip_events},
      {"missed_thumb_only_slip_events", m.missed_thumb_only_slip_events},
      {"controller_slip_flags", m.controller_slip_flags},
      {"false_slip_flags", m.false_slip_flags},
      {"false_slip_flags_by_cue", m.false_slip_flags_by_cue},
      {"incipient_slip_flags", m.incipient_slip_flags},
      {"estimation_samples", m.estimation_samples},
      {"physics_fault", m.physics_fault},
  };
  nlohmann::json expectations = nlohmann::json::array();
  for (const ExpectationOutcome& o : result.outcomes) {
    expectations.push_back({{"name", o.name},
                            {"limit", o.limit},
                            {"value", internal::OptionalJson(o.value)},
                            {"value_text", o.value_text},
                            {"passed", o.passed},
                            {"note", o.note}});
  }
  nlohmann::json events = nlohmann::json::array();
  for (const SlipEvent& e : m.events) {
    events.push_back(
        {{"onset_s", e.onset_s},
         {"end_s", e.end_s},
         {"peak_speed_mm_s", e.peak_speed_m_s * 1e3},
         {"distance_mm", e.distance_m * 1e3},
         {"gross", e.gross},
         {"ends_in_drop", e.ends_in_drop},
         {"detected", e.detected},
         {"sensed", e.sensed},
         {"finger_slid", e.finger_slid},
         {"thumb_slid", e.thumb_slid},
         {"latency_ms", e.detected ? nlohmann::json(e.latency_s * 1e3) : nlohmann::json(nullptr)}});
  }
  // When each script action fired; for event actions also when it was armed and saw its event.
  const auto time_or_null = [](double time_s) {
    return time_s >= 0.0 ? nlohmann::json(time_s) : nlohmann::json(nullptr);
  };
  nlohmann::json script = nlohmann::json::array();
  for (size_t i = 0; i < result.config.script.size(); ++i) {
    const Action& action = result.config.script[i];
    const ActionTiming timing = i < result.script_timings.size() ? result.script_timings[i] : ActionTiming{};
    nlohmann::json entry = {{"action", ActionName(action.kind)}, {"line", action.line}};
    if (action.after == ScriptEvent::kNone) {
      entry["at_s"] = action.at_s;
    } else {
      entry["after"] = EventName(action.after);
      entry["delay_s"] = action.delay_s;
      entry["timeout_s"] = action.timeout_s;
      entry["armed_s"] = time_or_null(timing.armed_s);
      entry["event_s"] = time_or_null(timing.event_s);
      entry["timed_out"] = timing.timed_out_s >= 0.0;
    }
    entry["fired_s"] = time_or_null(timing.fired_s);
    script.push_back(entry);
  }
  return {
      {"scenario", result.config.name},
      {"source_file", result.config.source_file},
      {"controller", result.config.controller.name},
      {"seed", result.config.seed},
      {"completed", result.completed},
      {"passed", result.passed},
      {"metrics", metrics},
      {"expectations", expectations},
      {"slip_events", events},
      {"script", script},
      {"physics_fault",
       {{"occurred", m.physics_fault}, {"cause", m.physics_fault_cause}, {"time_s", m.physics_fault_time_s}}},
      {"counters",
       {{"control_ticks", result.control_ticks},
        {"frames", result.frames},
        {"dropped_frames", result.dropped_frames},
        {"stale_ticks", result.stale_ticks},
        {"signal_rows_lost", result.signal_rows_lost}}},
      {"real_time_factor", result.real_time_factor},
  };
}

std::string SummaryTable(const RunResult& result) {
  const Metrics& m = result.metrics;
  std::ostringstream out;
  char line[256];
  if (result.config.backend != Backend::kSim) return internal::BenchSummaryTable(result);
  const auto optional_text = [](const std::optional<double>& v, const char* format) {
    if (!v) return std::string("none");
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), format, *v);
    return std::string(buffer);
  };
  std::snprintf(line, sizeof(line), "scenario %s, controller %s, seed %llu: %s\n", result.config.name.c_str(),
                result.config.controller.name.c_str(), static_cast<unsigned long long>(result.config.seed),
                !result.completed ? "INTERRUPTED"
                : result.passed   ? "PASSED"
                                  : "FAILED");
  out << line;
  std::snprintf(line, sizeof(line), "  grasped %s  dropped %s  slip %.2f mm  peak grip %.2f N  crushed %s\n",
                m.grasped ? "yes" : "no", m.dropped ? "yes" : "no", m.max_slip_mm, m.peak_grip_n,
                m.crushed ? "yes" : "no");
  out << line;
  out << "  grip: mean held " << optional_text(m.mean_held_grip_n, "%.2f N") << ", oracle "
      << (!m.oracle          ? std::string("not computed (run --oracle)")
          : m.oracle->grip_n ? optional_text(m.oracle->grip_n, "%.2f N")
                             : "none: " + m.oracle->reason)
      << ", efficiency " << optional_text(m.grip_efficiency, "%.2f") << ", peak/oracle "
      << optional_text(m.peak_grip_ratio, "%.2f") << "\n";
  std::snprintf(line, sizeof(line),
                "  gross slips %d (missed %d, latency %s), micro-slips %d (missed %d), false slip %.2f/min, "
                "stable after %s\n",
                m.gross.events, m.gross.events - m.gross.detected,
                optional_text(m.gross.worst_latency_ms, "%.1f ms").c_str(), m.micro.events,
                m.micro.events - m.micro.detected, m.false_slip_per_min,
                optional_text(m.time_to_stable_s, "%.3f s").c_str());
  out << line;
  // %g, not %f: an ideal sensor inverts exactly (RMSE ~1e-15 N), and 0.000 would hide whether the
  // error is rounding or a few tenths of a millinewton.
  std::snprintf(line, sizeof(line),
                "  Fn RMSE %s, Ft RMSE %s; %.2f s simulated in %.2f s (%.1fx real time)\n",
                optional_text(m.fn_rmse_n, "%.3g N").c_str(), optional_text(m.ft_rmse_n, "%.3g N").c_str(),
                m.sim_s, m.wall_s, result.real_time_factor);
  out << line;
  if (m.physics_fault) {
    std::snprintf(line, sizeof(line), "  PHYSICS FAULT at t = %.6g s, the run ended there: %s\n",
                  m.physics_fault_time_s, m.physics_fault_cause.c_str());
    out << line;
  }
  for (const ExpectationOutcome& o : result.outcomes) {
    std::snprintf(line, sizeof(line), "  [%s] %-24s %-14s got %s%s%s\n", o.passed ? "pass" : "FAIL",
                  o.name.c_str(), o.limit.c_str(), o.value_text.c_str(), o.note.empty() ? "" : " -- ",
                  o.note.c_str());
    out << line;
  }
  return out.str();
}

}  // namespace graspbed::testbed
