// `graspbed oracle`: the lightest constant grip that holds a scenario (testbed/oracle.h).
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "app/command_registry.h"
#include "app/stop_signal.h"
#include "testbed/oracle.h"
#include "testbed/scenario_config.h"

namespace graspbed::app {
namespace {

struct OracleCommandOptions {
  std::string scenario;
  std::vector<std::string> sets;
  bool json = false;
};

void OracleCommand(const OracleCommandOptions& options) {
  std::vector<testbed::Override> overrides;
  for (const std::string& text : options.sets) overrides.push_back(testbed::ParseOverride(text));
  const testbed::ScenarioConfig config = testbed::LoadScenario(options.scenario, overrides);
  if (config.backend != testbed::Backend::kSim) {
    throw std::invalid_argument(std::string("the oracle runs the simulation; backend ") +
                                testbed::BackendName(config.backend) + " has none");
  }
  testbed::OracleOptions oracle;
  oracle.stop = &StopRequested();
  StopSignalGuard guard;
  const testbed::OracleReport report = testbed::RunOracleReport(config, oracle);
  if (options.json) {
    std::cout << testbed::OracleReportJson(config, report).dump(2) << '\n';
  } else {
    std::cout << testbed::OracleReportTable(config, report);
  }
  const bool completed =
      report.full.completed && (!report.until_disturbance || report.until_disturbance->completed);
  if (!completed) throw CLI::RuntimeError(130);
}

void AddOracleCommand(CLI::App& root) {
  auto options = std::make_shared<OracleCommandOptions>();
  CLI::App* command = root.add_subcommand(
      "oracle",
      "The scenario's oracle grip: the lightest constant grip (controller constant_grip on the ideal "
      "sensor) with which it is not dropped, has no gross slip and is held on the sensorised pad: doubled from 2 N up to the stall "
      "pinch, halved down to 0.125 N when nothing above held, then bisected to 2 % or 0.02 N; also "
      "the lightest that holds it until its first disturbance action; exit 0, 2 on bad input");
  command->add_option("scenario", options->scenario, "scenario YAML file")->required();
  command->add_option("--set", options->sets, "override a key, e.g. --set object.mass_kg=0.3 (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  command->add_flag("--json", options->json,
                    "print JSON (oracle_grip_n, oracle_grip_until_disturbance_n, each search's steps)");
  command->callback([options] { OracleCommand(*options); });
}

const bool kRegisteredOracle = RegisterCommands(&AddOracleCommand);

}  // namespace
}  // namespace graspbed::app
