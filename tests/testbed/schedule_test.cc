// Suites and sweeps start the longest expected run first, so a long run does not start last and run
// alone while the other workers idle.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "testbed/schedule.h"
#include "testbed/suite.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed::testbed {
namespace {

using test_support::HeldBoxScenario;

TEST(Schedule, LongestFirstKeepsTheOrderOfEqualCosts) {
  EXPECT_EQ(LongestFirst(std::vector<double>{2.8, 2.5, 20.0, 3.0, 2.8}),
            (std::vector<size_t>{2, 3, 0, 4, 1}));
  EXPECT_TRUE(LongestFirst(std::vector<double>{}).empty());
}

TEST(Schedule, ExpectedCostIsPhysicsSteps) {
  ScenarioConfig config;
  config.duration_s = 2.0;
  config.scene.physics.timestep_s = 0.0005;
  EXPECT_DOUBLE_EQ(ExpectedRunCost(config), 4000.0);
  // A finer step costs more for the same simulated time.
  ScenarioConfig fine = config;
  fine.scene.physics.timestep_s = 0.00025;
  EXPECT_EQ(LongestFirst(std::vector<ScenarioConfig>{config, fine}), (std::vector<size_t>{1, 0}));
}

TEST(Schedule, SuiteStartsTheLongestRunFirstAndReportsInFileOrder) {
  std::vector<ScenarioConfig> configs;
  const double durations_s[] = {0.2, 0.35, 0.25};
  for (int i = 0; i < 3; ++i) {
    configs.push_back(
        LoadScenarioFromString(HeldBoxScenario(durations_s[i]), "run" + std::to_string(i) + ".yaml"));
  }
  std::vector<std::string> finished;
  SuiteOptions options;
  options.jobs = 1;  // one worker: runs finish in the order they start
  options.on_finished = [&](int, int, const SuiteRun& run) { finished.push_back(run.result.config.name); };
  const SuiteResult result = RunSuite(configs, options);
  EXPECT_EQ(finished, (std::vector<std::string>{"run1", "run2", "run0"}));
  ASSERT_EQ(result.runs.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(result.runs[i].result.config.name, "run" + std::to_string(i));
  EXPECT_TRUE(result.completed);
}

}  // namespace
}  // namespace graspbed::testbed
