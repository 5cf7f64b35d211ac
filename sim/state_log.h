#pragma once
/// The simulation state of a run over time (states.csv beside signals.csv): MuJoCo's qpos, qvel and
/// ctrl every StateRecorder::kPeriodS of simulated time, so a finished run can be shown again (the
/// viewer's replay) without simulating it: set the state, run mj_forward, draw.

#include <string>
#include <vector>

#include "common/signal_log.h"
#include "sim/simulation.h"

namespace graspbed::sim {

/// Records the state of one simulation in storage reserved up front (Record() allocates nothing).
class StateRecorder {
 public:
  /// State rows per second of simulated time: 200 Hz, enough for 60 fps replays and a fine scrub, a
  /// fifth of the control ticks.
  static constexpr double kPeriodS = 0.005;

  /// Reserves rows for `duration_s` [s] (0: records nothing) of `simulation`'s state.
  StateRecorder(const Simulation& simulation, double duration_s);
  /// At a control tick at `time_s` [s]: keeps a row when a period has passed since the last one.
  void Record(double time_s, const Simulation& simulation);
  /// Writes states.csv (time_s, qpos_<i>, qvel_<i>, ctrl_<i>) atomically. Throws std::runtime_error.
  void WriteCsv(const std::string& path) const;

 private:
  int nq_ = 0;
  int nv_ = 0;
  int nu_ = 0;
  common::SignalLog log_;
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

/// Reads `path`. Throws std::invalid_argument naming the file, line and column when it is missing,
/// malformed, or its columns do not match `nq`, `nv`, `nu` (a states.csv of another model).
StateLog LoadStateLog(const std::string& path, int nq, int nv, int nu);

/// Reads `path` as a state log of `simulation`'s model (LoadStateLog with its nq, nv, nu).
StateLog LoadStateLog(const std::string& path, const Simulation& simulation);

/// Puts `simulation` in the state of `log`'s row `row` (time, qpos, qvel, ctrl) and computes what
/// follows from it (positions, contacts) without stepping: a replay shows the recorded instant.
void ShowStateRow(const StateLog& log, size_t row, Simulation& simulation);

}  // namespace graspbed::sim
