#include "testbed/schedule.h"

#include <algorithm>
#include <numeric>

namespace graspbed::testbed {

double ExpectedRunCost(const ScenarioConfig& config) {
  return config.duration_s / config.scene.physics.timestep_s;
}

std::vector<size_t> LongestFirst(const std::vector<double>& costs) {
  std::vector<size_t> order(costs.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return costs[a] > costs[b]; });
  return order;
}

std::vector<size_t> LongestFirst(const std::vector<ScenarioConfig>& configs) {
  std::vector<double> costs;
  costs.reserve(configs.size());
  for (const ScenarioConfig& config : configs) costs.push_back(ExpectedRunCost(config));
  return LongestFirst(costs);
}

}  // namespace graspbed::testbed
