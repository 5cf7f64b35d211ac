#pragma once
/// Order in which a pool of workers starts the runs of a suite or a sweep: the longest expected run
/// first (longest-processing-time-first list scheduling). Started in file order, a long run that
/// happens to come last runs alone at the end while the other workers idle; started first, it runs
/// beside all the short ones. Results are still reported in the caller's order.

#include <cstddef>
#include <vector>

#include "testbed/scenario_config.h"

namespace graspbed::testbed {

/// Expected cost of running `config` [physics steps]: simulated time over the physics step. The
/// sensor model, readout and controller run at fixed rates per simulated second and scale the same
/// way, so runs of one model compare by this number.
double ExpectedRunCost(const ScenarioConfig& config);

/// Indices 0..costs.size()-1 ordered by cost, largest first; equal costs keep their order.
std::vector<size_t> LongestFirst(const std::vector<double>& costs);

/// LongestFirst of the ExpectedRunCost of each config.
std::vector<size_t> LongestFirst(const std::vector<ScenarioConfig>& configs);

}  // namespace graspbed::testbed
