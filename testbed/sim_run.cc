// The simulation as a run backend (run_backend.h): the rig (simulation, simulated sensor, control
// loop, controller, actuator) stepped between control ticks, the script played on it, and the ground
// truth the other backends lack: metrics and expectations, the truth columns of signals.csv, the
// oracle grip, states.csv and the plots of estimate against truth.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/config_error.h"
#include "common/plot.h"
#include "common/signal_log.h"
#include "controller/grasp_controller.h"
#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "sim/sim_rig.h"
#include "sim/state_log.h"
#include "testbed/oracle.h"
#include "testbed/run_backend.h"
#include "testbed/run_outputs.h"
#include "testbed/script_player.h"

namespace graspbed::testbed {
namespace {

using internal::HorizontalLine;
using internal::kLoopColumnCount;
using internal::Line;
using internal::MakeChart;
using internal::PerUnitFnChart;
using internal::ScriptMarkers;
using internal::WriteTaxelMaps;

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

constexpr size_t kTruthCount = internal::kGroundTruthColumnNames.size();
static_assert(kLoopColumnCount + kTruthCount <= kSignalBoundFixedColumns,
              "the loader's bound on signal memory must count every column");

// The simulation's block of signals.csv: the truth, then every unit's columns with the truth's.
std::vector<std::string> SimColumns(int units) {
  std::vector<std::string> names(internal::kGroundTruthColumnNames.begin(), internal::kGroundTruthColumnNames.end());
  const std::vector<std::string> unit_names = internal::UnitColumns(units, /*with_truth=*/true);
  names.insert(names.end(), unit_names.begin(), unit_names.end());
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
  const plot::Chart per_unit = PerUnitFnChart(log, time, layout);
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


/// RunBackend on the simulation.
class SimRun final : public internal::RunBackend {
 public:
  SimRun(const ScenarioConfig& config, const RunOptions& options)
      : config_(config),
        options_(options),
        layout_(sensor::LoadLayout(ResolveLayoutPath(config))),
        units_(layout_.unit_count()),
        player_(config),
        tracker_(config.metrics, config.scene.object.crush_limit_n, config.sensor.inversion.contact_threshold_n),
        truth_ring_(TruthRingCapacity(config), units_, config.controller.rate_hz) {
    const sim::SimRigConfig rig_config = RigConfigFor(config);
    rig_config.Validate();
    // The oracle first: its runs are scenarios of their own, and this run is scored against it.
    if (options.oracle == OracleMode::kAlways ||
        (options.oracle == OracleMode::kIfExpected && config.expectations.max_grip_efficiency)) {
      OracleOptions oracle_options;
      oracle_options.stop = options.stop;
      const OracleSearch search = FindOracleGrip(config, oracle_options);
      oracle_ = search.completed ? search.grip : OracleGrip{std::nullopt, "the oracle search was interrupted"};
    }
    // The rig refuses a scene whose bodies start inside each other before any output is written.
    // The host inverts with the sensor's nominal constants, not with anything the simulation
    // knows per unit (spread, drift): those show up as estimation error, as on hardware.
    std::unique_ptr<controller::GraspController> grasp = internal::MakeRunController(config, options);
    try {
      rig_ = std::make_unique<sim::SimRig>(
          layout_, sensor::NominalCalibration(config.sensor.strain_model.nominal, units_), rig_config,
          std::move(grasp));
    } catch (const std::invalid_argument& error) {
      throw internal::RefusedIn(config, error);
    }
    states_ = std::make_unique<sim::StateRecorder>(rig_->simulation(),
                                                   options.out_dir.empty() ? 0.0 : config.duration_s);
  }

  std::vector<std::string> Columns() const override { return SimColumns(units_); }
  size_t RowCapacity() const override {
    // The loop ticks at most once per physics step (the loader bounds this storage, kMaxSignalBytes).
    const double ticks_per_s = std::min(config_.controller.rate_hz, 1.0 / config_.scene.physics.timestep_s);
    return static_cast<size_t>(std::ceil(config_.duration_s * ticks_per_s)) + 16;
  }
  double duration_s() const override { return config_.duration_s; }
  controller::GraspController& controller() override { return rig_->controller(); }
  const controller::ControlLoop& loop() const override { return rig_->loop(); }
  controller::GraspIntent intent() const override { return player_.intent(); }
  const controller::ControllerTelemetry& telemetry() const override { return telemetry_; }

  void Start() override {
    player_.Start(*rig_);
    rig_->simulation().set_sliding_friction_fraction(config_.metrics.sliding_friction_fraction);
  }

  std::optional<double> NextTick() override {
    while (rig_->time_s() < config_.duration_s - 1e-9) {
      if (options_.stop != nullptr && options_.stop->load(std::memory_order_relaxed)) return std::nullopt;
      player_.Update(rig_->time_s(), *rig_);
      if (options_.before_step) options_.before_step(*rig_);
      const bool ticked = rig_->Step();
      // A physics fault ends the run at once; the state MuJoCo reset to is not recorded.
      if (rig_->simulation().fault().occurred) return std::nullopt;
      if (!ticked) continue;
      const double t = rig_->time_s();
      ObserveTick(t);
      return t;
    }
    return std::nullopt;
  }

  void Record(double /*time_s*/, double* cells, const char** /*texts*/) override {
    const sim::Simulation& simulation = rig_->simulation();
    double sensed = 0.0;
    for (const sensor::UnitLoad& load : true_loads_) sensed += load.fn_n;
    const double truth_cells[kTruthCount] = {
        sensed,
        truth_.finger_normal_force_n,
        truth_.thumb_normal_force_n,
        truth_.object_squeeze_n,
        truth_.finger_links_normal_force_n,
        truth_.palm_normal_force_n,
        truth_.slip_speed_m_s * 1e3,
        truth_.sliding_speed_m_s * 1e3,
        truth_.finger_sliding_speed_m_s * 1e3,
        truth_.thumb_sliding_speed_m_s * 1e3,
        truth_.sliding_load_share,
        truth_.load_bound_grip_n,
        truth_.object_position_m[0],
        truth_.object_position_m[1],
        truth_.object_position_m[2],
        truth_.object_height_above_table_m,
        truth_.wrist_position_m[0],
        truth_.wrist_position_m[1],
        truth_.wrist_position_m[2],
        simulation.wrist_target()[2],
        truth_.grip_closure_m,
        simulation.object_mass_kg(),
        player_.external_force_n()[0],
        player_.external_force_n()[1],
        player_.external_force_n()[2],
        tracker_.holding() ? 1.0 : 0.0,
        tracker_.in_slip_event() ? 1.0 : 0.0,
        tracker_.slip_distance_m() * 1e3};
    std::copy(std::begin(truth_cells), std::end(truth_cells), cells);
    internal::WriteUnitCells(cells + kTruthCount, units_, rig_->loop(), true_loads_);
  }

  bool AfterTick(double t) override {
    const sim::Simulation& simulation = rig_->simulation();
    if (!options_.out_dir.empty()) states_->Record(simulation.time_s(), simulation);
    if (options_.on_frame && options_.frame_period_s > 0.0 &&
        t >= static_cast<double>(next_frame_) * options_.frame_period_s - 1e-9) {
      options_.on_frame({t, static_cast<double>(next_frame_) * options_.frame_period_s, *rig_, player_});
      // One frame per tick: a period shorter than the control period repeats no tick.
      while (static_cast<double>(next_frame_) * options_.frame_period_s <= t + 1e-9) ++next_frame_;
    }
    // Same slack as the rig's control clock, so an instant on a tick is served at that tick.
    while (next_instant_ < options_.instants_s.size() && t >= options_.instants_s[next_instant_] - 1e-9) {
      if (options_.at_instant) options_.at_instant(options_.instants_s[next_instant_], *rig_);
      ++next_instant_;
    }
    return options_.stop_after_instants && next_instant_ == options_.instants_s.size();
  }

  void Finish(bool /*completed*/, double wall_s, RunResult& result) override {
    const double sim_s = rig_->time_s();
    result.metrics = tracker_.Finish(sim_s, wall_s, player_.first_close_time_s());
    if (oracle_) ApplyOracle(*oracle_, result.metrics);
    const sim::PhysicsFault& fault = rig_->simulation().fault();
    result.metrics.physics_fault = fault.occurred;
    result.metrics.physics_fault_cause = fault.occurred ? fault.cause_text() : "";
    result.metrics.physics_fault_time_s = fault.time_s;
    result.outcomes = EvaluateExpectations(config_.expectations, result.metrics, config_.metrics);
    // An event action that never ran fails the run like an expectation.
    for (ExpectationOutcome& outcome : player_.EventOutcomes(sim_s)) result.outcomes.push_back(std::move(outcome));
    result.script_timings = player_.timings();
    const sensor::BackendCounters counters = rig_->backend().counters();
    result.frames = counters.frames;
    result.dropped_frames = counters.dropped;
    result.stale_ticks = rig_->loop().counters().stale_ticks;
    result.control_ticks = rig_->loop().counters().ticks;
  }

  void WriteOutputs(const RunResult& result, const common::SignalLog& log, bool plots,
                    const std::string& dir) override {
    states_->WriteCsv(dir + "/states.csv");
    if (plots) WritePlots(result, log, layout_, dir);
  }

 private:
  static size_t TruthRingCapacity(const ScenarioConfig& config) {
    return static_cast<size_t>(std::ceil((MaxLatencyS(config) + config.controller.stale_timeout_s + 0.05) *
                                         config.controller.rate_hz)) +
           8;
  }

  // The tick's ground truth, scored whether or not its row is logged.
  void ObserveTick(double t) {
    sim::Simulation& simulation = rig_->simulation();
    const std::span<sensor::UnitLoad> tick_loads = truth_ring_.Next(t);
    // When the backend sampled this physics state it computed its loads: no second pass over the
    // contacts. (Between physics steps, t is ahead of the state, which holds, as the sensor's does.)
    if (rig_->backend().last_loads_time_s() == simulation.time_s()) {
      std::ranges::copy(rig_->backend().last_loads(), tick_loads.begin());
    } else {
      simulation.ComputeUnitLoads(tick_loads);
    }
    truth_ = simulation.truth();
    const sensor::TactileState& state = rig_->loop().state();
    true_loads_ = truth_ring_.Near(state.time_s);
    telemetry_ = rig_->controller().telemetry();
    TickSample sample;
    sample.time_s = t;
    sample.intent = player_.intent();
    sample.truth = &truth_;
    sample.state = &state;
    sample.true_loads = true_loads_;
    sample.controller_slip = telemetry_.slip_detected;
    sample.controller_cues = telemetry_.slip_cues;
    tracker_.Update(sample);
    player_.Observe(t, state, telemetry_.slip_detected);
  }

  const ScenarioConfig& config_;
  const RunOptions& options_;
  const sensor::Layout layout_;
  const int units_;
  std::optional<OracleGrip> oracle_;
  std::unique_ptr<sim::SimRig> rig_;
  ScriptPlayer player_;
  MetricsTracker tracker_;
  TruthRing truth_ring_;
  std::unique_ptr<sim::StateRecorder> states_;
  sim::GroundTruth truth_;
  controller::ControllerTelemetry telemetry_;
  std::span<const sensor::UnitLoad> true_loads_;
  size_t next_frame_ = 0;
  size_t next_instant_ = 0;
};

}  // namespace

sim::SimRigConfig RigConfigFor(const ScenarioConfig& config) {
  sim::SimRigConfig rig;
  rig.scene = config.scene;
  rig.backend.sample_rate_hz = config.sensor.sample_rate_hz;
  rig.backend.latency_s = config.sensor.latency_s;
  rig.backend.max_latency_s = MaxLatencyS(config);
  rig.backend.drop_probability = config.sensor.drop_probability;
  rig.backend.strain_model = config.sensor.strain_model;
  rig.proprioception = config.proprioception;
  rig.loop.stale_timeout_s = config.controller.stale_timeout_s;
  rig.loop.readout = config.sensor.readout;
  rig.loop.inversion = config.sensor.inversion;
  rig.control_rate_hz = config.controller.rate_hz;
  rig.seed = config.seed;
  return rig;
}

std::unique_ptr<internal::RunBackend> internal::MakeSimRun(const ScenarioConfig& config, const RunOptions& options) {
  return std::make_unique<SimRun>(config, options);
}

}  // namespace graspbed::testbed
