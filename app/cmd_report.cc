// `graspbed report DIR`: one self-contained HTML page for the output directory of a suite, a
// scorecard or a sweep (testbed/report.h).
#include <iostream>
#include <memory>
#include <string>

#include "app/command_registry.h"
#include "testbed/report.h"

namespace graspbed::app {
namespace {

void AddReportCommand(CLI::App& root) {
  auto dir = std::make_shared<std::string>();
  auto options = std::make_shared<testbed::ReportOptions>();
  CLI::App* command = root.add_subcommand(
      "report",
      "One self-contained HTML page (no network: styles, script and pictures inline) for the output "
      "directory of graspbed suite, score or sweep: the summary, the comparison figures and one row per "
      "run with its verdict, first failed expectation, oracle grip or why there is none, and links to its "
      "pictures; sortable, filterable by scenario, controller, sensor, verdict and oracle (also from the "
      "URL: report.html#verdict=failed)");
  // Not CLI::ExistingDirectory: the library's message names the directory and what it expected.
  command->add_option("dir", *dir, "output directory holding scorecard.json, suite.json or results.jsonl")
      ->required();
  command->add_option("--out", options->out_path, "the page's path (default DIR/report.html)");
  command->add_option("--runs-out", options->runs_dir,
                      "where `graspbed score --runs-out` kept the runs' outputs: each row links its folder");
  command->callback(
      [dir, options] { std::cout << testbed::DescribeReport(testbed::WriteReport(*dir, *options)) << '\n'; });
}

const bool kRegistered = RegisterCommands(&AddReportCommand);

}  // namespace
}  // namespace graspbed::app
