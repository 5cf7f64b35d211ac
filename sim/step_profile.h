#pragma once
/// Where one physics step's time goes: MuJoCo's own stage timers (collision, constraint assembly,
/// projection, solver with noslip) averaged over a stretch of simulated time, with the contact and
/// constraint counts and solver iterations that explain them. For benchmarks and tuning, not for
/// the per-step path (it installs MuJoCo's process-wide timer callback while it runs).

#include "sim/simulation.h"

namespace graspbed::sim {

/// Mean cost per physics step: CPU time, MuJoCo's stage timers [us of wall time, so they include
/// preemption on a loaded machine; read them as shares] and the work behind them.
struct StepProfile {
  int steps = 0;
  double step_cpu_us = 0.0;    ///< CPU time of the calling thread per Simulation::Step (the robust figure)
  double step_us = 0.0;        ///< whole mj_step
  double kinematics_us = 0.0;  ///< kinematics, com, tendons, transmission, inertia
  double collision_us = 0.0;   ///< broad and narrow phase
  double make_constraint_us = 0.0;     ///< constraint rows (Jacobians, impedance)
  double project_constraint_us = 0.0;  ///< J M^-1 J' (needed by noslip)
  double velocity_actuation_us = 0.0;  ///< velocity, actuation and smooth acceleration stages
  double solver_us = 0.0;              ///< constraint solver, noslip included
  double contacts = 0.0;               ///< mean number of contacts
  double constraint_rows = 0.0;        ///< mean number of constraint rows (nefc)
  double solver_iterations = 0.0;      ///< mean main-solver iterations per step
};

/// Steps `simulation` for `duration_s` of simulated time with MuJoCo's timers on and returns the
/// means. Not thread-safe with other simulations stepping at the same time (the timer callback is
/// process-wide).
StepProfile ProfileSteps(Simulation& simulation, double duration_s);

}  // namespace graspbed::sim
