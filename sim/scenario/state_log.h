#pragma once
/// The simulation state of a run over time (states.csv beside signals.csv): MuJoCo's qpos, qvel and
/// ctrl every StateRecorder::kPeriodS of simulated time, so a finished run can be shown again (the
/// viewer's replay) without simulating it: set the state, run mj_forward, draw.

#include <string>
#include <vector>

#include "sim/scenario/signal_log.h"
#include "sim/simulation.h"

namespace graspbed::scenario {

/// Records the state of one simulation in storage reserved up front (Record() allocates nothing).
class StateRecorder {
 public:
  /// State rows per second of simulated time: 200 Hz, enough for 60 fps replays and a fine scrub, a
  /// fifth of the control ticks.
  static constexpr double kPeriodS = 0.005;

  /// Reserves rows for `duration_s` [s] (0: records nothing) of `simulation`'s state.
  StateRecorder(const sim::Simulation& simulation, double duration_s);
  /// At a control tick at `time_s` [s]: keeps a row when a period has passed since the last one.
  void Record(double time_s, const sim::Simulation& simulation);
  /// Writes states.csv (time_s, qpos_<i>, qvel_<i>, ctrl_<i>) atomically. Throws std::runtime_error.
  void WriteCsv(const std::string& path) const;

 private:
  int nq_ = 0;
  int nv_ = 0;
  int nu_ = 0;
  SignalLog log_;
  double next_s_ = 0.0;
};

/// states.csv read back: one row per recorded instant.
struct StateLog {
  int nq = 0;
  int nv = 0;
  int nu = 0;
  std::vector<double> time_s;  ///< ascending [s]
  /// Per row: qpos (nq), qvel (nv), ctrl (nu), in that order.
  std::vector<std::vector<double>> rows;
  /// Row at or before `time_s` [s] (the first row before the first instant).
  size_t RowAt(double time_s) const;
};

/// A CSV file with a header line, its cells as text (signals.csv for the viewer's replay).
struct CsvTable {
  std::string path;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;  ///< each as long as the header
  /// Index of column `name`. Throws std::invalid_argument naming the file and column.
  size_t Column(const std::string& name) const;
  /// Cell (row, column) as a number; NaN when it is not one.
  double Number(size_t row, size_t column) const;
};

/// Reads `path`. Throws std::invalid_argument naming the file (and line) when it is missing, empty or
/// has a row of another length than the header.
CsvTable ReadCsvTable(const std::string& path);

/// Reads `path`. Throws std::invalid_argument naming the file, line and column when it is missing,
/// malformed, or its columns do not match `nq`, `nv`, `nu` (a states.csv of another model).
StateLog LoadStateLog(const std::string& path, int nq, int nv, int nu);

}  // namespace graspbed::scenario
