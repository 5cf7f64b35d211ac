// `graspbed compare RUN_A RUN_B`: two runs (a session on the hand and the simulated scenario it
// followed, or any two runs of the same sensor) aligned by intent events; residuals, grip and timing.
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include "app/command_registry.h"
#include "testbed/compare.h"
#include "testbed/runner.h"

namespace graspbed::app {
namespace {

struct CompareOptions {
  std::string run_a;
  std::string run_b;
  std::string out_dir;
  bool json = false;
};

void RunCompare(const CompareOptions& options) {
  const testbed::RunComparison comparison = testbed::CompareRuns(options.run_a, options.run_b);
  if (!options.out_dir.empty()) {
    std::error_code error;
    std::filesystem::create_directories(options.out_dir, error);
    if (error || !std::filesystem::is_directory(options.out_dir)) {
      throw std::invalid_argument("--out " + options.out_dir + ": cannot create the output directory");
    }
    common::WriteFileAtomic(options.out_dir + "/compare.json",
                              testbed::ComparisonJson(comparison).dump(2) + "\n");
    testbed::WriteComparisonPlot(comparison, options.out_dir + "/compare.png");
  }
  if (options.json) {
    std::cout << testbed::ComparisonJson(comparison).dump(2) << '\n';
  } else {
    std::cout << testbed::ComparisonTable(comparison);
    if (!options.out_dir.empty())
      std::cout << "  outputs: " << options.out_dir << "/ (compare.json, compare.png)\n";
  }
}

void AddCompareCommand(CLI::App& root) {
  auto options = std::make_shared<CompareOptions>();
  CLI::App* command = root.add_subcommand(
      "compare",
      "Compare two runs (e.g. a session on the hand and its simulated scenario), aligned by intent "
      "events: per-unit estimate residuals, grip and timing differences");
  command->add_option("run_a", options->run_a, "output directory of run A (its signals.csv)")
      ->required()
      ->check(CLI::ExistingDirectory);
  command->add_option("run_b", options->run_b, "output directory of run B")
      ->required()
      ->check(CLI::ExistingDirectory);
  command->add_option("--out", options->out_dir, "write compare.json and compare.png here");
  command->add_flag("--json", options->json, "print the comparison as JSON");
  command->callback([options] { RunCompare(*options); });
}

const bool kRegistered = RegisterCommands(&AddCompareCommand);

}  // namespace
}  // namespace graspbed::app
