// RunScenario: the one run loop every backend shares (run_backend.h), and the summary of a run.
#include "testbed/runner.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/config_error.h"
#include "common/signal_log.h"
#include "controller/grasp_controller.h"
#include "testbed/run_backend.h"
#include "testbed/run_outputs.h"

namespace graspbed::testbed {
namespace {

namespace fs = std::filesystem;

// Simulated time between progress callbacks [s].
constexpr double kProgressPeriodS = 0.1;

std::unique_ptr<internal::RunBackend> MakeRun(const ScenarioConfig& config, const RunOptions& options) {
  switch (config.backend) {
    case Backend::kSim:
      return internal::MakeSimRun(config, options);
    case Backend::kSerial:
      return internal::MakeSerialRun(config, options);
    case Backend::kReplay:
      return internal::MakeReplayRun(config, options);
  }
  throw std::logic_error("unknown backend");
}

// The signal rows of a run: the loop's columns, the backend's block, the controller's diagnostic
// columns last; text columns intent, phase, slip_cues, then the backend's.
common::SignalLog MakeSignalLog(internal::RunBackend& run, const std::vector<std::string>& diagnostic_columns) {
  std::vector<std::string> columns(internal::kLoopColumnNames, internal::kLoopColumnNames + internal::kLoopColumnCount);
  const std::vector<std::string> backend_columns = run.Columns();
  columns.insert(columns.end(), backend_columns.begin(), backend_columns.end());
  columns.insert(columns.end(), diagnostic_columns.begin(), diagnostic_columns.end());
  std::vector<std::string> text_columns = {"intent", "phase", "slip_cues"};
  const std::vector<std::string> backend_texts = run.TextColumns();
  text_columns.insert(text_columns.end(), backend_texts.begin(), backend_texts.end());
  return common::SignalLog(std::move(columns), std::move(text_columns), run.RowCapacity());
}

// signals.csv, the backend's files and plots, then summary.json; the INCOMPLETE marker goes last.
void WriteRunOutputs(const RunResult& result, const common::SignalLog& log, internal::RunBackend& run,
                     const RunOptions& options) {
  common::WriteCsvAtomic(log, options.out_dir + "/signals.csv");
  run.WriteOutputs(result, log, options.write_plots, options.out_dir);
  common::WriteFileAtomic(options.out_dir + "/summary.json", SummaryJson(result).dump(2) + "\n");
  if (result.completed) fs::remove(fs::path(options.out_dir) / internal::kIncompleteMarker);
}

}  // namespace

common::ConfigError internal::RefusedIn(const ScenarioConfig& config, const std::exception& error) {
  return common::ConfigError((config.source_file.empty() ? "" : config.source_file + ": ") + error.what());
}

std::unique_ptr<controller::GraspController> internal::MakeRunController(const ScenarioConfig& config,
                                                                         const RunOptions& options) {
  try {
    return options.make_controller ? options.make_controller(config.controller)
                                   : controller::MakeController(config.controller.name, config.controller.params);
  } catch (const std::invalid_argument& error) {
    throw internal::RefusedIn(config, error);
  }
}

RunResult RunScenario(const ScenarioConfig& config, const RunOptions& options) {
  // The backend first, then the controller's diagnostic columns: a scene, controller, port or
  // recording refused leaves no output behind.
  const std::unique_ptr<internal::RunBackend> run = MakeRun(config, options);
  std::vector<std::string> diagnostic_columns;
  try {
    diagnostic_columns = internal::DiagnosticColumns(run->controller());
  } catch (const std::invalid_argument& error) {
    throw internal::RefusedIn(config, error);
  }
  RunResult result;
  result.config = config;
  result.out_dir = options.out_dir;
  if (!options.out_dir.empty()) {
    internal::PrepareOutputDir(options.out_dir);
    common::WriteFileAtomic(options.out_dir + "/config.yaml", EmitScenarioYaml(config));
  }

  // Everything the loop writes is allocated here.
  common::SignalLog log = MakeSignalLog(*run, diagnostic_columns);
  const size_t diagnostics_first = log.numeric_column_count() - diagnostic_columns.size();

  const auto wall_start = std::chrono::steady_clock::now();
  run->Start();
  const auto stop_requested = [&] { return options.stop != nullptr && options.stop->load(std::memory_order_relaxed); };
  bool stopped = false;
  double next_progress_s = 0.0;
  // The loop: no allocation, no I/O (the progress callback excepted, 10 Hz).
  for (;;) {
    if (stop_requested()) {
      stopped = true;
      break;
    }
    const std::optional<double> tick = run->NextTick();
    if (!tick) {
      stopped = stop_requested();
      break;
    }
    const double t = *tick;
    const char** text = nullptr;
    double* row = log.AppendRow(&text);
    if (row != nullptr) {
      const controller::ControllerTelemetry& telemetry = run->telemetry();
      text[0] = controller::ToString(run->intent());
      text[1] = telemetry.phase;
      text[2] = telemetry.slip_cues;
      internal::WriteLoopCells(row, t, run->loop(), telemetry);
      run->Record(t, row + internal::kLoopColumnCount, text + 3);
      internal::WriteDiagnosticCells(row, diagnostics_first, diagnostic_columns.size(), run->controller());
    }
    if (options.progress && t >= next_progress_s) {
      options.progress(t, run->duration_s());
      next_progress_s = t + kProgressPeriodS;
    }
    if (run->AfterTick(t)) {
      stopped = true;
      break;
    }
  }
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  result.completed = !stopped;
  run->Finish(result.completed, wall_s, result);
  result.passed = result.completed && run->Healthy() &&
                  std::all_of(result.outcomes.begin(), result.outcomes.end(),
                              [](const ExpectationOutcome& o) { return o.passed; });
  result.real_time_factor = wall_s > 0.0 ? result.metrics.sim_s / wall_s : 0.0;
  result.signal_rows_lost = log.lost_rows();
  if (options.on_signals) options.on_signals(log);
  if (options.on_finished) options.on_finished(result);
  if (!options.out_dir.empty()) WriteRunOutputs(result, log, *run, options);
  return result;
}

namespace {

// The sensor a run read, as the scorecard groups runs by it: "<profile>/<sensitivities>".
std::string SensorLabel(const ScenarioConfig& config) {
  return config.sensor.profile + "/" + config.sensor.sensitivities;
}

// summary.json of a serial or replay run: no ground truth, so the bench's own record instead of the
// simulation's metrics, and the expectations listed, not scored.
nlohmann::json BenchSummaryJson(const RunResult& result) {
  const Metrics& m = result.metrics;
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
          {"sensor", SensorLabel(result.config)},
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

// The metrics of a simulated run (summary.json "metrics").
nlohmann::json MetricsJson(const Metrics& m) {
  return {
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
      {"contact_time_s", m.contact_time_s >= 0.0 ? nlohmann::json(m.contact_time_s) : nlohmann::json(nullptr)},
      {"acquisition_shift_mm", m.acquisition_shift_mm},
      {"pushed_out", m.pushed_out},
      {"sensed_grip_share", internal::OptionalJson(m.sensed_grip_share)},
      {"unsensed_held_s", m.unsensed_held_s},
      {"contact_unit", m.contact_unit >= 0 ? nlohmann::json(m.contact_unit) : nlohmann::json(nullptr)},
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
}

// summary.json of a simulated run: metrics, scored expectations, slip events, the script's timing.
nlohmann::json SimSummaryJson(const RunResult& result) {
  const Metrics& m = result.metrics;
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
      {"sensor", SensorLabel(result.config)},
      {"seed", result.config.seed},
      {"completed", result.completed},
      {"passed", result.passed},
      {"metrics", MetricsJson(m)},
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

}  // namespace

nlohmann::json SummaryJson(const RunResult& result) {
  return result.config.backend == Backend::kSim ? SimSummaryJson(result) : BenchSummaryJson(result);
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
