// states.csv, the state log a replay draws from: 200 Hz rows of qpos, qvel, ctrl; a logged state put
// back into the model (mj_forward) puts the object where signals.csv says it was at that tick; files of
// another model or malformed rows are refused naming file, line and column.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <fstream>
#include <string>

#include "sensor/layout.h"
#include "sim/simulation.h"
#include "sim/state_log.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::testbed {
namespace {

using test_support::SourcePath;
using test_support::TempDir;

// signals.csv and states.csv print 9 significant digits: positions of ~0.1 m to ~1e-9 m, with room for
// the rounding of the velocity used below.
constexpr double kPositionTolM = 1e-7;
constexpr double kClockTolS = 1e-9;

std::string MessageOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "no error";
}

TEST(StateLogTest, ReplayedStatePutsTheObjectWhereTheSignalsSay) {
  const ScenarioConfig config = LoadScenario(SourcePath("scenarios/default.yaml"));
  TempDir dir("state_log");
  RunOptions run;
  run.out_dir = dir.Path("run");
  run.write_plots = false;
  ASSERT_TRUE(RunScenario(config, run).completed);

  sim::Simulation simulation(sensor::LoadLayout(ResolveLayoutPath(config)), config.scene);
  mjModel* m = simulation.mutable_model();
  mjData* d = simulation.mutable_data();
  const sim::StateLog states = sim::LoadStateLog(run.out_dir + "/states.csv", m->nq, m->nv, m->nu);
  // The first control tick, then one row per 5 ms to the end.
  EXPECT_NEAR(static_cast<double>(states.rows.size()), config.duration_s / sim::StateRecorder::kPeriodS, 1.0);
  EXPECT_LT(states.time_s[0], sim::StateRecorder::kPeriodS);
  for (size_t r = 2; r < states.time_s.size(); ++r) {
    ASSERT_NEAR(states.time_s[r] - states.time_s[r - 1], sim::StateRecorder::kPeriodS, 1e-6) << "row " << r;
  }

  const common::CsvTable signals = common::ReadCsvTable(run.out_dir + "/signals.csv");
  const size_t c_time = signals.Column("time_s");
  const size_t c_object[3] = {signals.Column("object_x_m"), signals.Column("object_y_m"),
                              signals.Column("object_z_m")};
  const int object = mj_name2id(m, mjOBJ_BODY, "object");
  ASSERT_GE(object, 0);
  int compared = 0;
  for (size_t s = 0; s < signals.rows.size(); s += 97) {  // a spread of ticks through the run
    const double t = signals.Number(s, c_time);
    const size_t row = states.RowAt(t);
    if (std::abs(states.time_s[row] - t) > kClockTolS) continue;  // a tick between state rows
    const std::vector<double>& values = states.rows[row];
    std::copy_n(values.data(), m->nq, d->qpos);
    std::copy_n(values.data() + m->nq, m->nv, d->qvel);
    std::copy_n(values.data() + m->nq + m->nv, m->nu, d->ctrl);
    mj_forward(m, d);
    // signals.csv takes the object's position from the kinematics mj_step computed before it
    // integrated (the start of the tick's last physics step); the log holds the integrated state, one
    // step of travel on.
    const double* velocity = d->qvel + m->jnt_dofadr[m->body_jntadr[object]];
    const double step_travel_m =
        std::sqrt(velocity[0] * velocity[0] + velocity[1] * velocity[1] + velocity[2] * velocity[2]) *
        m->opt.timestep;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(d->xipos[3 * object + k], signals.Number(s, c_object[k]), step_travel_m + kPositionTolM)
          << "t = " << t << ", axis " << k;
    }
    ++compared;
  }
  EXPECT_GT(compared, 3);
}

TEST(StateLogTest, RefusesAnotherModelsLogAndMalformedRows) {
  TempDir dir("state_log_bad");
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir.Path(name)) << text;
    return dir.Path(name);
  };
  const std::string other = write("other.csv", "time_s,qpos_0,qvel_0\n0.001,1,2\n");
  EXPECT_EQ(
      MessageOf([&] { sim::LoadStateLog(other, 2, 1, 0); }),
      other +
          ":1: column 3 is 'qvel_0', expected 'qpos_1': not a state log of this model (nq 2, nv 1, nu 0)");
  const std::string text = write("text.csv", "time_s,qpos_0,ctrl_0\n0.001,1,2\n0.006,x,2\n");
  EXPECT_EQ(MessageOf([&] { sim::LoadStateLog(text, 1, 0, 1); }), text + ":3: column 2: not a number");
  const std::string backwards = write("back.csv", "time_s,qpos_0\n0.006,1\n0.001,1\n");
  EXPECT_EQ(MessageOf([&] { sim::LoadStateLog(backwards, 1, 0, 0); }),
            backwards + ":3: time_s 0.001000 does not follow 0.006000");
  EXPECT_NE(
      MessageOf([&] { sim::LoadStateLog(dir.Path("missing.csv"), 1, 0, 0); }).find("missing.csv: cannot read"),
      std::string::npos);
  const std::string ragged = write("ragged.csv", "time_s,phase\n0.001\n");
  EXPECT_EQ(MessageOf([&] { common::ReadCsvTable(ragged); }), ragged + ":2: 1 cells, the header has 2");
}

}  // namespace
}  // namespace graspbed::testbed
