#include "sim/step_profile.h"

#include <mujoco/mujoco.h>

#include <chrono>

#include "common/process.h"

namespace graspbed::sim {
namespace {

// MuJoCo's timer callback: microseconds on a monotonic clock.
mjtNum MicrosecondsNow() {
  using Clock = std::chrono::steady_clock;
  return std::chrono::duration<double, std::micro>(Clock::now().time_since_epoch()).count();
}

}  // namespace

StepProfile ProfileSteps(Simulation& simulation, double duration_s) {
  mjData* d = simulation.mutable_data();
  const mjfTime previous = mjcb_time;
  mjcb_time = &MicrosecondsNow;
  for (mjTimerStat& timer : d->timer) timer = mjTimerStat{};
  StepProfile profile;
  const double end_s = simulation.time_s() + duration_s;
  const double cpu_start_s = common::ThreadCpuSeconds();
  while (simulation.time_s() < end_s - 0.5 * simulation.timestep_s() && !simulation.fault().occurred) {
    simulation.Step();
    ++profile.steps;
    profile.contacts += d->ncon;
    profile.constraint_rows += d->nefc;
    profile.solver_iterations += d->solver_iter;
  }
  const double cpu_s = common::ThreadCpuSeconds() - cpu_start_s;
  mjcb_time = previous;
  if (profile.steps == 0) return profile;
  const double n = profile.steps;
  profile.step_cpu_us = 1e6 * cpu_s / n;
  auto mean_us = [&](int timer) { return d->timer[timer].duration / n; };
  profile.step_us = mean_us(mjTIMER_STEP);
  profile.kinematics_us = mean_us(mjTIMER_POS_KINEMATICS) + mean_us(mjTIMER_POS_INERTIA);
  profile.collision_us = mean_us(mjTIMER_POS_COLLISION);
  profile.make_constraint_us = mean_us(mjTIMER_POS_MAKE);
  profile.project_constraint_us = mean_us(mjTIMER_POS_PROJECT);
  profile.velocity_actuation_us =
      mean_us(mjTIMER_VELOCITY) + mean_us(mjTIMER_ACTUATION) + mean_us(mjTIMER_ACCELERATION);
  profile.solver_us = mean_us(mjTIMER_CONSTRAINT);
  profile.contacts /= n;
  profile.constraint_rows /= n;
  profile.solver_iterations /= n;
  return profile;
}

}  // namespace graspbed::sim
