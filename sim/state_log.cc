#include "sim/state_log.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>


namespace graspbed::sim {
namespace {

std::vector<std::string> StateColumns(int nq, int nv, int nu) {
  std::vector<std::string> names{"time_s"};
  for (int i = 0; i < nq; ++i) names.push_back("qpos_" + std::to_string(i));
  for (int i = 0; i < nv; ++i) names.push_back("qvel_" + std::to_string(i));
  for (int i = 0; i < nu; ++i) names.push_back("ctrl_" + std::to_string(i));
  return names;
}

// Slack on the recording clock, as on the rig's control clock [s].
constexpr double kClockSlackS = 1e-9;

}  // namespace

StateRecorder::StateRecorder(const Simulation& simulation, double duration_s)
    : nq_(simulation.model()->nq),
      nv_(simulation.model()->nv),
      nu_(simulation.model()->nu),
      log_(StateColumns(nq_, nv_, nu_), {},
           duration_s > 0.0 ? static_cast<size_t>(std::ceil(duration_s / kPeriodS)) + 4 : 0) {}

void StateRecorder::Record(double time_s, const Simulation& simulation) {
  if (time_s < next_s_ - kClockSlackS) return;
  next_s_ = (std::floor(time_s / kPeriodS + kClockSlackS) + 1.0) * kPeriodS;
  const char** no_text = nullptr;
  double* row = log_.AppendRow(&no_text);
  if (row == nullptr) return;
  const mjData* d = simulation.data();
  row[0] = time_s;
  std::copy_n(d->qpos, nq_, row + 1);
  std::copy_n(d->qvel, nv_, row + 1 + nq_);
  std::copy_n(d->ctrl, nu_, row + 1 + nq_ + nv_);
}

void StateRecorder::WriteCsv(const std::string& path) const { common::WriteCsvAtomic(log_, path); }

size_t StateLog::RowAt(double time) const {
  const auto after = std::upper_bound(time_s.begin(), time_s.end(), time + kClockSlackS);
  return after == time_s.begin() ? 0 : static_cast<size_t>(after - time_s.begin() - 1);
}

StateLog LoadStateLog(const std::string& path, const Simulation& simulation) {
  return LoadStateLog(path, simulation.model()->nq, simulation.model()->nv, simulation.model()->nu);
}

void ShowStateRow(const StateLog& log, size_t row, Simulation& simulation) {
  mjModel* m = simulation.mutable_model();
  mjData* d = simulation.mutable_data();
  const std::vector<double>& values = log.rows.at(row);
  std::copy_n(values.data(), m->nq, d->qpos);
  std::copy_n(values.data() + m->nq, m->nv, d->qvel);
  std::copy_n(values.data() + m->nq + m->nv, m->nu, d->ctrl);
  d->time = log.time_s[row];
  mj_forward(m, d);
}

StateLog LoadStateLog(const std::string& path, int nq, int nv, int nu) {
  std::ifstream file(path);
  if (!file) {
    throw std::invalid_argument(path +
                                ": cannot read (a run directory from graspbed run has states.csv since "
                                "the viewer's replay was added; run the scenario again)");
  }
  const std::vector<std::string> expected = StateColumns(nq, nv, nu);
  std::string line;
  std::getline(file, line);
  {
    std::stringstream header(line);
    size_t column = 0;
    for (std::string name; std::getline(header, name, ',');) {
      if (column >= expected.size() || name != expected[column]) {
        throw std::invalid_argument(path + ":1: column " + std::to_string(column + 1) + " is '" + name +
                                    "', expected '" +
                                    (column < expected.size() ? expected[column] : "(none)") +
                                    "': not a state log of this model (nq " + std::to_string(nq) + ", nv " +
                                    std::to_string(nv) + ", nu " + std::to_string(nu) + ")");
      }
      ++column;
    }
    if (column != expected.size()) {
      throw std::invalid_argument(path + ":1: " + std::to_string(column) + " columns, expected " +
                                  std::to_string(expected.size()) + ": not a state log of this model");
    }
  }
  StateLog log;
  log.nq = nq;
  log.nv = nv;
  log.nu = nu;
  int line_number = 1;
  while (std::getline(file, line)) {
    ++line_number;
    if (line.empty()) continue;
    std::vector<double> values;
    values.reserve(expected.size());
    const char* p = line.c_str();
    while (*p != '\0') {
      char* end = nullptr;
      const double value = std::strtod(p, &end);
      if (end == p || (*end != ',' && *end != '\0')) {
        throw std::invalid_argument(path + ":" + std::to_string(line_number) + ": column " +
                                    std::to_string(values.size() + 1) + ": not a number");
      }
      values.push_back(value);
      p = *end == ',' ? end + 1 : end;
    }
    if (values.size() != expected.size()) {
      throw std::invalid_argument(path + ":" + std::to_string(line_number) + ": " +
                                  std::to_string(values.size()) + " values, expected " +
                                  std::to_string(expected.size()));
    }
    if (!log.time_s.empty() && !(values[0] > log.time_s.back())) {
      throw std::invalid_argument(path + ":" + std::to_string(line_number) + ": time_s " +
                                  std::to_string(values[0]) + " does not follow " +
                                  std::to_string(log.time_s.back()));
    }
    log.time_s.push_back(values[0]);
    log.rows.emplace_back(values.begin() + 1, values.end());
  }
  if (log.rows.empty()) throw std::invalid_argument(path + ": no state rows");
  return log;
}

}  // namespace graspbed::sim
